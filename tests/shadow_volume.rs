//! Stencil shadow volumes: CPU and GPU extrusion agree, masks match the
//! ray-traced reference, z-pass shows its known failure.

mod common;
use common::*;
use glam::{Mat4, Vec3};
use shadowlab::scene::{Camera, Light, LightType, Material, Scene, shapes};
use shadowlab::technique::ParamValues;
use shadowlab::technique::shadow_volume::config::VolumeConfig;
use shadowlab::technique::shadow_volume::silhouette::{CasterPlan, VolumeKind};
use shadowlab::technique::shadow_volume::{self, ShadowVolumeRenderer};

/// Triangles of an index list, each rotated to start at its smallest
/// index (orientation kept), sorted.
fn canonical(list: &[u32]) -> Vec<[u32; 3]> {
    let mut t: Vec<[u32; 3]> = list
        .chunks_exact(3)
        .map(|t| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap();
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect();
    t.sort_unstable();
    t
}

#[test]
fn cpu_and_gpu_extrusion_give_the_same_volumes() {
    let gpu = gpu();
    for (name, light) in [
        ("room", "point"),
        ("room", "sun"),
        ("floating", "spot"),
        ("bunny", "sun"),
        ("teapot", "point"),
    ] {
        let scene = preset(name, "default", light);
        let l = scene.lights[0];
        let config =
            VolumeConfig::parse(&ParamValues::defaults(shadow_volume::FAMILY.params)).unwrap();
        let mut r = ShadowVolumeRenderer::new(gpu, config);
        let casters = r.volume_mesh(gpu, &scene).casters.clone();
        for (kind, zfail) in [
            (VolumeKind::Silhouette, false),
            (VolumeKind::Silhouette, true),
            (VolumeKind::Triangles, true),
        ] {
            let plans: Vec<CasterPlan> = casters
                .iter()
                .map(|c| CasterPlan {
                    kind,
                    zfail,
                    light: c.model.inverse() * l.homogeneous(),
                    capped: true,
                })
                .collect();
            let dark_cap = l.kind != LightType::Directional;
            let (cpu, cpu_edges) = r
                .volumes_read_back(gpu, &scene, &plans, dark_cap, false)
                .unwrap();
            let (on_gpu, gpu_edges) = r
                .volumes_read_back(gpu, &scene, &plans, dark_cap, true)
                .unwrap();
            let what = format!("{name}/{light} {kind:?} zfail={zfail}");
            assert_eq!(cpu_edges, gpu_edges, "{what}: silhouette edges");
            if kind == VolumeKind::Silhouette {
                assert!(cpu_edges > 0, "{what}");
            }
            let list = zfail as usize;
            assert!(!cpu[list].is_empty() && cpu[1 - list].is_empty(), "{what}");
            assert_eq!(
                canonical(&cpu[list]),
                canonical(&on_gpu[list]),
                "{what}: triangles"
            );
        }
    }
}

#[test]
fn every_preset_and_variant_matches_the_reference_on_squares_over_a_plane() {
    for light in lights_over_squares() {
        let scene = squares_over_floor(
            &[
                (Vec3::new(0.0, 1.0, 0.0), 0.7),
                (Vec3::new(1.2, 2.0, 0.5), 0.5),
            ],
            light,
            false,
        );
        for id in [
            "shadow-volume:auto",
            "shadow-volume:zpass",
            "shadow-volume:zfail",
            "shadow-volume:triangles",
            "shadow-volume:cpu",
            "shadow-volume:zfail[stencil=two-pass]",
            "shadow-volume:zpass[stencil=two-pass]",
            "shadow-volume:zfail[far_plane=depth-clamp]",
            "shadow-volume:zfail[length=40]",
            "shadow-volume:auto[scissor=false,cull_casters=false]",
        ] {
            let row = compare(&scene, id, (200, 200));
            let m = &row.mask;
            assert!(m.reference_shadowed_pct > 2.0, "{id}");
            assert!(m.all.total_pct <= 0.05, "{id} {:?}: {m:?}", light.kind);
        }
    }
}

/// Volumes compared against receivers 400–800 m away, with the camera's
/// near plane at 0.1 m: the depth test needs the reversed float depth
/// buffer (a 24-bit buffer with the near plane at depth 0 misplaced 2.3 %
/// of this frame, interior MAE 0.0043).
#[test]
fn volumes_keep_their_depth_test_on_distant_receivers() {
    let mut scene = preset("landscape", "ground", "point");
    scene.camera.eye = Vec3::new(-333.087, 262.626, 359.411);
    scene.camera.target = Vec3::new(21.768, -35.162, -180.152);
    assert!(scene.camera.near <= 0.1);
    for id in ["shadow-volume:zfail", "shadow-volume:zpass"] {
        let m = compare(&scene, id, (320, 180)).mask;
        assert!(m.reference_shadowed_pct > 5.0, "{id}: {m:?}");
        assert!(
            m.all.total_pct <= 0.6 && m.interior_mae <= 0.0015,
            "{id}: {m:?}"
        );
    }
}

#[test]
fn zpass_fails_with_the_camera_in_a_shadow_and_zfail_does_not() {
    for light in ["sun", "point"] {
        let scene = preset("columns", "in-shadow", light);
        let zpass = compare(&scene, "shadow-volume:zpass", (320, 180));
        assert!(
            zpass.mask.all.total_pct > 10.0,
            "{light}: z-pass should fail here: {:?}",
            zpass.mask
        );
        for id in ["shadow-volume:zfail", "shadow-volume:auto"] {
            let row = compare(&scene, id, (320, 180));
            assert!(row.mask.reference_shadowed_pct > 10.0);
            assert!(
                row.mask.all.total_pct <= 0.05,
                "{light} {id}: {:?}",
                row.mask
            );
        }
        // From outside every volume z-pass is exact too.
        let outside = preset("columns", "default", light);
        let row = compare(&outside, "shadow-volume:zpass", (320, 180));
        assert!(row.mask.all.total_pct <= 0.05, "{light}: {:?}", row.mask);
    }
}

#[test]
fn a_point_light_inside_the_room() {
    let scene = preset("room", "default", "point");
    for id in ["shadow-volume:auto", "shadow-volume:zfail"] {
        let row = compare(&scene, id, (320, 180));
        assert!(row.mask.reference_shadowed_pct > 1.0);
        assert!(row.mask.all.total_pct <= 0.05, "{id}: {:?}", row.mask);
    }
}

#[test]
fn open_meshes_need_per_triangle_volumes() {
    let scene = preset("teapot", "default", "point");
    let triangles = compare(&scene, "shadow-volume:triangles", (320, 180));
    assert!(triangles.mask.all.total_pct <= 0.05, "{:?}", triangles.mask);
    // Silhouette volumes of the open teapot miss the shadow seen through its opening.
    let edges = compare(&scene, "shadow-volume:edges", (320, 180));
    assert!(edges.mask.all.false_lit_pct > 0.2, "{:?}", edges.mask);
}

#[test]
fn statistics_and_debug_views() {
    let scene = preset("floating", "default", "point");
    let gpu = gpu();
    let mut counters = vec![];
    for id in ["shadow-volume:zfail", "shadow-volume:zfail[extrusion=cpu]"] {
        let mut hf = frame_with_debug_views(&scene, id, 160, 90);
        // The GPU extrusion's counters arrive by a readback that is not
        // waited for (the viewer must not stall): on a loaded machine,
        // after a later frame.
        for _ in 0..100 {
            let arrived = hf.techniques[0]
                .technique
                .counters()
                .iter()
                .any(|(k, v)| *k == "silhouette_edges" && *v > 0.0);
            if arrived {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
            render_again(&mut hf, &scene);
        }
        let t = &hf.techniques[0].technique;
        let c: std::collections::HashMap<&str, f64> = t.counters().into_iter().collect();
        assert!(c["silhouette_edges"] > 10.0, "{c:?}");
        assert!(c["volume_triangles"] > c["silhouette_edges"], "{c:?}");
        // A GPU that skips the empty fragment stage reports no count
        // (NVIDIA's driver: 0 was left out); a CPU rasteriser counts them.
        if gpu.pipeline_statistics && gpu.is_cpu_adapter() {
            assert!(c["volume_fragments"] > 0.0, "{c:?}");
        } else {
            eprintln!(
                "skipped: {} counts no volume fragments (no pipeline statistics, or a GPU that may skip the empty stage)",
                gpu.adapter_summary()
            );
        }
        assert!(c.get("volume_fragments").is_none_or(|&f| f > 0.0), "{c:?}");
        let views = t.debug_views(gpu).unwrap();
        // One line per silhouette edge (the open floor has per-triangle volumes).
        assert_eq!(views.lines.len() as f64, c["silhouette_edges"]);
        let image = &views.images[0];
        assert_eq!((image.width, image.height), (160, 90));
        let red = image
            .rgba
            .chunks_exact(4)
            .filter(|p| p[0] as i32 > p[1] as i32 + 20)
            .count();
        assert!(red > 100, "{red} reddish pixels");
        counters.push((c["silhouette_edges"], c["volume_triangles"]));
    }
    assert_eq!(counters[0], counters[1], "GPU and CPU statistics");
}

/// A box and, above it, a mirrored box (scale x = −1.2): their shadows
/// overlap on the floor. Mirroring turns the mesh's triangles clockwise; if
/// its volume were extruded from them as they are, its stencil counts would
/// run the other way and cancel the lower box's (+1 − 1 = 0: false lit).
#[test]
fn mirrored_casters_count_the_same_way_as_the_others() {
    let (mut s, grey) = grey_floor_scene("mirror", 20.0, 4);
    let cube = s.add_mesh(shapes::cuboid(Vec3::ONE));
    s.add_object(
        "Box",
        cube,
        grey,
        Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)),
    );
    s.add_object(
        "Mirrored",
        cube,
        grey,
        Mat4::from_translation(Vec3::new(0.3, 2.5, 0.2))
            * Mat4::from_scale(Vec3::new(-1.2, 1.0, 1.0)),
    );
    s.lights = vec![Light::directional(Vec3::new(0.2, -1.0, 0.1), 1.0)];
    s.camera = Camera::new(Vec3::new(0.5, 5.0, 3.5), Vec3::new(0.5, 0.0, 0.0));
    s.finalize().unwrap();
    assert!(s.objects[2].winding_reversed && !s.objects[1].winding_reversed);
    // Finalising again keeps the reversal (idempotent).
    s.finalize().unwrap();
    assert!(s.objects[2].winding_reversed);
    assert_ne!(s.objects[2].mesh, s.objects[1].mesh);
    for id in [
        "shadow-volume:zpass",
        "shadow-volume:zfail",
        "shadow-volume:edges",
        "shadow-volume:cpu",
    ] {
        let row = compare(&s, id, (200, 150));
        let m = &row.mask;
        assert!(m.reference_shadowed_pct > 2.0, "{id}: {m:?}");
        assert!(m.all.total_pct <= 0.05, "{id}: {m:?}");
    }
}

