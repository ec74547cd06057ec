//! The ray-traced reference against analytic shadows, and `compare` of
//! `none` against it.

mod common;
use common::*;
use glam::{Mat4, Vec3, Vec4};
use shadowlab::headless::{self, HeadlessFrame};
use shadowlab::measure;
use shadowlab::renderer::RenderSettings;
use shadowlab::scene::{Camera, Light, LightArea, Material, Scene, shapes};
use shadowlab::technique;

/// A floor and a 1×1 square occluder at height `h` facing down (so that
/// with back-face culling a camera above sees the floor through it, while
/// shadow rays, which hit both sides, are blocked).
fn square_over_plane(h: f32, light: Light) -> Scene {
    let mut s = Scene::new("square");
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let floor = s.add_mesh(shapes::plane(20.0, 20.0, 4));
    s.add_object("Floor", floor, grey, Mat4::IDENTITY);
    let quad = s.add_mesh(shapes::plane(1.0, 1.0, 1));
    s.add_object(
        "Square",
        quad,
        grey,
        Mat4::from_translation(Vec3::new(0.0, h, 0.0))
            * Mat4::from_rotation_x(std::f32::consts::PI),
    );
    s.lights = vec![light];
    s.finalize().unwrap();
    s
}

/// The floor point (y = 0) seen through pixel centre (x + 0.5, y + 0.5),
/// using the conventions documented in frame.json.
fn floor_point(view_proj: Mat4, w: u32, h: u32, x: u32, y: u32) -> Vec3 {
    floor_point_at(view_proj, w, h, x as f32 + 0.5, y as f32 + 0.5)
}

/// The floor point under continuous pixel coordinates (fx, fy).
fn floor_point_at(view_proj: Mat4, w: u32, h: u32, fx: f32, fy: f32) -> Vec3 {
    let inv = view_proj.inverse();
    let ndc_x = 2.0 * fx / w as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * fy / h as f32;
    let a = inv * Vec4::new(ndc_x, ndc_y, 1.0, 1.0);
    let b = inv * Vec4::new(ndc_x, ndc_y, 0.5, 1.0);
    let (a, b) = (a.truncate() / a.w, b.truncate() / b.w);
    let t = a.y / (a.y - b.y);
    a + (b - a) * t
}

fn render_reference(scene: &Scene, camera: &Camera, id: &str, w: u32, h: u32) -> (Vec<f32>, Mat4) {
    let gpu = gpu();
    let choice = technique::parse_choice(id).unwrap();
    let mut hf = HeadlessFrame::new(gpu, scene, &[choice], w, h).unwrap();
    let settings = RenderSettings {
        show_light_icons: false,
        ..Default::default()
    };
    hf.render(gpu, scene, camera, &scene.lights, &settings)
        .unwrap();
    let img = headless::read_back(gpu, &hf.frame, 1).unwrap();
    (img.masks[0].clone(), hf.frame.uniform().view_proj)
}

#[test]
fn hard_shadow_matches_the_projected_square() {
    // Point light at height 4 over a square at height 1: the shadow is the
    // square scaled by 4 / (4 − 1) about the light's foot, offset by its x, z.
    let light_pos = Vec3::new(0.3, 4.0, -0.2);
    let scene = square_over_plane(1.0, Light::point(light_pos, 1.0));
    let camera = Camera {
        up: Vec3::NEG_Z,
        ..Camera::new(Vec3::new(0.0, 6.0, 0.0), Vec3::ZERO)
    };
    let (w, h) = (200, 200);
    let (mask, vp) = render_reference(&scene, &camera, "raytraced", w, h);
    let shadowed = |p: Vec3| {
        // A floor point is shadowed iff the segment to the light crosses the
        // square: at height 1 the segment is at light + (p − light)·(3/4).
        let c = light_pos + (p - light_pos) * (3.0 / 4.0);
        c.x.abs() < 0.5 && c.z.abs() < 0.5
    };
    let (mut checked, mut crossed, mut in_shadow) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            // Pixels the boundary crosses: the classes at the pixel's corners differ.
            let corners: Vec<bool> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .map(|&(dx, dy)| shadowed(floor_point_at(vp, w, h, x as f32 + dx, y as f32 + dy)))
                .collect();
            if corners.iter().any(|&c| c != corners[0]) {
                crossed += 1;
                continue;
            }
            let expect = shadowed(floor_point(vp, w, h, x, y));
            let got = mask[(y * w + x) as usize];
            assert_eq!(got < 0.5, expect, "pixel ({x}, {y}): visibility {got}");
            assert!(
                got == 0.0 || got == 1.0,
                "hard light gives binary visibility"
            );
            checked += 1;
            in_shadow += expect as usize;
        }
    }
    assert!(
        in_shadow > 1000 && crossed < 2000 && checked > 35000,
        "{in_shadow} {crossed} {checked}"
    );
}

