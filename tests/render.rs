//! Every built-in scene renders a non-trivial image; golden images of a few
//! scenes stay within a tolerance; frame.json records what the GPU used.

mod common;
use common::*;
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

/// Compares against `tests/golden/NAME.png`; set SHADOWLAB_BLESS=1 to
/// rewrite the golden files.
fn check_golden(name: &str, rgba: &[u8], w: u32, h: u32) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/{name}.png"));
    if std::env::var_os("SHADOWLAB_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image::save_buffer(&path, rgba, w, h, image::ExtendedColorType::Rgba8).unwrap();
        return;
    }
    let golden = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8();
    assert_eq!(golden.dimensions(), (w, h));
    let diffs: Vec<u8> = golden
        .as_raw()
        .iter()
        .zip(rgba)
        .map(|(&a, &b)| a.abs_diff(b))
        .collect();
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    let large = diffs.iter().filter(|&&d| d > 24).count() as f64 / diffs.len() as f64;
    assert!(
        mean < 1.5 && large < 0.005,
        "{name}: mean channel difference {mean:.3}, {:.3}% over 24",
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
    // The projection recorded is wgpu's [0,1]-depth perspective for the camera.
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
        far / (n - far),
        -1.0,
        0.0,
        0.0,
        n * far / (n - far),
        0.0,
    ];
    for (a, b) in p.iter().zip(expect) {
        assert!(
            (a - b).abs() < 1e-4 * b.abs().max(1.0),
            "{p:?} vs {expect:?}"
        );
    }
    assert!(j["triangles"]["drawn"].as_u64().unwrap() > 1000);
    assert!(j["timings_ms"]["frame"].as_f64().unwrap() > 0.0);
    assert_eq!(j["lights"][0]["type"], "point");
}

#[test]
fn shading_modes_differ_and_culling_toggles() {
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
