//! Cascades, warps and fitting: cascades against one map at equal memory,
//! selection and blending, flicker along camera paths, texel footprints,
//! SDSM's depth bounds, the fitted, turned and focused maps, and the
//! casters each cascade draws.

use super::common::*;
use glam::Vec3;
use shadowlab::measure::flicker::CameraPath;
use shadowlab::scene::Light;

/// Cascades from the street: each cascade's texels are smaller than those
/// of one map fitted to the same view frustum with the same bias, so the
/// mismatch falls to half that map's or less at the same memory (4 × 1024²
/// against one 2048²), its interior included, and stays near the reference. (The default one map,
/// fitted to the pixels seen, comes close to them here.)
#[test]
fn cascades_beat_one_map_at_equal_memory_in_the_street() {
    let mut scene = shadowlab::scene::load("city").unwrap();
    scene.camera = scene.camera_preset("street").unwrap();
    scene.lights = scene.light_preset("sun").unwrap();
    let one = compare(
        &scene,
        "shadow-map:pcf[fit=frustum,normal_offset_directional=0.5]",
        (320, 180),
    )
    .mask;
    for id in ["shadow-map:csm", "shadow-map:pssm"] {
        let m = compare(&scene, id, (320, 180)).mask;
        assert!(
            m.all.total_pct * 2.0 <= one.all.total_pct
                && m.interior.total_pct <= one.interior.total_pct
                && m.all.total_pct <= 0.8,
            "{id}: {m:?}\none map: {one:?}"
        );
    }
}

/// Five squares along the view depth over a floor under a sun, seen from
/// `eye_height` at a grazing angle (each square `shift` further along x):
/// every cascade and every blend band holds shadow edges.
fn squares_along_the_view(shift: f32, eye_height: f32) -> shadowlab::scene::Scene {
    let squares: Vec<(Vec3, f32)> = (0..5)
        .map(|i| {
            (
                Vec3::new(shift * (i as f32 - 2.0), 0.6, 4.0 - 3.0 * i as f32),
                0.8,
            )
        })
        .collect();
    let mut scene = squares_over_floor(
        &squares,
        Light::directional(Vec3::new(0.4, -1.0, 0.3), 1.0),
        false,
    );
    scene.camera =
        shadowlab::scene::Camera::new(Vec3::new(0.0, eye_height, 8.0), Vec3::new(0.0, 0.0, -6.0));
    scene
}

/// Cascade selection and blending on a plane: squares spread along the
/// view depth over a floor, seen at a grazing angle, so that every cascade
/// and every blend band holds shadow edges; with or without blending the
/// mask matches the reference away from the edges.
#[test]
fn cascade_selection_and_blending_on_a_plane_match_the_reference() {
    let scene = squares_along_the_view(0.0, 2.0);
    for set in [
        "shadow-map:pcf[cascades=4,size=512]",
        "shadow-map:pcf[cascades=4,size=512,blend=0.3]",
        "shadow-map:pcf[cascades=3,size=512,stabilize=true,blend=0.2]",
        "shadow-map:pcf[cascades=4,size=512,select=map]",
        "shadow-map:pcf[cascades=3,size=512,stabilize=true,blend=0.2,select=map]",
    ] {
        let m = compare(&scene, set, (256, 256)).mask;
        assert!(m.reference_shadowed_pct > 5.0, "{set}: {m:?}");
        assert!(m.interior.total_pct <= 0.2, "{set}: {m:?}");
        assert!(m.all.total_pct <= 2.0, "{set}: {m:?}");
    }
}

/// Flicker (% of considered pixels, per technique of `techniques`) along
/// `path` over [`squares_along_the_view`] against `raytraced`.
fn flicker_over_squares(
    techniques: &str,
    path: CameraPath,
    size: (u32, u32),
    frames: u32,
) -> Vec<f64> {
    let scene = squares_along_the_view(0.5, 2.0);
    let list = shadowlab::measure::parse_technique_list(techniques).unwrap();
    let reference = shadowlab::technique::resolve("raytraced").unwrap();
    shadowlab::measure::flicker::run(
        gpu(),
        shadowlab::measure::FrameRequest {
            scene: &scene,
            camera: &scene.camera,
            lights: &scene.lights,
            size,
        },
        &list,
        &reference,
        path,
        frames,
        &tmpdir("flicker"),
    )
    .unwrap()
    .iter()
    .map(|r| r.flicker_pct)
    .collect()
}

