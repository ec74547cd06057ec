//! The per-device pipeline cache: technique instances share their family's
//! pipelines, switching back to a technique compiles nothing, a parameter
//! sweep keeps the cache at its bound, and a frame waits for the GPU once
//! while its timestamps still arrive.

use shadowlab::gpu::{GpuContext, PIPELINE_CACHE_BOUND};
use shadowlab::headless::HeadlessFrame;
use shadowlab::renderer::RenderSettings;
use shadowlab::scene::{Scene, builtin};
use shadowlab::technique::{self, TechniqueInstance};

/// A device of its own, so that other tests' pipelines do not count; the
/// tests of this file take turns (`bench`'s timings are compared, and a
/// test rendering beside them would skew them).
fn own_gpu() -> (GpuContext, std::sync::MutexGuard<'static, ()>) {
    static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let gpu = GpuContext::new(None).expect("a Vulkan adapter (install mesa-vulkan-drivers)");
    (gpu, turn)
}

fn room_with_spot() -> Scene {
    let mut scene = builtin::by_name("room").unwrap().unwrap();
    scene.lights = scene.light_preset("spot").unwrap();
    scene
}

fn render(gpu: &GpuContext, hf: &mut HeadlessFrame, scene: &Scene, settings: &RenderSettings) {
    hf.render(gpu, scene, &scene.camera, &scene.lights, settings)
        .unwrap();
}

fn use_technique(gpu: &GpuContext, hf: &mut HeadlessFrame, id: &str) {
    hf.techniques[0] = TechniqueInstance::new(gpu, technique::resolve(id).unwrap()).unwrap();
}

#[test]
fn switching_back_to_a_technique_compiles_nothing() {
    let (gpu, _turn) = own_gpu();
    let scene = room_with_spot();
    let settings = RenderSettings::default();
    let choice = technique::resolve("shadow-map:pcf").unwrap();
    let mut hf = HeadlessFrame::new(&gpu, &scene, &[choice], 96, 54).unwrap();
    render(&gpu, &mut hf, &scene, &settings);
    let after_first = gpu.cache.pipelines_created();
    assert!(after_first > 0);
    // A second frame compiles nothing.
    render(&gpu, &mut hf, &scene, &settings);
    assert_eq!(gpu.cache.pipelines_created(), after_first);
    // Another family compiles its own pipelines once.
    use_technique(&gpu, &mut hf, "shadow-volume");
    render(&gpu, &mut hf, &scene, &settings);
    let after_volume = gpu.cache.pipelines_created();
    assert!(after_volume > after_first, "shadow volumes need pipelines");
    // Back to the shadow map, and to the volumes again: nothing new.
    for id in ["shadow-map:pcf", "shadow-volume", "shadow-map:pcf"] {
        use_technique(&gpu, &mut hf, id);
        render(&gpu, &mut hf, &scene, &settings);
        assert_eq!(gpu.cache.pipelines_created(), after_volume, "{id}");
    }
    // A new instance (another light, another frame) shares them too.
    let again = HeadlessFrame::new(
        &gpu,
        &scene,
        &[technique::resolve("shadow-volume").unwrap()],
        96,
        54,
    );
    let mut again = again.unwrap();
    render(&gpu, &mut again, &scene, &settings);
    assert_eq!(gpu.cache.pipelines_created(), after_volume);
}

