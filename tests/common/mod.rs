#![allow(dead_code)]
//! Helpers shared by the integration tests.

use shadowlab::gpu::GpuContext;
use shadowlab::headless::{self, FrameImages, HeadlessFrame};
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
/// Light icons off and 8× texture anisotropy (the golden images' setting,
/// whatever the device's default).
pub fn render(scene: &Scene, technique_id: &str, w: u32, h: u32) -> FrameImages {
    render_with(scene, technique_id, w, h, &golden_settings())
}

/// The render settings of the golden images.
pub fn golden_settings() -> RenderSettings {
    RenderSettings {
        show_light_icons: false,
        anisotropy: Some(8),
        ..Default::default()
    }
}

/// [`render`] with chosen render settings.
pub fn render_with(
    scene: &Scene,
    technique_id: &str,
    w: u32,
    h: u32,
    settings: &RenderSettings,
) -> FrameImages {
    let gpu = gpu();
    let choice = technique::resolve(technique_id).unwrap();
    let n = scene.lights.len().max(1);
    let mut hf = HeadlessFrame::new(gpu, scene, &vec![choice; n], w, h).unwrap();
    hf.render(gpu, scene, &scene.camera, &scene.lights, settings)
        .unwrap();
    headless::read_back(gpu, &hf.frame, scene.lights.len()).unwrap()
}

