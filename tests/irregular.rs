//! The irregular z-buffer: masks against the ray-traced reference under
//! every light type, cut-outs, the casters culled, the samples binned,
//! large triangles in jobs, crowded cells, and a grid past the device's
//! limits.

mod common;
use common::*;
use glam::Vec3;
use shadowlab::technique::raytraced::{OFFSET_ULPS as ULPS, offset_ray_origin};

/// Under point, spot and directional lights, on open and closed meshes and
/// curved receivers, the mask is the reference's: no resolution error.
#[test]
fn masks_match_the_reference_under_every_light_type() {
    for (scene, camera, light) in [
        ("room", "default", "point"),
        ("room", "default", "spot"),
        ("room", "default", "sun"),
        ("bunny", "default", "spot"),
        ("curved", "default", "point"),
        ("columns", "default", "sun"),
        ("teapot", "default", "sun"),
    ] {
        let s = preset(scene, camera, light);
        let row = compare(&s, "irregular", (192, 108));
        let m = &row.mask;
        assert!(m.reference_shadowed_pct > 1.0, "{scene}/{light}: {m:?}");
        assert!(
            m.all.total_pct <= 0.02 && m.interior_mae <= 0.002,
            "{scene}/{camera}/{light}: {m:?}"
        );
        // The one map on the same frame has resolution error to lose.
        let pcf = compare(&s, "shadow-map:pcf[size=512]", (192, 108));
        assert!(
            pcf.mask.all.total_pct > m.all.total_pct,
            "{scene}/{light}: pcf {:?} against {m:?}",
            pcf.mask
        );
    }
}

/// On the landscape from the ground, the casters behind the camera, beside
/// its view or away from the light cannot shadow what it sees and are not
/// dispatched (most of the terrain); the mask is still the reference's.
#[test]
fn casters_that_cannot_shadow_the_view_are_not_dispatched() {
    for light in ["point", "sun"] {
        let s = preset("landscape", "ground", light);
        let all = s.caster_triangle_count() as f64;
        let hf = rendered_frame(&s, "irregular", &[], 192, 108);
        let kept = counter(&hf, "caster_triangles_kept");
        assert!(kept > 0.0 && kept < 0.5 * all, "{light}: {kept} of {all}");
        let m = compare(&s, "irregular", (192, 108)).mask;
        assert!(m.reference_shadowed_pct > 1.0, "{light}: {m:?}");
        assert!(m.all.total_pct <= 0.02, "{light}: {m:?}");
    }
}

/// Under a point light a frame's samples crowd onto a few of the six cube
/// faces (the bunny's mostly onto the floor's): with the grid left
/// automatic each face's cells follow its samples (about one each, none
/// for an empty face), so the cells number about the samples, not six
/// faces' worth, and the lists are no longer than under one side for every
/// face (`grid`, a side giving a cell per pixel were the samples spread
/// evenly, raised to the least, 64) with more than twice the cells; the
/// mask is the same.
#[test]
fn a_point_lights_cells_follow_its_samples() {
    let (w, h) = (192, 108);
    let s = preset("bunny", "default", "point");
    let counters = |params: &[&str]| {
        let mut hf = rendered_frame(&s, "irregular", params, w, h);
        render_again(&mut hf, &s);
        render_again(&mut hf, &s);
        let c = |name| counter(&hf, name);
        (c("samples_binned"), c("grid_cells"), c("list_length_p99"))
    };
    let (samples, cells, p99) = counters(&[]);
    assert!(samples > (w * h / 4) as f64, "{samples} samples");
    assert!(
        cells >= samples && cells <= samples + 2.0 * (6.0 * samples).sqrt() + 6.0,
        "{cells} cells for {samples} samples"
    );
    let side = ((w * h) as f64 / 6.0).sqrt().ceil() as u32;
    let even = format!("grid={}", side.max(64));
    let (_, even_cells, even_p99) = counters(&[even.as_str()]);
    assert!(even_cells > 2.0 * cells, "{even_cells} against {cells}");
    assert!(p99 <= even_p99, "fitted p99 {p99}, one side {even_p99}");
    let fitted = mask_of(&s, "irregular", &[], w, h);
    let one_side = mask_of(&s, "irregular", &[even.as_str()], w, h);
    assert_eq!(fitted, one_side);
}

