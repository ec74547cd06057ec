#![allow(dead_code)]
//! Helpers shared by the integration tests.

use shadowlab::frame::{self, FrameImages, HeadlessFrame};
use shadowlab::gpu::GpuContext;
use shadowlab::renderer::RenderSettings;
use shadowlab::scene::Scene;
use shadowlab::technique;
use std::process::{Command, Output};
use std::sync::OnceLock;

/// One GPU context for the whole test binary (lavapipe on CI).
pub fn gpu() -> &'static GpuContext {
    static GPU: OnceLock<GpuContext> = OnceLock::new();
    GPU.get_or_init(|| {
        GpuContext::new(None).expect("a Vulkan adapter (install mesa-vulkan-drivers)")
    })
}

/// Renders `scene` with its default camera and lights using `technique`.
pub fn render(scene: &Scene, technique_id: &str, w: u32, h: u32) -> FrameImages {
    let gpu = gpu();
    let choice = technique::resolve(technique_id).unwrap();
    let n = scene.lights.len().max(1);
    let mut hf = HeadlessFrame::new(gpu, scene, &vec![choice; n], w, h).unwrap();
    let settings = RenderSettings {
        show_light_icons: false,
        ..Default::default()
    };
    hf.render(gpu, scene, &scene.camera, &scene.lights, &settings)
        .unwrap();
    frame::read_back(gpu, &hf.frame, scene.lights.len()).unwrap()
}

/// Runs the `shadowlab` binary.
pub fn shadowlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(args)
        .output()
        .expect("run shadowlab")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn tmpdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("shadowlab-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
