//! Shadow maps: the light's texture matrix, cube-face selection, the filters
//! against the ray-traced reference, and the 8-bit failure.

mod common;
use common::*;
use glam::{Mat4, Vec3, Vec4};
use shadowlab::measure::flicker::CameraPath;
use shadowlab::scene::{Camera, Light, Material, Scene, builtin, shapes};
use shadowlab::technique::light_space::bias_matrix;
use shadowlab::technique::shadow_map::light_setup;

#[test]
fn texture_matrix_maps_a_known_point_to_its_texel_and_depth() {
    // Spot light at (0, 5, 0) looking down, 90° frustum, near 1, far 10: the
    // origin lies on the axis at distance 5, so uv = (0.5, 0.5) and
    // z = f/(f−n) − f·n/((f−n)·5) = 10/9 − 2/9 = 8/9.
    let light = Light::spot(Vec3::new(0.0, 5.0, 0.0), Vec3::ZERO, 1.0, 30.0, 40.0);
    let bounds = shadowlab::scene::Aabb {
        min: Vec3::splat(-1.0),
        max: Vec3::splat(1.0),
    };
    let cam = Camera::new(Vec3::new(0.0, 3.0, 8.0), Vec3::ZERO);
    let fp = shadowlab::technique::shadow_map::FrustumParams {
        near: 1.0,
        far: 10.0,
        fov_deg: 90.0,
        paraboloid: false,
        stabilize_size: None,
        previous_half: None,
        view_fit: Default::default(),
        turn: Default::default(),
    };
    let s = light_setup(&light, &bounds, &cam, 1.0, &fp);
    let t = bias_matrix() * s.faces[0] * Vec4::new(0.0, 0.0, 0.0, 1.0);
    let t = t / t.w;
    assert!((t.x - 0.5).abs() < 1e-6 && (t.y - 0.5).abs() < 1e-6, "{t}");
    assert!((t.z - 8.0 / 9.0).abs() < 1e-6, "{t}");
    // The light looks straight down, so its up vector is +Z and its right
    // axis f × up = (−Y) × Z = −X: world +x is texture-left. A point 1 unit
    // along +x at the same depth lies 1/5 off-axis: x_ndc = −(1/5)/tan(45°),
    // u = 0.5 + 0.5·x_ndc = 0.4, v stays 0.5 (texel row 1024 of 2048).
    let t = bias_matrix() * s.faces[0] * Vec4::new(1.0, 0.0, 0.0, 1.0);
    let (u, v) = (t.x / t.w, t.y / t.w);
    assert!((u - 0.4).abs() < 1e-6, "{u}");
    assert_eq!((v * 2048.0).floor(), 1024.0);
    // View up = s × f = (−X) × (−Y) = +Z: world +z is up in the map,
    // y_ndc = +1/5, and the bias matrix flips v: v = 0.5 − 0.5·(1/5) = 0.4.
    let t = bias_matrix() * s.faces[0] * Vec4::new(0.0, 0.0, 1.0, 1.0);
    let (u, v) = (t.x / t.w, t.y / t.w);
    assert!((u - 0.5).abs() < 1e-6 && (v - 0.4).abs() < 1e-6, "{u} {v}");
}

/// A point light in the middle of a closed box whose inside receives the
/// shadows of six squares, one on each axis.
fn light_in_a_box() -> Scene {
    let mut s = Scene::new("box");
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let mut walls = shapes::cuboid(Vec3::splat(10.0));
    walls.make_double_sided();
    let walls = s.add_mesh(walls);
    let mut o = shadowlab::scene::Object::from_name("BoxNS", walls, grey, Mat4::IDENTITY);
    o.casts_shadow = false;
    s.objects.push(o);
    let mut quad = shapes::plane(1.2, 1.2, 1);
    quad.make_double_sided();
    let quad = s.add_mesh(quad);
    for (i, d) in [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ]
    .into_iter()
    .enumerate()
    {
        // Each square faces the light, 2 units out, slightly off-axis so its
        // shadow crosses into a neighbouring cube face.
        let rot = glam::Quat::from_rotation_arc(Vec3::Y, -d);
        let pos = d * 2.0 + rot * Vec3::new(0.9, 0.0, 0.6);
        s.add_object(
            &format!("Square{i}"),
            quad,
            grey,
            Mat4::from_rotation_translation(rot, pos),
        );
    }
    s.lights = vec![Light::point(Vec3::ZERO, 1.0)];
    s.camera = Camera::new(Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.1, 0.2, -1.0));
    s.finalize().unwrap();
    s
}