/// An opaque solid's faces turned away from the light are not tested:
/// the mask is the one every face gives (the same solids as cut-outs with
/// no hole, which are never skipped), with fewer tests.
#[test]
fn a_solids_faces_away_from_the_light_are_skipped() {
    for light in ["sun", "point"] {
        let solids = preset("columns", "default", light);
        let mut holeless = solids.clone();
        for m in &mut holeless.materials {
            m.alpha_mode = shadowlab::scene::AlphaMode::Mask;
        }
        let tests = |s: &shadowlab::scene::Scene| {
            let mut hf = rendered_frame(s, "irregular", &[], 160, 90);
            render_again(&mut hf, s);
            render_again(&mut hf, s);
            counter(&hf, "sample_tests")
        };
        let (skipping, all) = (tests(&solids), tests(&holeless));
        assert!(
            skipping > 0.0 && skipping < 0.95 * all,
            "{light}: {skipping} of {all}"
        );
        let a = mask_of(&solids, "irregular", &[], 160, 90);
        let b = mask_of(&holeless, "irregular", &[], 160, 90);
        assert!(a.iter().any(|&v| v < 0.5), "{light}");
        assert_eq!(pixels_differing(&a, &b), 0, "{light}");
    }
}

/// Leaf cards and the fence are alpha-tested: light falls through their
/// holes as in the reference (drawn solid they cover several per cent).
#[test]
fn cut_out_casters_let_light_through_their_holes() {
    for light in ["sun", "point"] {
        let s = preset("foliage", "eye-level", light);
        let m = compare(&s, "irregular", (192, 108)).mask;
        assert!(m.all.total_pct <= 0.05, "{light}: {m:?}");
    }
}

/// The glass pane is translucent: `blended_casters=transmit` lets each
/// sample keep the light its crossings pass, as the reference does, where
/// `cutout` (the default) lights what lies in its shadow.
#[test]
fn translucent_casters_transmit_as_in_the_reference() {
    for light in ["sun", "point"] {
        let s = preset("foliage", "eye-level", light);
        let cutout = compare(&s, "irregular", (192, 108)).mask;
        let transmit = compare(&s, "irregular[blended_casters=transmit]", (192, 108)).mask;
        let (c, t) = (
            cutout
                .fractional_mae
                .expect("the pane's shadow is fractional"),
            transmit
                .fractional_mae
                .expect("the pane's shadow is fractional"),
        );
        assert!(c > 0.1 && t < 0.005, "{light}: cutout {c}, transmit {t}");
        assert!(
            transmit.all.total_pct <= 0.05 && transmit.mean_abs_error < 0.001,
            "{light}: {transmit:?}"
        );
    }
}

/// Every pixel that shows a surface the light reaches (facing it, inside a
/// spot's cone) is binned once, and the lists are short; elsewhere it is
/// not binned and it is shadowed, as in the reference, on every pixel.
#[test]
fn every_seen_sample_the_light_reaches_is_binned() {
    let (w, h) = (160, 90);
    for (scene, camera, light) in [("curved", "default", "sun"), ("room", "default", "spot")] {
        let s = preset(scene, camera, light);
        let mut hf = rendered_frame(&s, "irregular", &[], w, h);
        render_again(&mut hf, &s);
        render_again(&mut hf, &s);
        let raw = gpu()
            .read_texture(hf.frame.gbuffer_position(), 0, 16)
            .unwrap();
        let positions: &[[f32; 4]] = bytemuck::cast_slice(&raw);
        let raw = gpu().read_texture(hf.frame.gbuffer_normal(), 0, 8).unwrap();
        let normals: &[[half::f16; 4]] = bytemuck::cast_slice(&raw);
        let ulps = ULPS.default as f32;
        let reached: Vec<Option<bool>> = positions
            .iter()
            .zip(normals)
            .map(|(p, n)| {
                let n = Vec3::new(n[0].to_f32(), n[1].to_f32(), n[2].to_f32()).normalize();
                let o = offset_ray_origin(Vec3::new(p[0], p[1], p[2]), n, ulps);
                (p[3] >= 0.5).then(|| s.lights[0].reaches(o, n))
            })
            .collect();
        let seen = reached.iter().flatten().count();
        let binned = reached.iter().flatten().filter(|&&r| r).count();
        assert!(
            binned > w as usize * h as usize / 10,
            "{scene}/{light}: {binned} reached"
        );
        assert!(
            seen - binned > 100,
            "{scene}/{light}: {seen} seen, {binned} reached"
        );
        assert_eq!(
            counter(&hf, "samples_binned") as usize,
            binned,
            "{scene}/{light}"
        );
        assert!(counter(&hf, "list_length_p50") >= 1.0);
        assert!(counter(&hf, "list_length_p99") <= 8.0);
        let irregular = mask_of(&s, "irregular", &[], w, h);
        let reference = mask_of(&s, "raytraced", &[], w, h);
        assert_eq!(
            pixels_differing(&irregular, &reference),
            0,
            "{scene}/{light}"
        );
        let unreached = irregular
            .iter()
            .zip(&reached)
            .filter(|(_, r)| **r == Some(false));
        assert!(
            unreached.map(|(&v, _)| v).all(|v| v == 0.0),
            "{scene}/{light}"
        );
    }
}