/// Stabilised maps keep their texel grid while the camera strafes and
/// turns: no surface point changes its shadow state; maps refitted to the
/// frustum slide. (The default one map, fitted to the pixels seen, is
/// stabilised too.)
#[test]
fn stabilised_maps_do_not_flicker_along_a_camera_path() {
    for path in [CameraPath::Strafe, CameraPath::Turn] {
        let pct = flicker_over_squares(
            "shadow-map:pcf[size=256,fit=frustum],shadow-map:pcf[size=256,fit=frustum,stabilize=false],shadow-map:csm[size=256],shadow-map:csm[size=256,stabilize=false],shadow-map:pcf[size=256]",
            path,
            (200, 150),
            4,
        );
        assert!(
            pct[0] <= 0.01 && pct[2] <= 0.01 && pct[4] <= 0.01,
            "{path:?}: {pct:?}"
        );
        assert!(pct[1] > pct[0] && pct[3] > pct[2], "{path:?}: {pct:?}");
    }
}

/// On a dolly the split distances move with the camera, so selecting the
/// cascade by view depth moves pixels between cascades every frame and the
/// shadow edges they hold change state; choosing the finest stabilised map
/// that holds the point keeps them where the maps are (which move only in
/// whole texels). Edge ramps as filtered (`edge_ramp_pixels=0`): steepened,
/// they hide most of the change between two cascades' edges.
#[test]
fn map_selection_keeps_cascade_borders_still_on_a_dolly() {
    let pct = flicker_over_squares(
        "shadow-map:csm[size=256,select=depth,edge_ramp_pixels=0],shadow-map:csm[size=256,select=map,edge_ramp_pixels=0]",
        CameraPath::Dolly,
        (320, 240),
        6,
    );
    let (depth, map) = (pct[0], pct[1]);
    // Measured: depth 0.0108 %, map 0.0010 %.
    assert!(depth > 0.005, "depth selection: {depth}, map {map}");
    assert!(map * 4.0 <= depth, "map selection {map}, depth {depth}");
}

/// The aliasing measure: screen pixels per map texel. Doubling the map
/// halves it; on the landscape seen from the ground, cascades at the same
/// memory bring its 95th percentile under a quarter of the one map's.
#[test]
fn texel_footprint_halves_with_twice_the_map_and_shrinks_with_cascades() {
    let scene = squares_along_the_view(0.0, 1.0);
    let p95 = |scene: &shadowlab::scene::Scene, id: &str, size| {
        compare(scene, id, size)
            .aliasing
            .unwrap_or_else(|| panic!("{id} has a map"))
            .p95
    };
    let small = p95(&scene, "shadow-map:pcf[size=512]", (256, 192));
    let large = p95(&scene, "shadow-map:pcf[size=1024]", (256, 192));
    assert!((small / large - 2.0).abs() < 0.1, "{small} / {large}");
    assert!(compare(&scene, "none", (64, 48)).aliasing.is_none());
    let land = preset("landscape", "ground", "sun-side");
    let one = p95(&land, "shadow-map:pcf", (320, 180));
    let cascades = p95(&land, "shadow-map:csm", (320, 180));
    assert!(cascades * 4.0 <= one, "csm {cascades}, one map {one}");
}