#[test]
fn area_light_umbra_and_penumbra_match_similar_triangles() {
    // Sphere light radius R at height H, square half-size e at height hh:
    // k = H / (H − hh); umbra half-width e·k − R(k − 1); penumbra width 2R(k − 1).
    let (big_h, hh, r, e) = (5.0f32, 2.5f32, 0.5f32, 0.5f32);
    let mut light = Light::point(Vec3::new(0.0, big_h, 0.0), 1.0);
    light.area = Some(LightArea::Sphere { radius: r });
    let scene = square_over_plane(hh, light);
    let (w, h) = (320, 16);
    let half_width = 2.2f32;
    let aspect = w as f32 / h as f32;
    let camera = Camera {
        up: Vec3::NEG_Z,
        fov_y_deg: 2.0 * ((half_width / 6.0) / aspect).atan().to_degrees(),
        ..Camera::new(Vec3::new(0.0, 6.0, 0.0), Vec3::ZERO)
    };
    let (mask, vp) = render_reference(&scene, &camera, "raytraced:reference", w, h);
    let row = h / 2;
    let px = (floor_point(vp, w, h, 1, row).x - floor_point(vp, w, h, 0, row).x).abs();
    let k = big_h / (big_h - hh);
    let umbra_expect = 2.0 * (e * k - r * (k - 1.0));
    let penumbra_expect = 2.0 * r * (k - 1.0);
    let vis: Vec<f32> = (0..w).map(|x| mask[(row * w + x) as usize]).collect();
    let umbra = vis.iter().filter(|&&v| v == 0.0).count() as f32 * px;
    let penumbra = vis.iter().filter(|&&v| v > 0.0 && v < 1.0).count() as f32 * px / 2.0;
    assert!(
        (umbra - umbra_expect).abs() <= 2.0 * px,
        "umbra {umbra} vs {umbra_expect} (pixel {px})"
    );
    assert!(
        (penumbra - penumbra_expect).abs() <= 2.0 * px,
        "penumbra {penumbra} vs {penumbra_expect} (pixel {px})"
    );
    // Visibility grows monotonically (within sampling noise) from the umbra outwards.
    let centre = (w / 2) as usize;
    for x in centre..w as usize - 1 {
        assert!(
            vis[x + 1] + 0.05 >= vis[x],
            "x {x}: {} then {}",
            vis[x],
            vis[x + 1]
        );
    }
}

/// Embree (loaded at run time; scripts/setup.sh installs it) and the
/// pure-Rust obvhs kernel trace the same rays: on built-in views the masks
/// differ in at most a few pixels where a ray grazes a triangle's edge,
/// hard and soft; both pass the similar-triangle test above.
#[test]
fn embree_and_obvhs_give_the_same_masks() {
    shadowlab::scene::embree::available().expect("Embree 3 is installed (scripts/setup.sh)");
    for (name, light, w, h) in [
        ("columns", "point", 320, 180),
        ("bunny", "spot", 320, 180),
        ("city", "sun", 320, 180),
        ("floating", "area", 160, 90),
    ] {
        let mut scene = shadowlab::scene::builtin::by_name(name).unwrap().unwrap();
        scene.lights = scene.light_preset(light).unwrap();
        let camera = scene.camera;
        let (a, _) = render_reference(&scene, &camera, "raytraced[kernel=obvhs]", w, h);
        let (b, _) = render_reference(&scene, &camera, "raytraced[kernel=embree]", w, h);
        let differ = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| (*x - *y).abs() > 0.02)
            .count();
        let total = (w * h) as usize;
        assert!(
            differ * 10_000 <= total,
            "{name}/{light}: {differ} of {total} pixels differ"
        );
        assert!(a.iter().any(|&v| v < 0.5), "{name}/{light} has shadows");
    }
}

#[test]
fn a_scene_without_casters_is_fully_lit() {
    let mut scene = square_over_plane(1.0, Light::point(Vec3::new(0.0, 4.0, 0.0), 1.0));
    for o in &mut scene.objects {
        o.casts_shadow = false;
    }
    let camera = Camera::new(Vec3::new(3.0, 5.0, 3.0), Vec3::ZERO);
    let (mask, _) = render_reference(&scene, &camera, "raytraced", 64, 64);
    assert!(mask.iter().all(|&v| v == 1.0));
}