#[test]
fn cube_faces_cover_every_direction() {
    let scene = light_in_a_box();
    // Look at each wall from inside, near the light, with a wide lens.
    for d in [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ] {
        let eye = Vec3::new(0.05, 0.07, 0.03) - d * 0.5;
        let up = if d.y.abs() > 0.5 { Vec3::Z } else { Vec3::Y };
        let cam = Camera {
            up,
            fov_y_deg: 100.0,
            ..Camera::new(eye, eye + d)
        };
        let row = compare_with(&scene, &cam, "shadow-map:hard", (160, 160));
        let m = &row.mask;
        assert!(
            m.reference_shadowed_pct > 1.0,
            "{d}: no shadow in view: {m:?}"
        );
        assert!(m.interior.total_pct < 0.1, "{d}: {m:?}");
    }
}

#[test]
fn filters_match_the_reference_on_a_square_over_a_plane() {
    for light in [
        Light::point(Vec3::new(0.4, 5.0, -0.3), 1.0),
        Light::spot(Vec3::new(1.0, 5.0, 1.0), Vec3::ZERO, 1.0, 30.0, 40.0),
        Light::directional(Vec3::new(0.3, -1.0, 0.2), 1.0),
    ] {
        let scene = squares_over_floor(&[(Vec3::new(0.0, 1.0, 0.0), 0.7)], light, false);
        for (id, interior_tol) in [
            ("shadow-map:hard", 0.0),
            ("shadow-map:pcf2x2", 0.0),
            ("shadow-map:pcf", 0.0),
            ("shadow-map:pcf-disk", 0.0),
            ("shadow-map:pcss", 0.5),
            ("shadow-map:varwidth", 0.5),
            ("shadow-map:vsm", 0.5),
            ("shadow-map:esm", 0.5),
            ("shadow-map:evsm2", 0.5),
            ("shadow-map:evsm4", 0.5),
            ("shadow-map:msm", 0.5),
        ] {
            let row = compare(&scene, id, (200, 200));
            let m = &row.mask;
            assert!(m.reference_shadowed_pct > 2.0);
            assert!(
                m.interior.total_pct <= interior_tol,
                "{id} {:?}: {m:?}",
                light.kind
            );
            assert!(m.all.total_pct <= 1.5, "{id} {:?}: {m:?}", light.kind);
        }
    }
}

#[test]
fn eight_bit_depth_shows_acne_that_d32f_does_not() {
    let scene = builtin::by_name("floating").unwrap().unwrap();
    let byte = compare(&scene, "shadow-map:8bit", (320, 180));
    let float = compare(&scene, "shadow-map:hard[format=d32f]", (320, 180));
    assert!(
        byte.mask.interior.false_shadow_pct > 1.0,
        "8-bit: {:?}",
        byte.mask
    );
    assert!(
        float.mask.interior.false_shadow_pct < 0.1,
        "d32f: {:?}",
        float.mask
    );
    assert!(float.mask.reference_shadowed_pct > 1.0, "{:?}", float.mask);
    for f in ["d16", "d24"] {
        let r = compare(&scene, &format!("shadow-map:hard[format={f}]"), (320, 180));
        assert!(r.mask.interior.total_pct < 0.1, "{f}: {:?}", r.mask);
        // A mask missing the shadow would be all interior false lit.
        assert!(
            r.mask.all.total_pct < 0.2 * r.mask.reference_shadowed_pct,
            "{f}: {:?}",
            r.mask
        );
    }
}

#[test]
fn receiver_plane_depth_bias_removes_acne_that_a_constant_bias_leaves() {
    // The sun grazes the floor; with only a constant bias of 32 steps, PCF
    // taps half a texel away fall behind the sloped receiver. Without part
    // IDs: a flat floor ignores its own texels and has no acne at all.
    let scene = squares_over_floor(
        &[(Vec3::new(0.0, 1.0, 0.0), 0.7)],
        Light::directional(Vec3::new(1.0, -0.35, 0.3), 1.0),
        false,
    );
    let bare = "normal_offset_directional=0,slope_bias=0,depth_bias=32,part_ids=false";
    let without = compare(&scene, &format!("shadow-map:pcf[{bare}]"), (200, 200));
    let with = compare(
        &scene,
        &format!("shadow-map:pcf[{bare},receiver_plane=true]"),
        (200, 200),
    );
    assert!(
        without.mask.interior.false_shadow_pct > 5.0,
        "{:?}",
        without.mask
    );
    assert!(with.mask.interior.false_shadow_pct < 0.1, "{:?}", with.mask);
}