/// The warps (PSM, LiSPSM, TSM) on the landscape from the ground, one
/// 2048² map each: against the unwarped map they replace (fitted to the
/// view frustum, as their warps are, not to the pixels seen, upright as
/// their light view is, with their normal offset and no bias cap, which
/// warped maps lack), several times
/// fewer mismatched pixels and a clean interior with the sun from the side,
/// and still under half of its mismatch with the sun low in front of the
/// camera (the duelling frusta, where LiSPSM and TSM relax towards it).
#[test]
fn warped_maps_beat_the_one_map_on_the_landscape() {
    let mut land = shadowlab::scene::load("landscape").unwrap();
    land.camera = land.camera_preset("ground").unwrap();
    for (light, interior, ratio) in [("sun-side", 0.1, 3.0), ("sun-low-front", 0.5, 2.0)] {
        land.lights = land.light_preset(light).unwrap();
        let one = compare(
            &land,
            "shadow-map:pcf[fit=frustum,roll=up,normal_offset_directional=1,slope_bias_clamp=0]",
            (320, 180),
        );
        for warp in ["shadow-map:psm", "shadow-map:lispsm", "shadow-map:tsm"] {
            let r = compare(&land, warp, (320, 180));
            let m = &r.mask;
            assert!(
                m.all.total_pct * ratio <= one.mask.all.total_pct,
                "{light} {warp}: {} vs one map {}",
                m.all.total_pct,
                one.mask.all.total_pct
            );
            assert!(
                m.interior.false_shadow_pct <= interior && m.interior.false_lit_pct <= interior,
                "{light} {warp}: interior FS {} FL {}",
                m.interior.false_shadow_pct,
                m.interior.false_lit_pct
            );
        }
    }
}

/// SDSM's reduction finds the nearest and farthest view depths of the
/// receiving pixels, as a CPU pass over the read-back G-buffer does.
#[test]
fn sdsm_depth_bounds_are_the_seen_view_depths() {
    use shadowlab::technique::Feedback;
    let gpu = gpu();
    let scene = squares_along_the_view(0.0, 2.0);
    let hf = frame_with_debug_views(&scene, "shadow-map:sdsm", 256, 192);
    let counter = |name: &str| counter(&hf, name);
    let position = gpu
        .read_texture(hf.frame.gbuffer_position(), 0, 16)
        .unwrap();
    let normal = gpu.read_texture(hf.frame.gbuffer_normal(), 0, 8).unwrap();
    let position: &[[f32; 4]] = bytemuck::cast_slice(&position);
    let receives: Vec<bool> = bytemuck::cast_slice::<u8, [half::f16; 4]>(&normal)
        .iter()
        .map(|n| n[3].to_f32() > 0.5)
        .collect();
    let view = scene.camera.view();
    let depths: Vec<f32> = position
        .iter()
        .zip(&receives)
        .filter(|(p, r)| p[3] > 0.5 && **r)
        .map(|(p, _)| -view.transform_point3(Vec3::new(p[0], p[1], p[2])).z)
        .collect();
    let near = depths.iter().copied().fold(f32::MAX, f32::min) as f64;
    let far = depths.iter().copied().fold(0.0, f32::max) as f64;
    assert!(
        (counter("sdsm_near") - near).abs() < 1e-4 * near,
        "{} vs {near}",
        counter("sdsm_near")
    );
    assert!(
        (counter("sdsm_far") - far).abs() < 1e-4 * far,
        "{} vs {far}",
        counter("sdsm_far")
    );
    // Frame-late feedback (the viewer): the first frame has no result yet
    // and fits the frustum; the next one uses the first one's bounds.
    let choice = shadowlab::measure::parse_technique_list("shadow-map:sdsm")
        .unwrap()
        .remove(0);
    let mut late =
        shadowlab::headless::HeadlessFrame::new(gpu, &scene, &[choice], 256, 192).unwrap();
    let settings = shadowlab::renderer::RenderSettings {
        feedback: Feedback::PreviousFrame,
        ..Default::default()
    };
    let has_bounds = |hf: &shadowlab::headless::HeadlessFrame| {
        hf.techniques[0]
            .technique
            .counters()
            .iter()
            .any(|(n, _)| *n == "sdsm_near")
    };
    late.render(gpu, &scene, &scene.camera, &scene.lights, &settings)
        .unwrap();
    assert!(!has_bounds(&late), "the first frame cannot have waited");
    late.render(gpu, &scene, &scene.camera, &scene.lights, &settings)
        .unwrap();
    assert!(
        has_bounds(&late),
        "the second frame has the first one's bounds"
    );
}

