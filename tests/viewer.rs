//! The interactive viewer, started under Xvfb on the CPU Vulkan driver:
//! its screenshot must show the scene and the egui panel.

#![cfg(feature = "viewer")]

mod common;
use common::*;
use std::process::Command;

/// Runs `shadowlab view ARGS --screenshot SHOT` under Xvfb.
fn view_under_xvfb(args: &[&str], shot: &std::path::Path) -> std::process::Output {
    Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_shadowlab"))
        .arg("view")
        .args(args)
        .arg("--screenshot")
        .arg(shot)
        .output()
        .expect("xvfb-run (package xvfb) must be installed: scripts/setup.sh --test does it")
}

#[test]
fn viewer_screenshot_shows_scene_and_panel() {
    let dir = tmpdir("viewer");
    let shot = dir.join("view.png");
    let o = view_under_xvfb(
        &[
            "--scene",
            "floating",
            "--technique",
            "planar",
            "--size",
            "800x450",
            "--frames",
            "4",
            "--heatmap",
        ],
        &shot,
    );
    assert!(o.status.success(), "viewer failed: {}", stderr(&o));
    // The heatmap against raytraced arrived from its background thread.
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("heatmap: false shadow"), "{stdout}");
    let img = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (800, 450));
    // The panel: a dark, nearly grey strip on the left with some light text.
    let panel_dark = (0..450)
        .step_by(3)
        .flat_map(|y| (0..150).step_by(3).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let p = img.get_pixel(x, y);
            p[0] < 60 && p[1] < 60 && p[2] < 60 && p[0].abs_diff(p[2]) < 8
        })
        .count();
    assert!(
        panel_dark > 1500,
        "no egui panel on the left ({panel_dark} dark samples)"
    );
    let text = (0..450)
        .flat_map(|y| (0..250).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y)[0] > 150)
        .count();
    assert!(text > 200, "the panel shows no text ({text} light pixels)");
    // The scene: the checker floor (light and dark squares) and the red
    // sphere between the panel and the dock (the heatmap's window, anchored
    // to the right edge, may cover the torus).
    let middle: Vec<_> = (0..450)
        .flat_map(|y| (330..465).map(move |x| (x, y)))
        .map(|(x, y)| *img.get_pixel(x, y))
        .collect();
    let grey = |p: &&image::Rgba<u8>, lo: u8, hi: u8| {
        p[0] >= lo && p[0] <= hi && p[0].abs_diff(p[2]) < 12 && p[0].abs_diff(p[1]) < 12
    };
    let light_floor = middle.iter().filter(|p| grey(p, 150, 255)).count();
    let dark_floor = middle.iter().filter(|p| grey(p, 70, 149)).count();
    let red = middle
        .iter()
        .filter(|p| p[0] > 150 && p[1] < 130 && p[2] < 130 && p[0] > p[1] + 50)
        .count();
    assert!(
        light_floor > 2000 && dark_floor > 2000 && red > 200,
        "scene not visible: {light_floor} light and {dark_floor} dark floor pixels, {red} red pixels"
    );
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("view.json")).unwrap()).unwrap();
    assert_eq!(j["techniques"][0]["id"], "planar:default");
}