/// Reads a CSV file written by `compare` or `bench` into header → values rows.
fn read_csv(path: &std::path::Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().clone();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            header
                .iter()
                .zip(rec.iter())
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        })
        .collect()
}

fn num(row: &std::collections::HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse()
        .unwrap_or_else(|_| panic!("{key} = '{}'", row[key]))
}

#[test]
fn compare_none_reports_the_reference_shadow_as_false_lit() {
    let scene = shadowlab::scene::builtin::by_name("room").unwrap().unwrap();
    let out = tmpdir("compare");
    // The second label has commas inside brackets: the CSV must quote it.
    let list = measure::parse_technique_list("none,raytraced[samples=64,offset_ulps=100]").unwrap();
    let reference = technique::resolve("raytraced").unwrap();
    let rows = measure::compare::run(
        gpu(),
        shadowlab::measure::FrameRequest {
            scene: &scene,
            camera: &scene.camera,
            lights: &scene.lights,
            size: (160, 90),
        },
        &list,
        &reference,
        &out,
    )
    .unwrap();
    assert_eq!(rows.len(), 2);
    let m = &rows[0].mask;
    assert!(
        m.reference_shadowed_pct > 1.0,
        "the room has shadows: {}",
        m.reference_shadowed_pct
    );
    assert_eq!(m.all.false_shadow_pct, 0.0);
    assert!((m.all.false_lit_pct - m.reference_shadowed_pct).abs() < 1e-9);
    assert!((m.all.total_pct - m.edge.total_pct - m.interior.total_pct).abs() < 1e-9);
    assert!(m.mean_abs_error > 0.0 && rows[0].flip.mean > 0.0);
    // The reference against itself (hard light: samples do not matter, a
    // larger offset moves few pixels): almost no mismatch.
    let r = &rows[1].mask;
    assert!(
        r.all.total_pct <= 0.05 && r.interior.total_pct == 0.0 && r.interior_mae < 1e-3,
        "{r:?}"
    );
    // `none` is lit where the reference is shadowed: fully wrong there, in
    // the interior too, and never graded (it is exactly 1).
    assert!(
        m.interior_mae > 0.0 && m.graded_interior_pct == 0.0,
        "{m:?}"
    );
    for f in [
        "quality.md",
        "heatmap-none_default.png",
        "none_default.png",
        "reference/image.png",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    // The CSV and JSON carry the same numbers as the rows.
    let csv = read_csv(&out.join("quality.csv"));
    assert_eq!(csv.len(), 2);
    assert_eq!(csv[0]["technique"], "none:default");
    assert_eq!(
        csv[1]["technique"],
        "raytraced:default[samples=64,offset_ulps=100]"
    );
    for (c, row) in csv.iter().zip(&rows) {
        assert_eq!(
            num(c, "considered_pixels") as usize,
            row.mask.considered_pixels
        );
        assert!((num(c, "false_lit_pct") - row.mask.all.false_lit_pct).abs() < 1e-4);
        assert!((num(c, "total_pct") - row.mask.all.total_pct).abs() < 1e-4);
        assert!((num(c, "mean_abs_error") - row.mask.mean_abs_error).abs() < 1e-5);
        assert!((num(c, "interior_mae") - row.mask.interior_mae).abs() < 1e-5);
        assert!((num(c, "graded_interior_pct") - row.mask.graded_interior_pct).abs() < 1e-4);
    }
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("quality.json")).unwrap()).unwrap();
    assert_eq!(j["rows"][0]["technique"], "none:default");
    let json_total = j["rows"][0]["mask"]["all"]["total_pct"].as_f64().unwrap();
    assert!((json_total - m.all.total_pct).abs() < 1e-9, "{json_total}");
}