/// `id` rendered on `scene` with its debug views: how many receiving pixels
/// that the light reaches look up no map (partition 0), and the mean texel
/// footprint (screen pixels per texel) where a map is looked up.
fn map_coverage(scene: &shadowlab::scene::Scene, id: &str, (w, h): (u32, u32)) -> (usize, f32) {
    let gpu = gpu();
    let hf = frame_with_debug_views(scene, id, w, h);
    let lookup = hf.techniques[0].technique.map_lookup(gpu).unwrap().unwrap();
    let reached = shadowlab::measure::compare::considered_pixels(gpu, &hf, &scene.lights).unwrap();
    let outside = reached[0]
        .iter()
        .zip(&lookup.partition)
        .filter(|(r, p)| **r && **p == 0)
        .count();
    let looked_up: Vec<f32> = lookup
        .footprint
        .iter()
        .copied()
        .filter(|f| *f > 0.0)
        .collect();
    (
        outside,
        looked_up.iter().sum::<f32>() / looked_up.len() as f32,
    )
}

/// The mean texel footprints of `id` and `other` on `scene` ([`map_coverage`]),
/// once `id` is seen to leave no receiving pixel outside its maps.
fn footprints(
    scene: &shadowlab::scene::Scene,
    id: &str,
    other: &str,
    size: (u32, u32),
) -> (f32, f32) {
    let (outside, footprint) = map_coverage(scene, id, size);
    assert_eq!(outside, 0, "{id}: receiving pixels outside its maps");
    (footprint, map_coverage(scene, other, size).1)
}

/// SDSM's cascades fitted to the pixels they shade: every receiving pixel
/// finds its surface inside the map it looks up, the texels are smaller
/// than the frustum-fitted cascades', and the mask matches the reference.
#[test]
fn sdsm_cascades_cover_every_pixel_with_smaller_texels() {
    let scene = squares_along_the_view(0.0, 2.0);
    let (sdsm, frustum) = footprints(
        &scene,
        "shadow-map:sdsm",
        "shadow-map:sdsm[fit=frustum]",
        (256, 192),
    );
    assert!(
        sdsm < 0.8 * frustum,
        "sdsm {sdsm} px/texel, frustum-fitted {frustum}"
    );
    let m = compare(&scene, "shadow-map:sdsm", (256, 256)).mask;
    assert!(m.reference_shadowed_pct > 5.0, "{m:?}");
    assert!(
        m.interior.total_pct <= 0.2 && m.all.total_pct <= 2.0,
        "{m:?}"
    );
}

/// One directional map fitted to the pixels the camera saw (the default
/// `fit=samples`) on the landscape from the ground, where the view frustum
/// reaches 2 km: every receiving pixel inside the map, texels well under
/// the frustum-fitted map's and less than half of its mismatch.
#[test]
fn one_map_fitted_to_the_seen_pixels_covers_them_with_smaller_texels() {
    let land = preset("landscape", "ground", "sun-low-front");
    fitted_map_is_finer_and_closer(
        &land,
        "shadow-map:pcf",
        "shadow-map:pcf[fit=frustum]",
        (256, 144),
    );
}

/// `fitted` keeps every receiving pixel of `scene` inside its maps, with a
/// mean texel footprint under 0.8 of `wider`'s and at most half of its
/// total mismatch.
fn fitted_map_is_finer_and_closer(
    scene: &shadowlab::scene::Scene,
    fitted: &str,
    wider: &str,
    size: (u32, u32),
) {
    let (seen, wide) = footprints(scene, fitted, wider, size);
    assert!(
        seen < 0.8 * wide,
        "{fitted}: {seen} px/texel, {wider}: {wide}"
    );
    let close = compare(scene, fitted, size).mask;
    let far = compare(scene, wider, size).mask;
    assert!(
        close.all.total_pct * 2.0 <= far.all.total_pct,
        "{fitted}: {close:?}\n{wider}: {far:?}"
    );
}

