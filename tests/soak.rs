//! Long runs hold: every preset renders frame after frame with the camera
//! orbiting, and neither the process's resident memory nor the device's
//! live GPU objects grow between the end of the warm-up and the last frame.
//! One test in its own binary: resident memory is the process's, so nothing
//! else may run beside it.

mod common;

use shadowlab::gpu::{GpuContext, UniformSpace};
use shadowlab::measure::soak::{self, SoakLength, SoakRow};
use shadowlab::renderer::RenderSettings;
use shadowlab::technique::{self, TechniqueChoice};

/// Most resident memory a preset may gain over the measured frames, MiB.
/// A GPU object kept per frame, or a shader compiled and kept per frame
/// (the lavapipe defect below, ≥ 0.3 MiB a frame), passes it within them.
const GROWTH_BOUND_MIB: f64 = 4.0;

const LENGTH: SoakLength = SoakLength {
    warmup_frames: 5,
    min_frames: 40,
    seconds: 0.0,
};

/// The preset, with shadow maps at 256² (what is kept per frame does not
/// depend on the map's size; the soak's time does).
fn small(id: &str) -> TechniqueChoice {
    let mut choice = technique::resolve(id).unwrap();
    if choice.family.id == "shadow-map" {
        technique::apply_settings(&mut choice.params, &["size=256".into()]).unwrap();
    }
    choice
}

fn soaked(gpu: &GpuContext, scene: &str, light: &str, ids: &[String]) -> Vec<SoakRow> {
    let s = common::preset(scene, "default", light);
    let choices: Vec<TechniqueChoice> = ids.iter().map(|id| small(id)).collect();
    let settings = RenderSettings {
        show_light_icons: false,
        ..RenderSettings::default()
    };
    soak::run(
        gpu,
        shadowlab::measure::FrameRequest {
            scene: &s,
            camera: &s.camera,
            lights: &s.lights,
            size: (48, 32),
        },
        &settings,
        &choices,
        LENGTH,
    )
    .unwrap()
}

fn assert_holds(rows: &[SoakRow], what: &str) {
    for r in rows {
        assert!(
            r.frames >= LENGTH.min_frames,
            "{}: {} frames",
            r.technique,
            r.frames
        );
        assert!(
            r.live_start.counted(),
            "{what}: the device keeps no object counters"
        );
        assert!(
            r.grown_objects().is_empty(),
            "{what}, {}: GPU objects grew over {} frames: {:?}",
            r.technique,
            r.frames,
            r.grown_objects()
        );
        let growth = r.resident_growth_mib().expect("resident memory on Linux");
        assert!(
            growth <= GROWTH_BOUND_MIB,
            "{what}, {}: resident memory grew {growth:.1} MiB over {} frames",
            r.technique,
            r.frames
        );
    }
}

#[test]
fn every_preset_keeps_its_memory_and_objects_over_many_frames() {
    let gpu = common::gpu();
    let all: Vec<String> = technique::preset_ids()
        .into_iter()
        .filter(|id| id != "raytraced:reference")
        .collect();
    assert_holds(&soaked(gpu, "columns", "sun", &all), "columns/sun");
    // Point and spot lights: cube faces, paraboloids, spot maps, omni volumes.
    let omni: Vec<String> = all
        .iter()
        .filter(|id| id.starts_with("shadow-map:") || id.starts_with("shadow-volume:"))
        .cloned()
        .collect();
    assert_holds(&soaked(gpu, "room", "point", &omni), "room/point");
    assert_holds(&soaked(gpu, "room", "spot", &omni[..4]), "room/spot");

    // The instrument sees a leak: on the driver that compiles and keeps a
    // shader variant per pipeline bind, parameter blocks left in uniform
    // buffers make the shadow-map lookup grow by more than the bound.
    let mut leaky = GpuContext::new(None).unwrap();
    if leaky.uniform_space != UniformSpace::Storage {
        eprintln!(
            "skipped: the leak check needs lavapipe of Mesa 22 ({} has no such defect)",
            leaky.adapter_summary()
        );
        return;
    }
    leaky.uniform_space = UniformSpace::Uniform;
    let rows = soaked(&leaky, "columns", "sun", &["shadow-map:pcf".into()]);
    let growth = rows[0].resident_growth_mib().unwrap();
    eprintln!(
        "uniform buffers on lavapipe 22: shadow-map:pcf grew {growth:.1} MiB over {} frames",
        rows[0].frames
    );
    assert!(
        growth > GROWTH_BOUND_MIB,
        "uniform buffers on lavapipe 22 grew only {growth:.1} MiB: the soak would miss the leak"
    );
}