#[test]
fn a_depth_bias_sweep_keeps_the_cache_at_its_bound() {
    let (gpu, _turn) = own_gpu();
    let scene = room_with_spot();
    let settings = RenderSettings::default();
    let choice = technique::resolve("shadow-map:hard").unwrap();
    let mut hf = HeadlessFrame::new(&gpu, &scene, &[choice], 64, 36).unwrap();
    render(&gpu, &mut hf, &scene, &settings);
    let before = gpu.cache.pipelines_created();
    // Depth passes per bias value: back faces, and with the spot map's
    // capped bias (`slope_bias_clamp_local`) the concave solids' pushed
    // front faces.
    // Enough values to fill the cache past its bound: the first tells how
    // many pipelines each takes.
    let (mut per_value, mut values) = (0, 1);
    let mut bias = 0;
    while bias < values {
        let mut params = hf.techniques[0].choice.params.clone();
        params.set("depth_bias", &format!("{}", 10 + bias)).unwrap();
        hf.techniques[0].set_params(params).unwrap();
        render(&gpu, &mut hf, &scene, &settings);
        if bias == 0 {
            per_value = gpu.cache.pipelines_created() - before;
            values = PIPELINE_CACHE_BOUND as u64 / per_value.max(1) + 10;
        }
        assert!(gpu.cache.pipelines_cached() <= PIPELINE_CACHE_BOUND);
        bias += 1;
    }
    // The bias value's depth passes, each compiled once; the cache full.
    assert!(
        (1..=2).contains(&per_value),
        "{per_value} pipelines a bias value"
    );
    assert_eq!(gpu.cache.pipelines_created(), before + values * per_value);
    assert_eq!(gpu.cache.pipelines_cached(), PIPELINE_CACHE_BOUND);
    // The pipelines in use every frame stayed (least recently used goes
    // first): one more frame compiles nothing.
    render(&gpu, &mut hf, &scene, &settings);
    assert_eq!(gpu.cache.pipelines_created(), before + values * per_value);
    // The sweep still draws shadows.
    let mask = shadowlab::headless::read_back(&gpu, &hf.frame, 1)
        .unwrap()
        .masks
        .remove(0);
    assert!(mask.iter().any(|&v| v < 0.5));
}

#[test]
fn a_frame_waits_once_and_its_gpu_times_still_arrive() {
    let (gpu, _turn) = own_gpu();
    let scene = room_with_spot();
    // The whole cone: a map focused on the pixels seen (`fit=samples`)
    // waits for its reduction too in measurements.
    let choice = shadowlab::measure::parse_technique_list("shadow-map:pcf[fit=depth]")
        .unwrap()
        .remove(0);
    let mut hf = HeadlessFrame::new(&gpu, &scene, &[choice], 96, 54).unwrap();
    let settings = RenderSettings {
        gpu_timing: true,
        stage_waits: false,
        ..Default::default()
    };
    let mut seen = None;
    for _ in 0..4 {
        let waits = gpu.waits();
        let t = hf
            .render(&gpu, &scene, &scene.camera, &scene.lights, &settings)
            .unwrap();
        assert_eq!(gpu.waits(), waits + 1, "one wait per frame");
        seen = seen.or(t.gpu);
    }
    if !gpu.timestamps {
        eprintln!(
            "skipped: {} has no timestamp queries; the GPU times were not checked",
            gpu.adapter_summary()
        );
        assert!(seen.is_none());
        return;
    }
    // The times arrive a frame late, one per stage (their size is the
    // benchmarks' business, not a test's).
    let t = seen.expect("GPU times of an earlier frame");
    let stages = [t.prepass_ms, t.masks_ms, t.lighting_ms];
    assert!(
        stages.iter().all(|ms| ms.is_finite() && *ms >= 0.0),
        "{t:?}"
    );
    // With stage waits, each frame reports its own times.
    let waited = RenderSettings {
        stage_waits: true,
        ..settings
    };
    let t = hf
        .render(&gpu, &scene, &scene.camera, &scene.lights, &waited)
        .unwrap();
    assert!(t.gpu.is_some());
    // Shadow volumes read their statistics back without a second wait.
    let mut hf = HeadlessFrame::new(
        &gpu,
        &scene,
        &[technique::resolve("shadow-volume").unwrap()],
        96,
        54,
    )
    .unwrap();
    for _ in 0..2 {
        let waits = gpu.waits();
        hf.render(&gpu, &scene, &scene.camera, &scene.lights, &settings)
            .unwrap();
        assert_eq!(gpu.waits(), waits + 1, "one wait per frame");
    }
    let counters: std::collections::HashMap<_, _> =
        hf.techniques[0].technique.counters().into_iter().collect();
    assert!(counters["silhouette_edges"] > 0.0, "{counters:?}");
}