/// A warped map fitted to the pixels it shades (`fit=samples`, the
/// default): its body B cut to the prism along the light around them. On
/// the landscape from the ground with the sun low behind the camera, the
/// view frustum spans the valley while the camera sees a slope and a
/// path: every receiving pixel stays inside the map, with texels well
/// under those of the same warp over the seen depths alone (`fit=depth`),
/// and less than half of its mismatch.
#[test]
fn warped_maps_fitted_to_the_seen_pixels_cover_them_with_smaller_texels() {
    let land = preset("landscape", "ground", "sun-low-back");
    for warp in ["psm", "lispsm", "tsm"] {
        fitted_map_is_finer_and_closer(
            &land,
            &format!("shadow-map:{warp}"),
            &format!("shadow-map:{warp}[fit=depth]"),
            (256, 144),
        );
    }
}

/// The single map turned to the smallest square around the pixels seen
/// (`roll=square`, the default): a wide view straight down onto squares in
/// a row sees a floor strip 5.3 times longer than wide, along the world's
/// x, which a sun in the y-z plane sees along its image's x axis (upright,
/// the square's side is the strip's length; turned 45°, (length +
/// width)/√2); the map turns off upright and clear of the world's axes, keeps every
/// receiving pixel inside it with texels smaller than the upright map's,
/// and its mask is as clean.
#[test]
fn one_map_turned_to_the_smallest_square_has_smaller_texels() {
    let squares: Vec<(Vec3, f32)> = (0..7)
        .map(|i| (Vec3::new(2.0 * (i as f32 - 3.0) + 1.0, 0.6, 4.0), 0.5))
        .collect();
    let mut scene = squares_over_floor(
        &squares,
        Light::directional(Vec3::new(0.0, -1.0, 0.4), 1.0),
        false,
    );
    // Off the scene's centre, so that a box taken along the wrong
    // directions would miss it.
    scene.camera = shadowlab::scene::Camera {
        up: Vec3::NEG_Z,
        fov_y_deg: 20.0,
        ..shadowlab::scene::Camera::new(Vec3::new(1.0, 8.0, 4.0), Vec3::new(1.0, 0.0, 4.0))
    };
    let (w, h) = (512, 96);
    let (turned, upright) = footprints(&scene, "shadow-map:pcf", "shadow-map:pcf[roll=up]", (w, h));
    assert!(
        turned < 0.9 * upright,
        "turned {turned} px/texel, upright {upright}"
    );
    let turn = |id: &str| counter(&frame_with_debug_views(&scene, id, w, h), "map_turn_deg");
    let t = turn("shadow-map:pcf");
    assert!((15.0..=75.0).contains(&t), "turned {t}°");
    assert_eq!(turn("shadow-map:pcf[roll=up]"), 0.0);
    let m = compare(&scene, "shadow-map:pcf", (w, h)).mask;
    assert!(m.reference_shadowed_pct > 2.0, "{m:?}");
    assert!(
        m.interior.total_pct <= 0.05 && m.all.total_pct <= 1.0,
        "{m:?}"
    );
}

/// Caster culling: the cascades over the landscape seen from the ground
/// draw, per cluster, only the casters that can shadow the view from the
/// side-lit sun — about 1.4 times the scene's casters for four cascades
/// (each cascade's square alone held 2.9 times) — and their masks still
/// match the reference's in the interior.
#[test]
fn cascades_draw_only_the_casters_that_can_shadow_the_view() {
    let land = preset("landscape", "ground", "sun-side");
    let hf = rendered_frame(&land, "shadow-map:csm", &[], 320, 180);
    let drawn = counter(&hf, "map_triangles");
    let casters = land.caster_triangle_count() as f64;
    assert!(
        drawn <= 1.6 * casters,
        "{drawn} triangles drawn, {casters} casters"
    );
    let m = compare(&land, "shadow-map:csm", (320, 180)).mask;
    assert!(
        m.interior.false_lit_pct <= 0.1 && m.interior.false_shadow_pct <= 0.1,
        "{m:?}"
    );
}