/// One frame of `technique` (an id with optional `[k=v]` settings) with
/// its debug views enabled, rendered from the scene's camera and lights.
pub fn frame_with_debug_views(scene: &Scene, technique: &str, w: u32, h: u32) -> HeadlessFrame {
    let gpu = gpu();
    let choice = shadowlab::measure::parse_technique_list(technique)
        .unwrap()
        .remove(0);
    let mut hf = HeadlessFrame::new(gpu, scene, &[choice], w, h).unwrap();
    hf.techniques[0].technique.enable_debug(true);
    render_again(&mut hf, scene);
    hf
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

/// A fresh directory for one call: tests running in parallel that ask for
/// the same name (two comparisons of one technique) get their own.
pub fn tmpdir(name: &str) -> std::path::PathBuf {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!(
        "shadowlab-test-{}-{call}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

use glam::{Mat4, Vec3};
use shadowlab::scene::{Light, Material, shapes};

/// One light of each type above [`squares_over_floor`]'s squares: a point
/// light, a spot aimed at the origin and a sun, each slightly off the
/// vertical so that shadows fall beside their casters.
pub fn lights_over_squares() -> [Light; 3] {
    [
        Light::point(Vec3::new(0.4, 5.0, -0.3), 1.0),
        Light::spot(Vec3::new(1.0, 5.0, 1.0), Vec3::ZERO, 1.0, 30.0, 40.0),
        Light::directional(Vec3::new(0.3, -1.0, 0.2), 1.0),
    ]
}

/// A scene named `name` with one grey material and a `side` × `side` floor
/// at y = 0 cut into `subdiv`² squares; the scene and the material.
pub fn grey_floor_scene(name: &str, side: f32, subdiv: u32) -> (Scene, usize) {
    let mut s = Scene::new(name);
    let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
    let floor = s.add_mesh(shapes::plane(side, side, subdiv));
    s.add_object("Floor", floor, grey, Mat4::IDENTITY);
    (s, grey)
}

/// A 20×20 floor at y = 0 (also a `ShadowPlane` when `plane_object`) and
/// axis-aligned square casters `(centre, half size)` facing down, so a camera
/// above sees the floor through them with back-face culling while shadow
/// rays and flattened shadows still see them.
pub fn squares_over_floor(squares: &[(Vec3, f32)], light: Light, plane_object: bool) -> Scene {
    let (mut s, grey) = grey_floor_scene("squares", 20.0, 4);
    if plane_object {
        let floor = s.objects[0].mesh;
        s.add_object("ShadowPlaneFloor", floor, grey, Mat4::IDENTITY);
    }
    let quad = s.add_mesh(shapes::plane(2.0, 2.0, 1));
    for (i, &(c, h)) in squares.iter().enumerate() {
        s.add_object(
            &format!("Square{i}"),
            quad,
            grey,
            Mat4::from_translation(c)
                * Mat4::from_scale(Vec3::splat(h))
                * Mat4::from_rotation_x(std::f32::consts::PI),
        );
    }
    s.lights = vec![light];
    s.camera = shadowlab::scene::Camera {
        up: Vec3::NEG_Z,
        ..shadowlab::scene::Camera::new(Vec3::new(0.0, 8.0, 0.0), Vec3::ZERO)
    };
    s.finalize().unwrap();
    s
}

/// A headless frame of `technique_id` (with `--set`-style settings) on
/// `scene`, not yet rendered.
pub fn frame_of(scene: &Scene, technique_id: &str, set: &[&str], w: u32, h: u32) -> HeadlessFrame {
    let mut choice = technique::resolve(technique_id).unwrap();
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    technique::apply_settings(&mut choice.params, &set).unwrap();
    HeadlessFrame::new(gpu(), scene, &[choice], w, h).unwrap()
}

/// A built-in scene seen from a camera preset under a light preset.
pub fn preset(scene: &str, camera: &str, light: &str) -> Scene {
    let mut s = shadowlab::scene::builtin::by_name(scene).unwrap().unwrap();
    s.camera = s.camera_preset(camera).unwrap();
    s.lights = s.light_preset(light).unwrap();
    s
}

/// [`frame_of`], rendered once (kept for more frames).
pub fn rendered_frame(
    scene: &Scene,
    technique_id: &str,
    set: &[&str],
    w: u32,
    h: u32,
) -> HeadlessFrame {
    let mut hf = frame_of(scene, technique_id, set, w, h);
    render_again(&mut hf, scene);
    hf
}

/// Renders `hf` again from the scene's camera and lights (no light icons).
pub fn render_again(hf: &mut HeadlessFrame, scene: &Scene) {
    let settings = RenderSettings {
        show_light_icons: false,
        ..Default::default()
    };
    hf.render(gpu(), scene, &scene.camera, &scene.lights, &settings)
        .unwrap();
}

/// A technique's counter after the frame `hf` rendered last.
pub fn counter(hf: &HeadlessFrame, name: &str) -> f64 {
    hf.techniques[0]
        .technique
        .counters()
        .into_iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no counter {name}"))
        .1
}

/// Pixels whose visibility differs by more than 1e-3 between two masks.
pub fn pixels_differing(a: &[f32], b: &[f32]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(a, b)| (*a - *b).abs() > 1e-3)
        .count()
}

/// Renders one frame with `technique_id` (with `--set`-style settings) and
/// returns light 0's mask.
pub fn mask_of(scene: &Scene, technique_id: &str, set: &[&str], w: u32, h: u32) -> Vec<f32> {
    let gpu = gpu();
    let mut hf = frame_of(scene, technique_id, set, w, h);
    let settings = RenderSettings {
        show_light_icons: false,
        ..Default::default()
    };
    hf.render(gpu, scene, &scene.camera, &scene.lights, &settings)
        .unwrap();
    headless::read_back(gpu, &hf.frame, 1)
        .unwrap()
        .masks
        .remove(0)
}

/// Quality of `technique_id` against `raytraced` on `scene`'s camera and lights.
pub fn compare(
    scene: &Scene,
    technique_id: &str,
    size: (u32, u32),
) -> shadowlab::measure::compare::QualityRow {
    compare_with(scene, &scene.camera, technique_id, size)
}

/// The same from another camera.
pub fn compare_with(
    scene: &Scene,
    camera: &shadowlab::scene::Camera,
    technique_id: &str,
    size: (u32, u32),
) -> shadowlab::measure::compare::QualityRow {
    use shadowlab::measure;
    let out = tmpdir(&format!("cmp-{}", measure::file_stem(technique_id)));
    let list = measure::parse_technique_list(technique_id).unwrap();
    let reference = technique::resolve("raytraced").unwrap();
    measure::compare::run(
        gpu(),
        shadowlab::measure::FrameRequest {
            scene,
            camera,
            lights: &scene.lights,
            size,
        },
        &list,
        &reference,
        &out,
    )
    .unwrap()
    .remove(0)
}