#[test]
fn the_maps_and_floor_stages_render_maps_but_write_a_lit_mask() {
    let scene = squares_over_floor(
        &[(Vec3::new(0.0, 1.0, 0.0), 0.7)],
        Light::point(Vec3::new(0.4, 5.0, -0.3), 1.0),
        false,
    );
    let full = mask_of(&scene, "shadow-map", &[], 64, 64);
    assert!(full.iter().any(|&v| v < 0.5));
    for stage in ["maps", "floor"] {
        let m = mask_of(&scene, "shadow-map", &[&format!("stage={stage}")], 64, 64);
        assert!(m.iter().all(|&v| v == 1.0), "{stage}");
        // The maps were rendered all the same: the depth map seen from the
        // light holds the square (near) and the floor (far).
        let hf = frame_with_debug_views(&scene, &format!("shadow-map[stage={stage}]"), 64, 64);
        let views = hf.techniques[0].technique.debug_views(gpu()).unwrap();
        let map = &views.images[0];
        let greys: std::collections::HashSet<u8> =
            map.rgba.chunks_exact(4).map(|p| p[0] / 16).collect();
        assert!(greys.len() >= 2, "{stage}: depth map {greys:?}");
        assert!(hf.techniques[0].technique.resource_bytes() > 0, "{stage}");
    }
}