#[test]
fn viewer_shows_the_technique_debug_views() {
    let dir = tmpdir("viewer-debug");
    let o = view_under_xvfb(
        &[
            "--scene",
            "room",
            "--light",
            "spot",
            "--technique",
            "shadow-map:hard",
            "--size",
            "640x360",
            "--frames",
            "3",
            "--debug-views",
        ],
        &dir.join("debug.png"),
    );
    assert!(o.status.success(), "viewer failed: {}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("debug views: 3 image(s)"), "{stdout}");
    // The spot light's frustum is drawn in yellow over the scene.
    let img = image::open(dir.join("debug.png")).unwrap().to_rgba8();
    // Line colour (1, 0.85, 0.2) linear is about (255, 238, 124) in sRGB.
    let yellow = img
        .pixels()
        .filter(|p| p[0] > 220 && p[1] > 200 && p[2] > 90 && p[2] < 160)
        .count();
    assert!(yellow > 100, "no frustum lines ({yellow} yellow pixels)");
}

/// `--mask 0` shows light 0's visibility mask in grey. The blit that draws
/// the view and the one that presents it share an encoder; with one shared
/// uniform buffer both saw the second's mode and the mask never showed.
#[test]
fn the_mask_overlay_shows_the_mask() {
    let dir = tmpdir("viewer-mask");
    let shot = dir.join("mask.png");
    let o = view_under_xvfb(
        &[
            "--scene",
            "floating",
            "--technique",
            "shadow-map",
            "--mask",
            "0",
            "--size",
            "800x450",
            "--frames",
            "3",
        ],
        &shot,
    );
    assert!(o.status.success(), "viewer failed: {}", stderr(&o));
    let img = image::open(&shot).unwrap().to_rgba8();
    // The view right of the panel: every pixel grey; lit (white) and
    // shadowed (dark) pixels both present; none of the image's colours.
    let view: Vec<_> = (0..450)
        .flat_map(|y| (560..800).map(move |x| (x, y)))
        .map(|(x, y)| *img.get_pixel(x, y))
        .collect();
    let coloured = view
        .iter()
        .filter(|p| p[0].abs_diff(p[1]) > 2 || p[1].abs_diff(p[2]) > 2)
        .count();
    let white = view.iter().filter(|p| p[0] > 250).count();
    let dark = view.iter().filter(|p| p[0] < 60).count();
    assert!(
        coloured == 0 && white > 1000 && dark > 200,
        "{coloured} coloured, {white} white, {dark} dark pixels"
    );
    // A light that does not exist is refused before a window opens.
    let o = shadowlab(&["view", "--scene", "floating", "--mask", "3"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--mask 3: there are 1 light(s)"),
        "{}",
        stderr(&o)
    );
}

/// The window shows exactly the frame `shadowlab render` makes of the same
/// view: the view reaches the window by a copy in the window's colour
/// format (BGRA here) or by a blit, with no change to any pixel.
#[test]
fn the_window_shows_the_rendered_frame_unchanged() {
    let dir = tmpdir("viewer-exact");
    let shot = dir.join("view.png");
    let o = view_under_xvfb(
        &[
            "--scene",
            "room",
            "--technique",
            "none",
            "--light",
            "spot",
            "--size",
            "800x450",
            "--frames",
            "3",
        ],
        &shot,
    );
    assert!(o.status.success(), "viewer failed: {}", stderr(&o));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("view.json")).unwrap()).unwrap();
    let (w, h) = (
        j["size"]["width"].as_u64().unwrap() as u32,
        j["size"]["height"].as_u64().unwrap() as u32,
    );
    assert!(w < 800 && h == 450, "view {w}x{h} beside the panel");
    let out = dir.join("render");
    let size = format!("{w}x{h}");
    let o = shadowlab(&[
        "render",
        "--scene",
        "room",
        "--technique",
        "none",
        "--light",
        "spot",
        "--size",
        &size,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "render failed: {}", stderr(&o));
    let window = image::open(&shot).unwrap().to_rgba8();
    let frame = image::open(out.join("image.png")).unwrap().to_rgba8();
    let left = 800 - w;
    let mut differing = 0;
    for (x, y, p) in frame.enumerate_pixels() {
        let q = window.get_pixel(left + x, y);
        if (0..3).any(|c| p[c].abs_diff(q[c]) > 1) {
            differing += 1;
        }
    }
    // The viewer's FPS line does not reach the view; nothing else differs.
    assert_eq!(differing, 0, "{differing} of {w}x{h} pixels differ");
}

/// `--camera-path strafe` moves the camera one step per frame to its right
/// (the steps of `compare --path`), keeping its direction.
#[test]
fn the_camera_follows_a_path() {
    let dir = tmpdir("viewer-path");
    let shot = dir.join("path.png");
    let o = view_under_xvfb(
        &[
            "--scene",
            "floating",
            "--camera-path",
            "strafe",
            "--size",
            "400x300",
            "--frames",
            "5",
        ],
        &shot,
    );
    assert!(o.status.success(), "viewer failed: {}", stderr(&o));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("path.json")).unwrap()).unwrap();
    let v = |k: &str| -> Vec<f64> {
        j["camera"][k]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let scene = shadowlab::scene::load("floating").unwrap();
    let start = scene.camera;
    let (eye, target) = (v("eye"), v("target"));
    let moved = glam::Vec3::new(eye[0] as f32, eye[1] as f32, eye[2] as f32) - start.eye;
    let forward = (start.target - start.eye).normalize();
    let right = forward.cross(start.up).normalize();
    let step = (start.target - start.eye).length() * shadowlab::measure::flicker::MOVE_STEP;
    // One step per frame: the screenshot after frame 5 is 5 steps along.
    let steps = moved.dot(right) / step;
    assert!((steps - 5.0).abs() < 1e-3, "moved {moved} = {steps} steps");
    assert!(moved.dot(forward).abs() < 1e-3 * step.max(1.0), "{moved}");
    let look = glam::Vec3::new(target[0] as f32, target[1] as f32, target[2] as f32)
        - glam::Vec3::new(eye[0] as f32, eye[1] as f32, eye[2] as f32);
    assert!(look.normalize().dot(forward) > 0.9999);
}