#[test]
fn bench_writes_ratios_to_none() {
    let scene = shadowlab::scene::builtin::by_name("floating")
        .unwrap()
        .unwrap();
    let out = tmpdir("bench");
    let list = measure::parse_technique_list("raytraced,shadow-map[size=256,filter=hard]").unwrap();
    let bench = |counts: measure::bench::BenchFrames, out: &std::path::Path| {
        measure::bench::run(
            gpu(),
            shadowlab::measure::FrameRequest {
                scene: &scene,
                camera: &scene.camera,
                lights: &scene.lights,
                size: (96, 54),
            },
            &Default::default(),
            &list,
            counts,
            out,
        )
        .unwrap()
    };
    let rows = bench(
        measure::bench::BenchFrames {
            warmup: 1,
            measured: 3,
            progress: false,
            max_seconds: None,
        },
        &out,
    );
    assert_eq!(rows.len(), 3, "none is added");
    assert_eq!(rows[0].technique, "none:default");
    let none = rows[0].frame_ms.median;
    for r in &rows {
        let f = &r.frame_ms;
        assert!(0.0 < f.p5 && f.p5 <= f.median && f.median <= f.p95, "{r:?}");
        assert!(r.masks_ms.median <= f.median, "{r:?}");
        assert!(
            (r.ratio_to_none - f.median / none).abs() < 1e-9 * r.ratio_to_none,
            "{}: ratio {} vs {} / {none}",
            r.technique,
            r.ratio_to_none,
            f.median
        );
        assert_eq!(r.triangles_drawn, scene.triangle_count());
        assert_eq!(r.measured_frames, 3);
    }
    // Out of time at once: the warm-up is skipped, one frame measured.
    let hurried = bench(
        measure::bench::BenchFrames {
            warmup: 2,
            measured: 5,
            progress: false,
            max_seconds: Some(0.0),
        },
        &tmpdir("bench-hurried"),
    );
    assert!(
        hurried.iter().all(|r| r.measured_frames == 1),
        "{hurried:?}"
    );
    // One shadow ray per covered pixel for the hard light.
    let rays = rows[1]
        .counters
        .iter()
        .find(|(k, _)| k == "rays")
        .map(|(_, v)| *v)
        .unwrap();
    assert!(rays > 0.3 * 96.0 * 54.0 && rays <= 96.0 * 54.0, "{rays}");
    assert!(rows[1].shadow_resource_bytes > 0);
    // The point light's cube: six 256² faces, each texel a d24 depth (4
    // bytes) and its convex part's ID (4 bytes, part_ids).
    assert_eq!(rows[2].shadow_resource_bytes, 6 * 256 * 256 * (4 + 4));
    assert!(out.join("bench.md").exists());
    let csv = read_csv(&out.join("bench.csv"));
    assert_eq!(csv.len(), 3);
    assert_eq!(csv[2]["technique"], "shadow-map:pcf[filter=hard,size=256]");
    for (c, r) in csv.iter().zip(&rows) {
        assert_eq!(c["technique"], r.technique);
        assert!((num(c, "frame_ms_median") - r.frame_ms.median).abs() < 1e-3);
        assert!((num(c, "ratio_to_none") - r.ratio_to_none).abs() < 1e-4);
        assert_eq!(
            num(c, "shadow_resource_bytes") as u64,
            r.shadow_resource_bytes
        );
    }
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("bench.json")).unwrap()).unwrap();
    assert_eq!(j["rows"].as_array().unwrap().len(), 3);
    // serde_json's float parsing may differ from the written value by an ULP.
    let json_ratio = j["rows"][1]["ratio_to_none"].as_f64().unwrap();
    assert!(
        (json_ratio - rows[1].ratio_to_none).abs() <= 1e-12 * rows[1].ratio_to_none,
        "{json_ratio} vs {}",
        rows[1].ratio_to_none
    );
}