#[test]
fn maps_past_the_device_or_the_memory_budget_are_refused_before_allocating() {
    let gpu = gpu();
    // Frames beyond the device limit are refused.
    let e = shadowlab::frame::FrameTargets::new(gpu, gpu.max_texture_size() + 1, 8)
        .err()
        .unwrap();
    assert!(
        e.to_string().contains("the device's largest texture"),
        "{e}"
    );
    // A 16384² cube of VSM maps: 6 faces × 16384² × (4 + 2·16) bytes ≈ 55 GiB,
    // refused against the default 4 GiB budget on every device.
    let mut scene = builtin::by_name("room").unwrap().unwrap();
    scene.lights = scene.light_preset("point").unwrap();
    let mut c = shadowlab::technique::resolve("shadow-map:vsm").unwrap();
    c.params.set("size", "16384").unwrap();
    let mut hf = shadowlab::headless::HeadlessFrame::new(gpu, &scene, &[c], 64, 64).unwrap();
    let render = |hf: &mut shadowlab::headless::HeadlessFrame| {
        hf.render(
            gpu,
            &scene,
            &scene.camera,
            &scene.lights,
            &Default::default(),
        )
    };
    let e = format!("{:#}", render(&mut hf).unwrap_err());
    assert!(e.contains("6 map(s) of 16384x16384"), "{e}");
    assert!(e.contains("more than the memory budget of 4096 MiB"), "{e}");
    assert!(e.contains("55296.0 MiB"), "{e}");
    // Nothing failed stays cached: a size that fits renders shadows next.
    let mut params = hf.techniques[0].choice.params.clone();
    params.set("size", "256").unwrap();
    hf.techniques[0].set_params(params).unwrap();
    render(&mut hf).unwrap();
    let mask = shadowlab::headless::read_back(gpu, &hf.frame, 1)
        .unwrap()
        .masks
        .remove(0);
    assert!(mask.iter().any(|&v| v < 0.5));
    assert_eq!(
        hf.techniques[0].technique.resource_bytes(),
        6 * 256 * 256 * 36
    );
    // The budget is configurable on the command line.
    let o = shadowlab(&[
        "render",
        "--scene",
        "floating",
        "--technique",
        "shadow-map",
        "--set",
        "size=4096",
        "--memory-budget",
        "32",
        "--size",
        "32x32",
        "--out",
        tmpdir("budget").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("more than the memory budget of 32 MiB"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn soft_shadows_from_an_area_light_match_the_reference() {
    let mut scene = builtin::by_name("floating").unwrap().unwrap();
    scene.lights = scene.light_preset("area").unwrap();
    let out = tmpdir("soft");
    let list =
        shadowlab::measure::parse_technique_list("shadow-map:area,shadow-map:pcss,shadow-map:pcf")
            .unwrap();
    let reference = shadowlab::measure::parse_technique_list("raytraced:reference[samples=256]")
        .unwrap()
        .remove(0);
    let rows = shadowlab::measure::compare::run(
        gpu(),
        &scene,
        &scene.camera,
        &scene.lights,
        (320, 180),
        &list,
        &reference,
        &out,
    )
    .unwrap();
    let (area, pcss, hard) = (&rows[0].mask, &rows[1].mask, &rows[2].mask);
    assert!(area.mean_abs_error <= 0.03, "area: {area:?}");
    assert!(pcss.mean_abs_error <= 0.06, "pcss: {pcss:?}");
    // Both soften the shadow: closer to the reference than a hard-edged map.
    assert!(area.mean_abs_error < hard.mean_abs_error && pcss.mean_abs_error < hard.mean_abs_error);
}

#[test]
fn point_light_in_the_room_cube_and_dual_paraboloid() {
    let scene = builtin::by_name("room").unwrap().unwrap();
    for omni in ["cube", "dual-paraboloid"] {
        let row = compare(
            &scene,
            &format!("shadow-map:hard[size=1024,omni={omni}]"),
            (320, 180),
        );
        // An all-lit (or all-shadowed) mask would miss the reference's
        // shadow entirely: the mismatch must be a small part of it.
        let m = &row.mask;
        assert!(m.reference_shadowed_pct > 1.0, "{omni}: {m:?}");
        assert!(m.all.total_pct <= 2.0, "{omni}: {m:?}");
        assert!(
            m.all.total_pct <= 0.1 * m.reference_shadowed_pct,
            "{omni}: {m:?}"
        );
    }
    // A filtered lookup on the paraboloid maps stays within the bar too.
    let pcf = compare(&scene, "shadow-map:pcf[omni=dual-paraboloid]", (160, 90));
    let m = &pcf.mask;
    assert!(m.reference_shadowed_pct > 1.0, "{m:?}");
    assert!(m.all.total_pct <= 0.1 * m.reference_shadowed_pct, "{m:?}");
}

#[test]
fn debug_views_show_frusta_the_map_and_texels_per_pixel() {
    let mut scene = builtin::by_name("floating").unwrap().unwrap();
    scene.lights = scene.light_preset("sun").unwrap();
    let gpu = gpu();
    let hf = frame_with_debug_views(&scene, "shadow-map:hard", 160, 90);
    let views = hf.techniques[0].technique.debug_views(gpu).unwrap();
    // A directional light: one box, twelve edges.
    assert_eq!(views.lines.len(), 12);
    assert_eq!(views.images.len(), 3);
    let (map, projection, texels) = (&views.images[0], &views.images[1], &views.images[2]);
    assert_eq!((map.width, map.height), (256, 256));
    assert_eq!((projection.width, projection.height), (160, 90));
    // The map holds nearer casters (darker) than the far floor.
    let greys: std::collections::HashSet<u8> =
        map.rgba.chunks_exact(4).map(|p| p[0] / 16).collect();
    assert!(greys.len() > 3, "{greys:?}");
    // Texels per pixel are coloured on the geometry: green-to-red or green-to-blue.
    let coloured = texels
        .rgba
        .chunks_exact(4)
        .filter(|p| p[1] > 0 || p[0] > 0 || p[2] > 0)
        .count();
    assert!(coloured > 160 * 90 / 3, "{coloured}");
}

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
        &scene,
        &scene.camera,
        &scene.lights,
        size,
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
/// whole texels).
#[test]
fn map_selection_keeps_cascade_borders_still_on_a_dolly() {
    let pct = flicker_over_squares(
        "shadow-map:csm[size=256,select=depth],shadow-map:csm[size=256,select=map]",
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
    let (w, h) = (256, 144);
    let (seen, frustum) = footprints(
        &land,
        "shadow-map:pcf",
        "shadow-map:pcf[fit=frustum]",
        (w, h),
    );
    assert!(
        seen < 0.8 * frustum,
        "fitted to the pixels {seen} px/texel, to the frustum {frustum}"
    );
    let fitted = compare(&land, "shadow-map:pcf", (w, h)).mask;
    let wide = compare(&land, "shadow-map:pcf[fit=frustum]", (w, h)).mask;
    assert!(
        fitted.all.total_pct * 2.0 <= wide.all.total_pct,
        "fitted {fitted:?}\nfrustum {wide:?}"
    );
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

/// The bias cap (`slope_bias_clamp`): in the half-pipe lit at grazing
/// angles, the uncapped slope bias pushes the pipe's own stored depth far
/// behind it and light leaks through onto the wall it shades; capped, the
/// interior is clean, and no acne appears elsewhere. The same holds for a
/// virtual map's clipmap levels, each capped by its own texel size.
#[test]
fn capping_the_slope_bias_stops_light_leaking_at_grazing_casters() {
    let pipe = preset("curved", "pipe", "sun");
    for (technique, capped_at_most, uncapped_at_least) in [
        ("shadow-map:pcf", 0.05, 0.2),
        ("shadow-map:virtual", 0.01, 0.03),
    ] {
        let capped = compare(&pipe, technique, (320, 180)).mask;
        let uncapped = compare(
            &pipe,
            &format!("{technique}[slope_bias_clamp=0]"),
            (320, 180),
        )
        .mask;
        assert!(
            capped.interior.false_lit_pct <= capped_at_most
                && uncapped.interior.false_lit_pct >= uncapped_at_least,
            "{technique}: capped {capped:?}\nuncapped {uncapped:?}"
        );
        // Capped, no acne comes back on the other scenes under the sun.
        for name in ["room", "bunny", "columns", "teapot", "floating"] {
            let mut scene = builtin::by_name(name).unwrap().unwrap();
            scene.lights = scene.light_preset("sun").unwrap();
            let m = compare(&scene, technique, (320, 180)).mask;
            assert!(
                m.interior.false_shadow_pct <= 0.1,
                "{technique} on {name}: {m:?}"
            );
        }
    }
}

#[test]
fn edge_masked_filters_equal_the_full_kernel_on_the_builtin_scenes() {
    for name in ["room", "columns", "city", "floating", "curved"] {
        let scene = builtin::by_name(name).unwrap().unwrap();
        for (filter, extra) in [
            ("grid", "samples=5"),
            ("disk", "radius=4"),
            ("pcss", "samples=4"),
            ("varwidth", "samples=3"),
            ("grid", "format=r8"),
            ("grid", "receiver_plane=true"),
        ] {
            let set = ["filter", filter].join("=");
            let full = mask_of(&scene, "shadow-map", &[&set, extra], 240, 135);
            let masked = mask_of(
                &scene,
                "shadow-map",
                &[&set, extra, "edge_mask=true"],
                240,
                135,
            );
            let differ = pixels_differing(&full, &masked);
            assert!(
                differ as f64 <= 1e-4 * full.len() as f64,
                "{name} {filter} {extra}: {differ} of {} pixels differ",
                full.len()
            );
        }
    }
}

/// `cull=solids` (the default): the columns and their lintel bound solids,
/// so the map holds their back faces unbiased and their lit faces take no
/// normal offset — the shadow edges stay where the silhouettes put them,
/// with fewer mismatched pixels than both faces biased and offset
/// (`cull=none`) and no acne on the lit faces. On the bunny, a smooth solid
/// that shadows itself near its terminators, a back face can lie too close
/// before the receiver to shadow it; the front faces stored with a pushed
/// bias (`solid_front_bias`) still do.
#[test]
fn solids_store_their_back_faces_and_keep_shadow_edges_in_place() {
    let columns = preset("columns", "default", "sun");
    let solids = compare(&columns, "shadow-map:pcf", (640, 360)).mask;
    let both = compare(&columns, "shadow-map:pcf[cull=none]", (640, 360)).mask;
    assert!(
        solids.all.total_pct <= 0.8 * both.all.total_pct && solids.interior.false_shadow_pct == 0.0,
        "solids {solids:?}\nboth faces {both:?}"
    );
    let bunny = preset("bunny", "default", "sun");
    let with_front = compare(&bunny, "shadow-map:pcf", (640, 360)).mask;
    let back_only = compare(&bunny, "shadow-map:pcf[solid_front_bias=0]", (640, 360)).mask;
    assert!(
        with_front.all.total_pct * 2.0 <= back_only.all.total_pct
            && with_front.interior.false_lit_pct <= 0.01
            && back_only.interior.false_lit_pct > 0.01,
        "front faces too {with_front:?}\nback faces only {back_only:?}"
    );
}

/// The receiver plane taken from the surface's own normal, each texel
/// compared against the plane at its centre: edges stay in place (screen
/// derivatives of the light-space position broke the plane at every pixel
/// quad that straddles an edge: 0.117 % total mismatch on columns/sun), and
/// a lit wall next to its building's corner no longer compares against the
/// back face that meets it there (the street's interior false shadow).
#[test]
fn the_receiver_plane_from_the_normal_keeps_edges_and_clears_corners() {
    let columns = preset("columns", "default", "sun");
    let plane = compare(&columns, "shadow-map:pcf[receiver_plane=true]", (640, 360)).mask;
    assert!(plane.all.total_pct <= 0.03, "{plane:?}");
    let city = preset("city", "street", "sun");
    let constant = compare(&city, "shadow-map:pcf[part_ids=false]", (640, 360)).mask;
    let plane = compare(
        &city,
        "shadow-map:pcf[part_ids=false,receiver_plane=true]",
        (640, 360),
    )
    .mask;
    assert!(
        plane.interior.false_shadow_pct <= 0.3 * constant.interior.false_shadow_pct,
        "plane {plane:?}\nconstant depth {constant:?}"
    );
}

/// Convex part IDs beside the depth (`part_ids`, the default): a lit wall
/// of a building in the street ignores the back faces of its own box that
/// meet it at the corner (interior false shadow 0.123 → 0.017 % at
/// 640×360), while the buildings of one block mesh, separate parts, still
/// shadow each other and the trunks under the canopies (separate parts of
/// one tree) stay shadowed — the receiver plane's failure. A floor is a
/// flat part: it takes no normal offset, which only moved its shadow edges
/// (room under the point light: 0.0054 → 0.0036 % total mismatch).
#[test]
fn convex_parts_ignore_their_own_texels_and_still_shadow_each_other() {
    let city = preset("city", "street", "sun");
    let parts = compare(&city, "shadow-map:pcf", (640, 360)).mask;
    let without = compare(&city, "shadow-map:pcf[part_ids=false]", (640, 360)).mask;
    assert!(
        parts.interior.false_shadow_pct <= 0.25 * without.interior.false_shadow_pct
            && parts.interior.false_shadow_pct <= 0.1
            && parts.interior.false_lit_pct <= without.interior.false_lit_pct + 0.001,
        "part IDs {parts:?}\nwithout {without:?}"
    );
    let landscape = preset("landscape", "ground", "sun");
    let parts = compare(&landscape, "shadow-map:pcf", (640, 360)).mask;
    let without = compare(&landscape, "shadow-map:pcf[part_ids=false]", (640, 360)).mask;
    assert!(
        parts.interior.false_lit_pct <= without.interior.false_lit_pct + 0.001,
        "part IDs {parts:?}\nwithout {without:?}"
    );
    let room = preset("room", "default", "point");
    let parts = compare(&room, "shadow-map:pcf", (640, 360)).mask;
    let without = compare(&room, "shadow-map:pcf[part_ids=false]", (640, 360)).mask;
    assert!(
        parts.all.total_pct <= 0.8 * without.all.total_pct
            && parts.interior.total_pct <= without.interior.total_pct,
        "part IDs {parts:?}\nwithout {without:?}"
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
/// come far closer to the reference.
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
        "shadow-map:pcf[fit=frustum]",
        (w, h),
    );
    assert!(
        focused < 0.6 * whole,
        "focused {focused} px/texel, the whole cone {whole}"
    );
    let f = compare(&scene, "shadow-map:pcf[size=256]", (w, h)).mask;
    let c = compare(&scene, "shadow-map:pcf[size=256,fit=frustum]", (w, h)).mask;
    assert!(f.reference_shadowed_pct > 2.0, "{f:?}");
    assert!(
        // Measured at 256²: 0.43 against 1.96 %.
        f.all.total_pct * 3.0 <= c.all.total_pct,
        "focused {f:?}\nwhole cone {c:?}"
    );
}
