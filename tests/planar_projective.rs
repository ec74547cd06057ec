//! Planar projected shadows and projective shadow textures against the
//! ray-traced reference and their documented limits.

mod common;
use common::*;
use glam::Vec3;
use shadowlab::scene::{Light, builtin};

fn distinct(mask: &[f32]) -> Vec<f32> {
    let mut v: Vec<f32> = mask.iter().map(|x| (x * 1000.0).round() / 1000.0).collect();
    v.sort_by(|a, b| a.total_cmp(b));
    v.dedup();
    v
}

#[test]
fn stencil_darkens_each_pixel_once_and_no_stencil_twice() {
    // Two overlapping squares at different heights under a point light.
    let scene = squares_over_floor(
        &[
            (Vec3::new(-0.3, 1.0, 0.0), 0.6),
            (Vec3::new(0.3, 1.5, 0.2), 0.6),
        ],
        Light::point(Vec3::new(0.0, 5.0, 0.0), 1.0),
        true,
    );
    let with = mask_of(&scene, "planar", &["darkening=0.5"], 160, 160);
    assert_eq!(
        distinct(&with),
        vec![0.5, 1.0],
        "stencil: each pixel darkened once"
    );
    let without = mask_of(
        &scene,
        "planar",
        &["darkening=0.5", "stencil=false"],
        160,
        160,
    );
    let values = distinct(&without);
    assert!(
        values.contains(&0.25),
        "no stencil: overlaps darken twice: {values:?}"
    );
}

#[test]
fn anti_shadows_and_false_shadows_are_not_drawn() {
    // A square above the light (anti-shadow) and one below the floor (false shadow).
    let light = Light::point(Vec3::new(0.0, 2.0, 0.0), 1.0);
    for square in [
        (Vec3::new(0.5, 3.0, 0.0), 0.5),
        (Vec3::new(0.5, -1.0, 0.0), 0.5),
    ] {
        let scene = squares_over_floor(&[square], light, true);
        let mask = mask_of(&scene, "planar", &[], 120, 120);
        assert!(
            mask.iter().all(|&v| v == 1.0),
            "square at {:?} cast a shadow",
            square.0
        );
    }
    // Control: the same square between light and floor does cast one.
    let scene = squares_over_floor(&[(Vec3::new(0.5, 1.0, 0.0), 0.5)], light, true);
    assert!(mask_of(&scene, "planar", &[], 120, 120).contains(&0.0));
}

#[test]
fn planar_matches_ray_tracing_on_the_plane_for_every_light_type() {
    for light in lights_over_squares() {
        // No ShadowPlane object: the floor is found as the largest planar receiver.
        let scene = squares_over_floor(
            &[
                (Vec3::new(0.0, 1.0, 0.0), 0.7),
                (Vec3::new(0.8, 2.0, 0.5), 0.4),
            ],
            light,
            false,
        );
        let row = compare(&scene, "planar", (200, 200));
        let m = &row.on_planes;
        assert!(
            m.considered_pixels > 30000 && m.reference_shadowed_pct > 3.0,
            "{m:?}"
        );
        assert_eq!(m.interior.total_pct, 0.0, "{:?}: {m:?}", light.kind);
        assert!(m.edge.total_pct <= 0.05, "{:?}: {m:?}", light.kind);
    }
}

#[test]
fn projective_matches_on_receivers_and_alpha_depth_self_shadows() {
    let scene = squares_over_floor(
        &[(Vec3::new(0.0, 1.0, 0.0), 0.7)],
        Light::point(Vec3::new(0.4, 5.0, -0.3), 1.0),
        false,
    );
    let row = compare(&scene, "projective[size=1024]", (200, 200));
    assert!(
        row.mask.interior.total_pct < 0.01 && row.mask.edge.total_pct < 0.2,
        "{:?}",
        row.mask
    );

    // On a curved caster, 8-bit depth-in-alpha shadows the caster's own lit side.
    let s = builtin::by_name("floating").unwrap().unwrap();
    let plain = compare(&s, "projective", (320, 180));
    let alpha = compare(&s, "projective:alpha-depth", (320, 180));
    assert!(
        plain.off_planes.all.false_shadow_pct < 0.01,
        "{:?}",
        plain.off_planes
    );
    assert!(
        alpha.off_planes.all.false_shadow_pct > 0.5,
        "{:?}",
        alpha.off_planes
    );
}

/// The presets that darken instead of removing the light mark exactly the
/// reference's shadow at 1 − darkening (½), and `planar:no-stencil` (0.6)
/// at 0.4 where no shadows overlap: each against the ray-traced mask, pixel
/// by pixel, all but a rim of edge pixels.
#[test]
fn darken_and_no_stencil_presets_follow_the_reference() {
    let scene = squares_over_floor(
        &[(Vec3::new(0.2, 1.0, -0.1), 0.8)],
        Light::point(Vec3::new(0.4, 5.0, -0.3), 1.0),
        true,
    );
    let (w, h) = (160, 160);
    let reference = mask_of(&scene, "raytraced", &[], w, h);
    let shadowed = reference.iter().filter(|&&v| v < 0.5).count();
    assert!(shadowed > 1000, "{shadowed} shadowed pixels");
    for (technique, inside) in [
        ("planar:darken", 0.5),
        ("shadow-volume:darken", 0.5),
        ("planar:no-stencil", 0.4),
    ] {
        let mask = mask_of(&scene, technique, &[], w, h);
        let off = reference
            .iter()
            .zip(&mask)
            .filter(|(r, m)| {
                let expected = if **r < 0.5 { inside } else { 1.0 };
                (**m - expected).abs() > 0.01
            })
            .count();
        // The shadow's rim: about its perimeter in pixels, a few percent.
        assert!(
            off * 25 <= shadowed,
            "{technique}: {off} pixels off of {shadowed} shadowed"
        );
    }
}
