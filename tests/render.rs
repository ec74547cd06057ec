//! Every built-in scene renders a non-trivial image; golden images of a few
//! scenes stay within a tolerance; frame.json records what the GPU used.

mod common;
use common::*;
use shadowlab::renderer::RenderSettings;
use shadowlab::scene::builtin;

/// Number of distinct colours (quantised to 4 bits per channel).
fn distinct_colours(rgba: &[u8]) -> usize {
    let mut set = std::collections::HashSet::new();
    for p in rgba.chunks_exact(4) {
        set.insert((p[0] >> 4, p[1] >> 4, p[2] >> 4));
    }
    set.len()
}

#[test]
fn every_builtin_scene_renders_a_non_trivial_image() {
    for name in builtin::NAMES {
        let scene = builtin::by_name(name).unwrap().unwrap();
        let img = render(&scene, "none", 320, 180);
        let covered =
            img.coverage.iter().filter(|&&c| c).count() as f64 / img.coverage.len() as f64;
        assert!(
            covered > 0.2 && covered < 1.0,
            "{name}: geometry covers {covered:.2} of the frame"
        );
        let colours = distinct_colours(&img.color);
        assert!(colours >= 8, "{name}: only {colours} distinct colours");
        let luma: Vec<f64> = img
            .color
            .chunks_exact(4)
            .map(|p| 0.3 * p[0] as f64 + 0.59 * p[1] as f64 + 0.11 * p[2] as f64)
            .collect();
        let mean = luma.iter().sum::<f64>() / luma.len() as f64;
        let sd = (luma.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / luma.len() as f64).sqrt();
        assert!(sd > 10.0, "{name}: luminance standard deviation {sd:.1}");
        // `none` writes a fully lit mask on every covered pixel.
        for m in &img.masks {
            assert!(
                m.iter().zip(&img.coverage).all(|(&v, &c)| !c || v == 1.0),
                "{name}"
            );
        }
    }
}