/// A triangle's samples are tested the same whether its own thread tests
/// them or workgroups share them in jobs; no job overflows. On `foliage`
/// the opaque casters' jobs fill the list from its start and the
/// see-through casters' (leaves, fence, glass) from its end.
#[test]
fn large_triangles_in_jobs_give_the_same_mask() {
    for (scene, camera, light, extra) in [
        ("room", "default", "point", None),
        (
            "foliage",
            "eye-level",
            "sun",
            Some("blended_casters=transmit"),
        ),
    ] {
        let s = preset(scene, camera, light);
        let params = |large| -> Vec<&str> { [Some(large), extra].into_iter().flatten().collect() };
        let direct = mask_of(&s, "irregular", &params("large_samples=16384"), 160, 90);
        let jobs = mask_of(&s, "irregular", &params("large_samples=1"), 160, 90);
        assert!(direct.iter().any(|&v| v < 0.5), "{scene}");
        assert_eq!(pixels_differing(&direct, &jobs), 0, "{scene}");
        let mut hf = rendered_frame(&s, "irregular", &params("large_samples=1"), 160, 90);
        render_again(&mut hf, &s);
        render_again(&mut hf, &s);
        assert!(counter(&hf, "large_triangle_jobs") > 0.0, "{scene}");
        assert_eq!(counter(&hf, "job_overflow_samples"), 0.0, "{scene}");
    }
}

/// Where a coarse grid crowds thousands of a ground camera's samples into
/// one cell, every one is still tested (jobs of 1024 samples, not one
/// thread looping past the driver's loop budget): the mask is the
/// reference's.
#[test]
fn crowded_cells_are_tested_in_full() {
    let s = preset("landscape", "ground", "sun-side");
    for params in [&["grid=64"][..], &["grid=64", "large_samples=1"][..]] {
        let mut hf = rendered_frame(&s, "irregular", params, 192, 108);
        render_again(&mut hf, &s);
        assert!(counter(&hf, "list_length_max") > 2048.0, "{params:?}");
        assert!(counter(&hf, "large_triangle_jobs") > 0.0, "{params:?}");
        let spec = format!("irregular[{}]", params.join(","));
        let m = compare(&s, &spec, (192, 108)).mask;
        assert!(m.reference_shadowed_pct > 1.0, "{params:?}: {m:?}");
        assert!(
            m.all.total_pct <= 0.02 && m.interior_mae <= 0.002,
            "{params:?}: {m:?}"
        );
    }
}