/// A spot light over the whole 20 × 20 floor, and a camera that sees one
/// corner of it: with `fit=samples` (the default) the map is focused on
/// the part of the cone the camera sees — every receiving pixel the spot
/// reaches still inside it, texels well under the whole cone's (measured
/// 0.51 of them: the part seen spans about a third of the cone's side,
/// and a fresh fit takes a quarter octave of room) — and its shadow edges
/// come far closer to the reference. With `fit=frustum` it is focused on
/// what the view frustum holds of the cone, between the two: every pixel
/// inside, texels under the whole cone's (`fit=depth`).
#[test]
fn a_spot_map_focused_on_what_the_camera_sees_has_smaller_texels() {
    let squares: Vec<(Vec3, f32)> = (0..3)
        .flat_map(|i| {
            (0..3).map(move |j| {
                (
                    Vec3::new(4.0 + 1.5 * i as f32, 0.7, 4.0 + 1.5 * j as f32),
                    0.35,
                )
            })
        })
        .collect();
    let mut scene = squares_over_floor(
        &squares,
        Light::spot(Vec3::new(0.0, 12.0, 0.0), Vec3::ZERO, 1.0, 35.0, 45.0),
        false,
    );
    scene.camera =
        shadowlab::scene::Camera::new(Vec3::new(3.0, 4.0, 3.0), Vec3::new(6.0, 0.0, 6.0));
    let (w, h) = (256, 192);
    let (focused, whole) = footprints(
        &scene,
        "shadow-map:pcf",
        "shadow-map:pcf[fit=depth]",
        (w, h),
    );
    assert!(
        focused < 0.6 * whole,
        "focused {focused} px/texel, the whole cone {whole}"
    );
    let (outside, frustum) = map_coverage(&scene, "shadow-map:pcf[fit=frustum]", (w, h));
    assert_eq!(outside, 0, "fit=frustum: receiving pixels outside its map");
    // Measured: 0.41 against 0.74 (the pixels: 0.37).
    assert!(
        frustum < 0.7 * whole && frustum >= focused,
        "the view frustum's part {frustum} px/texel, the whole cone {whole}, the pixels {focused}"
    );
    let f = compare(&scene, "shadow-map:pcf[size=256]", (w, h)).mask;
    let c = compare(&scene, "shadow-map:pcf[size=256,fit=depth]", (w, h)).mask;
    assert!(f.reference_shadowed_pct > 2.0, "{f:?}");
    assert!(
        // Measured at 256²: 0.43 against 1.96 %.
        f.all.total_pct * 3.0 <= c.all.total_pct,
        "focused {f:?}\nwhole cone {c:?}"
    );
}

/// The projection debug view tints each pixel by the cascade it looks up
/// (red, green, blue, yellow for cascades 1 to 4: `debug.wgsl`'s
/// `cascade_tint`), the same cascade `compare` reads as its partition.
#[test]
fn the_cascade_debug_view_tints_each_pixel_by_its_cascade() {
    let scene = squares_along_the_view(0.0, 2.0);
    let (w, h) = (128, 96);
    let hf = frame_with_debug_views(&scene, "shadow-map:csm", w, h);
    let gpu = gpu();
    let views = hf.techniques[0].technique.debug_views(gpu).unwrap();
    let projection = &views.images[1];
    let lookup = hf.techniques[0].technique.map_lookup(gpu).unwrap().unwrap();
    // Cascades 1 to 4 by their tints' strongest channels.
    let strongest = |p: &[u8]| -> Option<usize> {
        let above = |a: u8, b: u8| a > b.saturating_add(8);
        match (above(p[0], p[2]), above(p[1], p[2]), above(p[2], p[0])) {
            (true, true, _) if p[0].abs_diff(p[1]) <= 8 => Some(3),
            (true, false, _) => Some(0),
            (false, true, _) => Some(1),
            (false, false, true) => Some(2),
            _ => None,
        }
    };
    let mut seen = [0usize; 4];
    for (p, &part) in projection.rgba.chunks_exact(4).zip(&lookup.partition) {
        if part == 0 {
            continue;
        }
        let tint = strongest(p);
        assert_eq!(
            tint,
            Some(part as usize - 1),
            "pixel {p:?} of cascade {part}"
        );
        seen[part as usize - 1] += 1;
    }
    assert!(seen.iter().filter(|&&n| n > 0).count() >= 2, "{seen:?}");
}