/// `tests/golden/NAME.png`; with SHADOWLAB_BLESS=1, `blessed` (its RGBA
/// bytes, width, height, colour type) is written there instead and the
/// test fails, so that a blessing run never counts as a pass.
fn golden_file(
    name: &str,
    blessed: (&[u8], u32, u32, image::ExtendedColorType),
) -> image::DynamicImage {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/{name}.png"));
    if std::env::var_os("SHADOWLAB_BLESS").is_some() {
        let (bytes, w, h, kind) = blessed;
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image::save_buffer(&path, bytes, w, h, kind).unwrap();
        panic!(
            "blessed {}; run again without SHADOWLAB_BLESS to test",
            path.display()
        );
    }
    image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The frame's colour against its golden image, over the RGB channels
/// (alpha is always opaque): mean difference under 0.75 of 255 and at
/// most 0.2 % of the channels more than 24 apart.
fn check_golden(name: &str, rgba: &[u8], w: u32, h: u32) {
    let golden = golden_file(name, (rgba, w, h, image::ExtendedColorType::Rgba8)).to_rgba8();
    assert_eq!(golden.dimensions(), (w, h));
    let diffs: Vec<u8> = golden
        .as_raw()
        .chunks(4)
        .zip(rgba.chunks(4))
        .flat_map(|(a, b)| (0..3).map(move |c| a[c].abs_diff(b[c])))
        .collect();
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    let large = diffs.iter().filter(|&&d| d > 24).count() as f64 / diffs.len() as f64;
    assert!(
        mean < 0.75 && large < 0.002,
        "{name}: mean RGB difference {mean:.3}, {:.3}% over 24",
        large * 100.0
    );
}

/// A light's visibility mask against its golden mask (8-bit grey, 255
/// lit): mean difference under 0.004 and at most 0.2 % of the pixels more
/// than 0.1 apart.
fn check_golden_mask(name: &str, mask: &[f32], w: u32, h: u32) {
    let grey: Vec<u8> = mask
        .iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    let golden = golden_file(name, (&grey, w, h, image::ExtendedColorType::L8)).to_luma8();
    assert_eq!(golden.dimensions(), (w, h));
    let diffs: Vec<f64> = golden
        .as_raw()
        .iter()
        .zip(mask)
        .map(|(&g, &v)| (g as f64 / 255.0 - v as f64).abs())
        .collect();
    let mean = diffs.iter().sum::<f64>() / diffs.len() as f64;
    let large = diffs.iter().filter(|&&d| d > 0.1).count() as f64 / diffs.len() as f64;
    assert!(
        mean < 0.004 && large < 0.002,
        "{name}: mean mask difference {mean:.4}, {:.3}% over 0.1",
        large * 100.0
    );
}

#[test]
fn golden_images_match() {
    for name in ["room", "floating", "bunny"] {
        let scene = builtin::by_name(name).unwrap().unwrap();
        let img = render(&scene, "none", 256, 144);
        check_golden(name, &img.color, 256, 144);
    }
}

/// The lighting pass is specialised per shading mode, specular model and
/// material: each variant matches the image of the former single shader
/// (blessed before the specialisation).
#[test]
fn golden_images_of_the_shading_variants_match() {
    use shadowlab::renderer::{LightingModel, Shading};
    for (name, shading, lighting) in [
        ("room", Shading::Flat, LightingModel::BlinnPhong),
        ("room", Shading::Gouraud, LightingModel::BlinnPhong),
        ("room", Shading::Pixel, LightingModel::Phong),
        ("bunny", Shading::Gouraud, LightingModel::Phong),
        ("floating", Shading::Flat, LightingModel::Phong),
    ] {
        let scene = builtin::by_name(name).unwrap().unwrap();
        let settings = RenderSettings {
            shading,
            lighting,
            ..golden_settings()
        };
        let img = render_with(&scene, "none", 256, 144, &settings);
        let label = format!(
            "{name}-{}-{}",
            format!("{shading:?}").to_lowercase(),
            if lighting == LightingModel::Phong {
                "phong"
            } else {
                "blinn-phong"
            }
        );
        check_golden(&label, &img.color, 256, 144);
    }
}

/// One golden image and one golden mask per technique family (its default
/// preset) on `room` under the spot light, where every family draws a
/// visible shadow.
#[test]
fn golden_images_of_every_family_match() {
    let mut scene = builtin::by_name("room").unwrap().unwrap();
    scene.lights = scene.light_preset("spot").unwrap();
    let mut blessed = vec![];
    for family in shadowlab::technique::FAMILIES {
        let img = render(&scene, family.id, 256, 144);
        if family.id != "none" {
            let shadowed = img.masks[0]
                .iter()
                .zip(&img.coverage)
                .filter(|&(&v, &c)| c && v < 0.5)
                .count();
            assert!(shadowed > 100, "{}: {shadowed} shadowed pixels", family.id);
        }
        let name = format!("room-spot-{}", family.id);
        if std::panic::catch_unwind(|| check_golden(&name, &img.color, 256, 144)).is_err() {
            blessed.push(name.clone());
        }
        let mask = format!("{name}-mask");
        if std::panic::catch_unwind(|| check_golden_mask(&mask, &img.masks[0], 256, 144)).is_err() {
            blessed.push(mask);
        }
    }
    assert!(blessed.is_empty(), "golden images differ: {blessed:?}");
}

#[test]
fn render_writes_image_masks_and_frame_json() {
    let out = tmpdir("render");
    let o = shadowlab(&[
        "render",
        "--scene",
        "floating",
        "--size",
        "160x90",
        "--out",
        out.to_str().unwrap(),
        "--eye",
        "0,4,7.5",
        "--target",
        "0,0.8,0",
        "--fov",
        "60",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Quiet success: no window-system probe complains on a headless run.
    assert!(
        !stderr(&o).to_lowercase().contains("error"),
        "a successful render printed: {}",
        stderr(&o)
    );
    let img = image::open(out.join("image.png")).unwrap();
    assert_eq!((img.width(), img.height()), (160, 90));
    let vis = image::open(out.join("visibility-0.png")).unwrap();
    assert!(matches!(vis, image::DynamicImage::ImageLuma16(_)));
    assert!(
        vis.to_luma16().pixels().all(|p| p[0] == 65535),
        "`none` is lit everywhere"
    );
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("frame.json")).unwrap()).unwrap();
    assert_eq!(j["size"]["width"], 160);
    assert_eq!(j["techniques"][0]["id"], "none:default");
    assert_eq!(j["camera"]["fov_y_deg"], 60.0);
    // The projection recorded is wgpu's [0,1]-depth perspective for the
    // camera, reversed: z_ndc = n/(far−n)·(far + z)/(−z).
    let p: Vec<f32> = j["matrices"]["projection"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    let f = 1.0 / (30f32.to_radians()).tan();
    let (n, far) = (
        j["camera"]["near"].as_f64().unwrap() as f32,
        j["camera"]["far"].as_f64().unwrap() as f32,
    );
    let expect = [
        f / (160.0 / 90.0),
        0.0,
        0.0,
        0.0,
        0.0,
        f,
        0.0,
        0.0,
        0.0,
        0.0,
        n / (far - n),
        -1.0,
        0.0,
        0.0,
        n * far / (far - n),
        0.0,
    ];
    for (a, b) in p.iter().zip(expect) {
        assert!(
            (a - b).abs() < 1e-4 * b.abs().max(1.0),
            "{p:?} vs {expect:?}"
        );
    }
    // The conventions written beside it say the same (1 at the near plane).
    let depth = j["conventions"]["depth_range"].as_str().unwrap();
    assert!(depth.contains("1 = near plane"), "{depth}");
    assert!(j["triangles"]["drawn"].as_u64().unwrap() > 1000);
    assert!(j["timings_ms"]["frame"].as_f64().unwrap() > 0.0);
    assert_eq!(j["lights"][0]["type"], "point");
}

#[test]
fn shading_modes_differ() {
    let out = tmpdir("shading");
    let mut images = vec![];
    for mode in ["flat", "gouraud", "pixel"] {
        let d = out.join(mode);
        let o = shadowlab(&[
            "render",
            "--scene",
            "floating",
            "--size",
            "128x72",
            "--shading",
            mode,
            "--out",
            d.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        images.push(image::open(d.join("image.png")).unwrap().to_rgba8());
    }
    assert_ne!(
        images[0], images[2],
        "flat and per-pixel shading give the same image"
    );
    assert_ne!(
        images[1], images[2],
        "Gouraud and per-pixel shading give the same image"
    );
}

/// A single upward-facing square seen from below: back-face culling hides
/// it (the frame shows the background), `--no-cull` draws it.
#[test]
fn back_face_culling_toggles() {
    let dir = tmpdir("culling");
    let scene = dir.join("under.toml");
    std::fs::write(
        &scene,
        "[[model]]\nshape = \"plane\"\nsize = [4.0, 4.0]\n\
         [[light]]\ntype = \"point\"\nposition = [0.0, -3.0, 0.5]\n\
         [camera]\neye = [0.0, -3.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n",
    )
    .unwrap();
    let centre = |extra: &[&str]| {
        let out = dir.join(format!("o{}", extra.len()));
        let mut args = vec![
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--size",
            "32x32",
            "--background",
            "1,0,0",
            "--no-icons",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = shadowlab(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let img = image::open(out.join("image.png")).unwrap().to_rgba8();
        let p = img.get_pixel(16, 16).0;
        (p[0], p[1], p[2])
    };
    assert_eq!(centre(&[]), (255, 0, 0), "culled: the background shows");
    let (r, g, b) = centre(&["--no-cull"]);
    assert!(
        g > 0 && b > 0 && (r, g, b) != (255, 0, 0),
        "drawn: {r} {g} {b}"
    );
}

/// Removes what legitimately varies between runs: timings.
fn without_timings(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| !(k.ends_with("_ms") || k.ends_with("per_second")));
            m.values_mut().for_each(without_timings);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(without_timings),
        _ => {}
    }
}

/// The same command twice gives bit-identical images and masks and the same
/// frame.json apart from timings, for a technique of every family.
#[test]
fn the_same_command_gives_bit_identical_output() {
    let out = tmpdir("determinism");
    for technique in [
        "raytraced",
        "planar",
        "projective",
        "shadow-map:pcss",
        "shadow-volume",
    ] {
        let run = |k: usize| {
            let d = out.join(format!("{}-{k}", technique.replace(':', "_")));
            let o = shadowlab(&[
                "render",
                "--scene",
                "floating",
                "--light",
                "spot",
                "--technique",
                technique,
                "--size",
                "96x54",
                "--out",
                d.to_str().unwrap(),
            ]);
            assert!(o.status.success(), "{technique}: {}", stderr(&o));
            let mut j: serde_json::Value =
                serde_json::from_slice(&std::fs::read(d.join("frame.json")).unwrap()).unwrap();
            without_timings(&mut j);
            (
                std::fs::read(d.join("visibility-0.png")).unwrap(),
                std::fs::read(d.join("image.png")).unwrap(),
                j,
            )
        };
        let (a, b) = (run(0), run(1));
        assert!(a.0 == b.0, "{technique}: masks differ between runs");
        assert!(a.1 == b.1, "{technique}: images differ between runs");
        assert_eq!(a.2, b.2, "{technique}: frame.json differs between runs");
        // Not a trivially lit mask.
        let mask = image::load_from_memory(&a.0).unwrap().to_luma16();
        assert!(
            mask.pixels().any(|p| p[0] < 32768),
            "{technique}: no shadow"
        );
    }
}

/// The mip filter reaches the material sampler: nearest and linear differ
/// on the bunny's textured floor at anisotropy 1, and anisotropy above 1
/// implies linear whatever was chosen.
#[test]
fn mip_filter_changes_textured_pixels_and_anisotropy_implies_linear() {
    use shadowlab::renderer::MipFilter;
    let scene = builtin::by_name("bunny").unwrap().unwrap();
    let with = |anisotropy, mip_filter| {
        let settings = RenderSettings {
            anisotropy: Some(anisotropy),
            mip_filter: Some(mip_filter),
            ..golden_settings()
        };
        render_with(&scene, "none", 320, 180, &settings).color
    };
    let differing = |a: &[u8], b: &[u8]| {
        a.chunks_exact(4)
            .zip(b.chunks_exact(4))
            .filter(|(p, q)| p != q)
            .count()
    };
    let nearest = with(1, MipFilter::Nearest);
    let linear = with(1, MipFilter::Linear);
    let changed = differing(&nearest, &linear);
    assert!(
        changed > 100,
        "only {changed} pixels differ between nearest and linear mip filtering"
    );
    assert_eq!(
        differing(&with(8, MipFilter::Nearest), &with(8, MipFilter::Linear)),
        0,
        "anisotropy 8 must filter linearly between mip levels"
    );
}