/// A grid whose lists exceed the device's largest storage buffer is a
/// clear error and exit code 2, not a wrong mask.
#[test]
fn a_grid_past_the_device_limit_is_an_error() {
    let out = tmpdir("irregular-limit");
    let o = shadowlab(&[
        "render",
        "--scene",
        "room",
        "--light",
        "point",
        "--technique",
        "irregular[grid=4096]",
        "--size",
        "64x36",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("largest storage buffer"),
        "{}",
        stderr(&o)
    );
}

/// Sub-pixel samples converge to the covered fraction: under a sun straight
/// down, a square turned about the vertical casts a shadow whose edges cross
/// pixels at an angle; each edge pixel's visibility approaches the share of
/// its floor footprint outside the shadow (integrated on 32 × 32 points),
/// while one sample per pixel is 0 or 1 there; the reference with as many
/// samples agrees.
#[test]
fn sub_pixel_samples_converge_to_the_covered_fraction() {
    use glam::{Mat4, Vec2};
    use shadowlab::scene::{Camera, Light, shapes};
    let turn = 0.4f32;
    let (mut s, grey) = grey_floor_scene("turned square", 20.0, 4);
    let quad = s.add_mesh(shapes::plane(2.0, 2.0, 1));
    s.add_object(
        "Square",
        quad,
        grey,
        Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0))
            * Mat4::from_rotation_y(turn)
            * Mat4::from_rotation_x(std::f32::consts::PI),
    );
    s.lights = vec![Light::directional(Vec3::NEG_Y, 1.0)];
    s.camera = Camera {
        up: Vec3::NEG_Z,
        ..Camera::new(Vec3::new(0.3, 5.0, 0.2), Vec3::new(0.3, 0.0, 0.2))
    };
    s.finalize().unwrap();
    let (w, h) = (96u32, 96u32);
    let view_proj = s.camera.projection(1.0) * s.camera.view();
    let inv = view_proj.inverse();
    let lit_at = |fx: f32, fy: f32| {
        let ndc = Vec2::new(fx / w as f32 * 2.0 - 1.0, 1.0 - fy / h as f32 * 2.0);
        let a = inv.project_point3(ndc.extend(1.0));
        let b = inv.project_point3(ndc.extend(0.5));
        let p = a + (b - a) * (a.y / (a.y - b.y));
        let q = Mat4::from_rotation_y(-turn).transform_point3(p);
        q.x.abs() > 1.0 || q.z.abs() > 1.0
    };
    const SUB: u32 = 32;
    let covered: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let lit = (0..SUB * SUB)
                .filter(|k| {
                    let (u, v) = ((k % SUB) as f32 + 0.5, (k / SUB) as f32 + 0.5);
                    lit_at(x + u / SUB as f32, y + v / SUB as f32)
                })
                .count();
            lit as f32 / (SUB * SUB) as f32
        })
        .collect();
    let edge: Vec<usize> = (0..covered.len())
        .filter(|&i| covered[i] > 0.02 && covered[i] < 0.98)
        .collect();
    assert!(edge.len() > 100, "{} edge pixels", edge.len());
    let error = |technique: &str, n: u32| {
        let set = format!("pixel_samples={n}");
        let mask = mask_of(&s, technique, &[&set], w, h);
        let interior = (0..mask.len())
            .filter(|&i| covered[i] == 0.0 || covered[i] == 1.0)
            .filter(|&i| (mask[i] - covered[i]).abs() > 0.01)
            .count();
        assert_eq!(interior, 0, "{n} samples: interior pixels wrong");
        edge.iter()
            .map(|&i| (mask[i] - covered[i]).abs())
            .sum::<f32>()
            / edge.len() as f32
    };
    let errors: Vec<f32> = [1, 4, 16, 32]
        .into_iter()
        .map(|n| error("irregular", n))
        .collect();
    eprintln!(
        "edge pixels {}, MAE for 1, 4, 16, 32 samples: {errors:?}",
        edge.len()
    );
    assert!(errors[0] > 0.15, "{errors:?}");
    assert!(errors[1] < errors[0] && errors[2] < errors[1], "{errors:?}");
    assert!(errors[2] < 0.06 && errors[3] < 0.04, "{errors:?}");
    // The supersampled reference samples the same points.
    let reference = error("raytraced", 32);
    assert!(
        (reference - errors[3]).abs() < 0.005,
        "{reference} {errors:?}"
    );
}

/// Sub-pixel samples on a curved, faceted receiver do not shadow their own
/// surface: samples on a triangle's plane past a concave edge would lie
/// under the next triangle (a wireframe of false shadow, mean error 0.08
/// before samples were lifted off the plane). Averaged over the frame, the
/// sub-pixel masks stay within a pixel-edge's worth of the centre samples.
#[test]
fn sub_pixel_samples_do_not_shadow_their_own_surface() {
    let s = preset("curved", "default", "sun");
    let (w, h) = (160, 90);
    let centre = mask_of(&s, "raytraced", &[], w, h);
    for (technique, set) in [
        ("raytraced", "pixel_samples=32"),
        ("irregular", "pixel_samples=16"),
    ] {
        let mask = mask_of(&s, technique, &[set], w, h);
        let mean = mask
            .iter()
            .zip(&centre)
            .map(|(a, b)| (a - b).abs())
            .sum::<f32>()
            / mask.len() as f32;
        assert!(mean < 0.01, "{technique}[{set}]: {mean}");
    }
}
