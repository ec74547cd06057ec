//! The irregular z-buffer: masks against the ray-traced reference under
//! every light type, cut-outs, the samples binned, large triangles in
//! chunks, and a grid past the device's limits.

mod common;
use common::*;

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

/// Every pixel that shows a surface is binned once, and the lists are short.
#[test]
fn every_seen_sample_is_binned() {
    let s = preset("room", "default", "sun");
    let mut hf = rendered_frame(&s, "irregular", &[], 160, 90);
    render_again(&mut hf, &s);
    render_again(&mut hf, &s);
    let raw = gpu()
        .read_texture(hf.frame.gbuffer_position(), 0, 16)
        .unwrap();
    let positions: &[[f32; 4]] = bytemuck::cast_slice(&raw);
    let seen = positions.iter().filter(|p| p[3] >= 0.5).count();
    assert!(seen > 160 * 90 / 2);
    assert_eq!(counter(&hf, "samples_binned") as usize, seen);
    assert!(counter(&hf, "list_length_p50") >= 1.0);
    assert!(counter(&hf, "list_length_p99") <= 8.0);
}

/// A triangle's samples are tested the same whether its own thread tests
/// them or workgroups share them in jobs; no job overflows.
#[test]
fn large_triangles_in_jobs_give_the_same_mask() {
    let s = preset("room", "default", "point");
    let direct = mask_of(&s, "irregular", &["large_samples=16384"], 160, 90);
    let jobs = mask_of(&s, "irregular", &["large_samples=1"], 160, 90);
    assert!(direct.iter().any(|&v| v < 0.5));
    assert_eq!(pixels_differing(&direct, &jobs), 0);
    let mut hf = rendered_frame(&s, "irregular", &["large_samples=1"], 160, 90);
    render_again(&mut hf, &s);
    render_again(&mut hf, &s);
    assert!(counter(&hf, "large_triangle_jobs") > 0.0);
    assert_eq!(counter(&hf, "job_overflow_samples"), 0.0);
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