/// `bench` counts one frame's invocations per stage where the adapter has
/// pipeline-statistics queries (lavapipe does): `none` asks nothing of the
/// mask stage; a shadow map's lookup runs once per pixel beside its depth
/// pass's vertices; shadow volumes extrude in compute and fill at least the
/// fragments they count themselves; and bench.json carries it all.
#[test]
fn bench_counts_the_work_of_each_stage() {
    if !gpu().pipeline_statistics {
        eprintln!(
            "SKIPPED: {} has no pipeline-statistics queries",
            gpu().adapter_summary()
        );
        return;
    }
    let scene = shadowlab::scene::builtin::by_name("floating")
        .unwrap()
        .unwrap();
    let out = tmpdir("bench-work");
    let list = measure::parse_technique_list("shadow-map[size=256,filter=hard],shadow-volume:auto")
        .unwrap();
    let (w, h) = (96u64, 54u64);
    let frames = measure::bench::BenchFrames {
        warmup: 1,
        measured: 2,
        progress: false,
        max_seconds: None,
    };
    let run = |out: &std::path::Path| {
        measure::bench::run(
            gpu(),
            shadowlab::measure::FrameRequest {
                scene: &scene,
                camera: &scene.camera,
                lights: &scene.lights,
                size: (w as u32, h as u32),
            },
            &Default::default(),
            &list,
            frames,
            out,
        )
        .unwrap()
    };
    let rows = run(&out);
    let work = |i: usize| rows[i].work.expect("counted");
    let none = work(0);
    assert_eq!(
        none.masks,
        Default::default(),
        "none draws nothing into its mask"
    );
    assert!(none.prepass.fragment_invocations >= w * h / 2, "{none:?}");
    assert!(none.lighting.fragment_invocations > 0, "{none:?}");
    let map = work(1);
    assert!(map.masks.vertex_invocations > 0, "{map:?}");
    assert!(
        map.masks.fragment_invocations >= w * h,
        "the lookup covers the frame: {map:?}"
    );
    assert_eq!(map.prepass, none.prepass, "the same prepass");
    let volumes = work(2);
    assert!(
        volumes.masks.compute_invocations > 0,
        "extrusion: {volumes:?}"
    );
    let counted = rows[2]
        .counters
        .iter()
        .find(|(n, _)| n == "volume_fragments")
        .map(|c| c.1)
        .expect("volume_fragments");
    assert!(
        volumes.masks.fragment_invocations as f64 >= counted,
        "{volumes:?} vs {counted}"
    );
    // The count is the frame's, not the run's: a second run counts the
    // same fragments, compute invocations and primitives (vertex shader
    // invocations depend on the rasterizer's vertex reuse: within 5 %).
    let again = run(&tmpdir("bench-work-again"));
    for (a, b) in rows.iter().zip(&again) {
        let (a, b, t) = (a.work.unwrap(), b.work.unwrap(), &a.technique);
        for (x, y) in [
            (a.prepass, b.prepass),
            (a.masks, b.masks),
            (a.lighting, b.lighting),
        ] {
            assert_eq!(x.fragment_invocations, y.fragment_invocations, "{t}");
            assert_eq!(x.compute_invocations, y.compute_invocations, "{t}");
            assert_eq!(x.clipper_primitives, y.clipper_primitives, "{t}");
            let (vx, vy) = (x.vertex_invocations as f64, y.vertex_invocations as f64);
            assert!((vx - vy).abs() <= 0.05 * vx.max(vy), "{t}: {vx} vs {vy}");
        }
    }
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    assert_eq!(
        j["rows"][1]["work"]["masks"]["fragment_invocations"].as_u64(),
        Some(map.masks.fragment_invocations)
    );
}

/// Rolling terrain (a heightfield of 64² quads with valleys, 20 units
/// wide) under a sun, seen from afar at a slant, as a terrain asset is: a
/// pixel spans about 0.08 units of it.
fn terrain_from_afar() -> (Scene, Camera) {
    let mut s = Scene::new("terrain");
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let ground = s.add_mesh(shapes::heightfield(20.0, 64, |x, z| {
        0.8 * (0.9 * x).sin() * (0.7 * z).cos() + 0.3 * (2.3 * x + 1.1 * z).sin()
    }));
    s.add_object("Terrain", ground, grey, Mat4::IDENTITY);
    s.lights = vec![Light::directional(Vec3::new(-1.0, -0.7, -0.3), 1.0)];
    s.finalize().unwrap();
    (s, Camera::new(Vec3::new(14.0, 12.0, 24.0), Vec3::ZERO))
}

/// The G-buffer's positions are interpolated by the rasterizer, with an
/// error that grows with the pixel's footprint, not a few ULPs: offset by
/// ULPs alone, rays from a terrain's concave creases start under the next
/// triangle and shadow themselves (speckles of false shadow). The
/// reference's default lift (`offset_footprint`) only removes shadow, and
/// brings it to the exact shadow volumes (rasterized like the G-buffer)
/// at least twice as close; the irregular z-buffer starts its rays where
/// the reference does.
#[test]
fn rays_from_a_terrain_do_not_shadow_themselves() {
    let (scene, camera) = terrain_from_afar();
    let (w, h) = (320, 180);
    let mask = |id| render_reference(&scene, &camera, id, w, h).0;
    let lifted = mask("raytraced");
    let unlifted = mask("raytraced[offset_footprint=0]");
    let volumes = mask("shadow-volume:auto");
    let irregular = mask("irregular");
    let differ = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .filter(|(x, y)| (*x - *y).abs() > 0.5)
            .count()
    };
    let speckles = unlifted
        .iter()
        .zip(&lifted)
        .filter(|(u, l)| **u < 0.5 && **l > 0.5)
        .count();
    assert!(
        speckles >= 20 && speckles == differ(&unlifted, &lifted),
        "without the lift {speckles} pixels shadow themselves, {} differ",
        differ(&unlifted, &lifted)
    );
    let (near, far) = (differ(&volumes, &lifted), differ(&volumes, &unlifted));
    assert!(
        2 * near <= far,
        "volumes against the reference: {near} pixels lifted, {far} not"
    );
    assert_eq!(differ(&irregular, &lifted), 0);
    assert!(
        lifted.iter().filter(|&&v| v < 0.5).count() > 200,
        "the terrain shadows itself"
    );
}