/// A zero scale has no inverse: its normals and volumes are undefined, so
/// the scene is refused with an error naming the object.
#[test]
fn singular_transforms_are_refused() {
    let mut s = Scene::new("flat");
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let cube = s.add_mesh(shapes::cuboid(Vec3::ONE));
    s.add_object(
        "Squashed",
        cube,
        grey,
        Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)),
    );
    s.lights = vec![Light::point(Vec3::new(0.0, 3.0, 0.0), 1.0)];
    let e = s.finalize().unwrap_err().to_string();
    assert!(
        e.contains("object 'Squashed' has a singular transform"),
        "{e}"
    );
}

/// The documents' z-fail failure cases, reproducible: volumes left open
/// (`caps=false`) and volumes cut by a finite far plane (`far_plane=clip`,
/// which loses a point light's dark cap at infinity) miss shadows that
/// capped z-fail with the far plane at infinity gets right.
#[test]
fn zfail_fails_without_caps_and_with_a_clipping_far_plane() {
    let scene = preset("columns", "default", "point");
    let exact = compare(&scene, "shadow-volume:zfail", (320, 180)).mask;
    assert!(exact.reference_shadowed_pct > 10.0, "{exact:?}");
    assert!(exact.all.total_pct <= 0.05, "{exact:?}");
    for id in ["shadow-volume:zfail-open", "shadow-volume:zfail-far-clip"] {
        let m = compare(&scene, id, (320, 180)).mask;
        assert!(m.all.total_pct > 10.0, "{id} should fail here: {m:?}");
    }
}

/// `far_plane=depth-clamp` draws the volumes with unclipped depth wherever
/// the adapter has depth clamping (lavapipe does), and says when it fell
/// back to the far plane at infinity; the default never clamps.
#[test]
fn depth_clamp_is_used_where_the_adapter_has_it() {
    let gpu = gpu();
    let scene = preset("columns", "default", "point");
    let clamped = |id: &str| {
        let mut hf = frame_with_debug_views(&scene, id, 64, 36);
        render_again(&mut hf, &scene);
        let c: std::collections::HashMap<&str, f64> =
            hf.techniques[0].technique.counters().into_iter().collect();
        c["depth_clamped"]
    };
    assert_eq!(clamped("shadow-volume:zfail"), 0.0);
    if gpu.depth_clamp {
        assert_eq!(clamped("shadow-volume:zfail[far_plane=depth-clamp]"), 1.0);
    } else {
        assert_eq!(clamped("shadow-volume:zfail[far_plane=depth-clamp]"), 0.0);
        eprintln!(
            "skipped: {} has no depth clamp; the fallback to the far plane at infinity was checked",
            gpu.adapter_summary()
        );
    }
}
