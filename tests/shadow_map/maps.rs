//! One map per face: the light's texture matrix, cube-face selection, the
//! filters against the ray-traced reference, the 8-bit failure, stages,
//! the memory budget, area lights, the point light's faces and debug views.

use super::common::*;
use glam::{Mat4, Vec3, Vec4};
use shadowlab::scene::{Camera, Light, LightArea, Material, Scene, builtin, shapes};
use shadowlab::technique::light_space::bias_matrix;

/// The six directions along the world's axes: one per cube face.
const AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];
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
    for (i, d) in AXES.into_iter().enumerate() {
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
    for d in AXES {
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

/// `edge_ramp_pixels`: where the map's texels are magnified (a 64² map
/// seen close up, a few pixels a texel), a kernel's ramp spans many pixels
/// of graded visibility past the reference's edge band — the 3×3 grid's
/// some fifteen, and under a light without an area (no penumbra to draw)
/// the ½-texel disk of pcss and varwidth and the moment filters' blur
/// fewer; steepened to two
/// pixels, the edge is as sharp as the hard light's, and no pixel changes
/// side of ½ (the thresholded mismatch cannot move).
#[test]
fn magnified_texels_keep_a_hard_lights_edge_sharp() {
    let sun = lights_over_squares()[2];
    let mut scene = squares_over_floor(&[(Vec3::new(0.0, 1.0, 0.0), 0.7)], sun, false);
    scene.camera = Camera::new(Vec3::new(1.0, 0.8, 1.2), Vec3::new(1.0, 0.0, 0.2));
    for (id, least_graded) in [
        ("shadow-map:pcf", 5.0),
        ("shadow-map:pcss", 2.0),
        ("shadow-map:varwidth", 2.0),
        ("shadow-map:vsm", 2.0),
        ("shadow-map:msm", 2.0),
    ] {
        let steep = compare(&scene, &format!("{id}[size=64]"), (160, 90)).mask;
        let soft = compare(
            &scene,
            &format!("{id}[size=64,edge_ramp_pixels=0]"),
            (160, 90),
        )
        .mask;
        assert!(
            soft.graded_interior_pct > least_graded
                && steep.graded_interior_pct <= 0.2 * soft.graded_interior_pct
                && steep.interior_mae <= 0.5 * soft.interior_mae,
            "{id}: steepened {steep:?}\nas filtered {soft:?}"
        );
        let a = mask_of(&scene, id, &["size=64"], 160, 90);
        let b = mask_of(&scene, id, &["size=64", "edge_ramp_pixels=0"], 160, 90);
        let changed = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| (**x < 0.5) != (**y < 0.5))
            .count();
        let graded = b.iter().filter(|v| **v > 0.05 && **v < 0.95).count();
        assert!(
            changed == 0 && graded > 100,
            "{id}: {changed} pixels changed side, {graded} graded as filtered"
        );
    }
}

/// A penumbra is not a ramp to steepen: under a light with an area, pcss
/// draws the penumbra the area casts, and `edge_ramp_pixels` leaves every
/// pixel of it as it is, magnified texels or not.
#[test]
fn an_area_lights_penumbra_is_not_steepened() {
    let mut sun = lights_over_squares()[2];
    sun.area = Some(LightArea::Sphere { radius: 0.02 });
    let mut scene = squares_over_floor(&[(Vec3::new(0.0, 1.0, 0.0), 0.7)], sun, false);
    scene.camera = Camera::new(Vec3::new(1.0, 0.8, 1.2), Vec3::new(1.0, 0.0, 0.2));
    for id in ["shadow-map:pcss", "shadow-map:vsm"] {
        let a = mask_of(&scene, id, &["size=64"], 160, 90);
        let b = mask_of(&scene, id, &["size=64", "edge_ramp_pixels=0"], 160, 90);
        let graded = a.iter().filter(|v| **v > 0.05 && **v < 0.95).count();
        assert!(
            a == b && graded > 100,
            "{id}: {graded} graded pixels, masks equal: {}",
            a == b
        );
    }
}

/// `esm` filters exp(c·z) in log space, so no exponent overflows a 32-bit
/// float: at c = 2000, 25 times what exp(c(z − 1)) allowed, the square's
/// shadow is still there, as sharp as the reference's away from its edges,
/// and every visibility is a number in [0, 1].
#[test]
fn log_space_esm_takes_exponents_past_a_floats_range() {
    for light in lights_over_squares() {
        let scene = squares_over_floor(&[(Vec3::new(0.0, 1.0, 0.0), 0.7)], light, false);
        let m = compare(&scene, "shadow-map:esm[esm_exponent=2000]", (200, 200)).mask;
        let shadow = m.reference_shadowed_pct;
        assert!(
            shadow > 2.0
                && m.all.total_pct <= 0.08 * shadow
                && m.interior_mae < 0.002
                && m.graded_interior_pct < 0.5,
            "{:?}: {m:?}",
            light.kind
        );
        let mask = mask_of(&scene, "shadow-map:esm", &["esm_exponent=2000"], 64, 64);
        assert!(
            mask.iter().all(|v| (0.0..=1.0).contains(v)),
            "{:?}: a visibility outside [0, 1]",
            light.kind
        );
    }
}

#[test]
fn filters_match_the_reference_on_a_square_over_a_plane() {
    // Bounds as shares of the reference's shadow: the hard-edged filters
    // within 1 % of it and exact away from its edges; the soft and moment
    // filters, whose penumbrae and light bleeding widen the edge, within
    // 8 % and 2 % away from it.
    for light in lights_over_squares() {
        let scene = squares_over_floor(&[(Vec3::new(0.0, 1.0, 0.0), 0.7)], light, false);
        for (id, total_share, interior_share) in [
            ("shadow-map:hard", 0.01, 0.0),
            ("shadow-map:pcf2x2", 0.01, 0.0),
            ("shadow-map:pcf", 0.01, 0.0),
            ("shadow-map:pcf-disk", 0.01, 0.0),
            ("shadow-map:pcss", 0.08, 0.02),
            ("shadow-map:varwidth", 0.08, 0.02),
            ("shadow-map:vsm", 0.08, 0.02),
            ("shadow-map:esm", 0.08, 0.02),
            ("shadow-map:evsm2", 0.08, 0.02),
            ("shadow-map:evsm4", 0.08, 0.02),
            ("shadow-map:msm", 0.08, 0.02),
        ] {
            let row = compare(&scene, id, (200, 200));
            let m = &row.mask;
            let shadow = m.reference_shadowed_pct;
            assert!(shadow > 2.0);
            assert!(
                m.interior.total_pct <= interior_share * shadow,
                "{id} {:?}: {m:?}",
                light.kind
            );
            assert!(
                m.all.total_pct <= total_share * shadow,
                "{id} {:?}: {:.4} % of a {shadow:.3} % shadow: {m:?}",
                light.kind,
                m.all.total_pct
            );
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
    let without = compare(
        &scene,
        &format!("shadow-map:pcf[{bare},receiver_plane=false]"),
        (200, 200),
    );
    let with = compare(&scene, &format!("shadow-map:pcf[{bare}]"), (200, 200));
    assert!(
        without.mask.interior.false_shadow_pct > 5.0,
        "{:?}",
        without.mask
    );
    assert!(
        with.mask.interior.false_shadow_pct < 0.1 && with.mask.interior_mae < 0.002,
        "{:?}",
        with.mask
    );
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
        shadowlab::measure::FrameRequest {
            scene: &scene,
            camera: &scene.camera,
            lights: &scene.lights,
            size: (320, 180),
        },
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