/// `bench` of `list` on `scene`'s camera and lights at `size`, with
/// `(warmup, measured)` frames and no time limit, written to `out`.
fn bench_of(
    gpu: &GpuContext,
    scene: &Scene,
    list: &[technique::TechniqueChoice],
    size: (u32, u32),
    (warmup, measured): (u32, u32),
    out: &std::path::Path,
) -> Vec<shadowlab::measure::bench::BenchRow> {
    let frames = shadowlab::measure::bench::BenchFrames {
        warmup,
        measured,
        progress: false,
        max_seconds: None,
    };
    let view = shadowlab::measure::FrameRequest {
        scene,
        camera: &scene.camera,
        lights: &scene.lights,
        size,
    };
    shadowlab::measure::bench::run(gpu, view, &RenderSettings::default(), list, frames, out)
        .unwrap()
}

/// `bench` measures its frames round-robin: the same techniques in two
/// orders give ratios to `none` whose spreads (the 5th–95th percentile of
/// the per-round ratios) overlap, each median inside its own spread.
#[test]
fn bench_ratios_do_not_depend_on_the_order() {
    use shadowlab::measure::bench;
    let (gpu, _turn) = own_gpu();
    let scene = room_with_spot();
    let run = |spec: &str| {
        let list = shadowlab::measure::parse_technique_list(spec).unwrap();
        let out = std::env::temp_dir().join(format!("shadowlab-bench-order-{}", spec.len()));
        bench_of(&gpu, &scene, &list, (320, 180), (2, 20), &out)
    };
    let forward = run("none,shadow-map:pcf[size=512],shadow-volume:zfail");
    let backward = run("shadow-volume:zfail,shadow-map:pcf[size=512],none");
    for a in &forward {
        let b = backward
            .iter()
            .find(|b| b.technique == a.technique)
            .unwrap();
        assert_eq!(a.measured_frames, 20);
        let inside = |r: &bench::BenchRow| {
            r.ratio_spread.0 <= r.ratio_to_none && r.ratio_to_none <= r.ratio_spread.1
        };
        let overlap =
            a.ratio_spread.0.max(b.ratio_spread.0) <= a.ratio_spread.1.min(b.ratio_spread.1);
        assert!(
            inside(a) && inside(b) && overlap,
            "{}: ×{:.2} (spread {:?}) forward, ×{:.2} (spread {:?}) backward",
            a.technique,
            a.ratio_to_none,
            a.ratio_spread,
            b.ratio_to_none,
            b.ratio_spread
        );
    }
}

/// A bench of every preset interleaved frame by frame, as a report's view
/// is, compiles no pipeline in its measured frames: the device's cache
/// holds what all of them need, so no technique's frame pays for a compile
/// that another's evicted.
#[test]
fn a_bench_of_many_techniques_compiles_nothing_while_measuring() {
    let (gpu, _turn) = own_gpu();
    let mut scene = room_with_spot();
    scene.lights = scene.light_preset("sun").unwrap();
    // The 1024-sample reference takes seconds a frame even this small.
    let ids: Vec<String> = technique::preset_ids()
        .into_iter()
        .filter(|id| id != "raytraced:reference")
        .collect();
    let list = shadowlab::measure::parse_technique_list(&ids.join(",")).unwrap();
    let out = std::env::temp_dir().join("shadowlab-bench-many");
    bench_of(&gpu, &scene, &list, (64, 36), (1, 2), &out);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    assert!(ids.len() > 40, "{} presets", ids.len());
    assert_eq!(json["meta"]["pipelines_compiled_while_measuring"], 0);
}
