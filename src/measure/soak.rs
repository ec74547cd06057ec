//! `shadowlab bench --soak SECONDS`: each technique renders frame after
//! frame for a while with the camera orbiting, and the run reports what
//! grew — the process's resident memory, the device's live GPU objects —
//! and how the frame time drifted from the first quarter of the frames to
//! the last. Something kept per frame shows as memory that grows with the
//! frame count; a cache that grows without bound, as frames that slow.

use super::bench::Stat;
use super::flicker::{CameraPath, path_camera};
use super::{FrameRequest, choice_label};
use crate::gpu::{GpuContext, LiveResources, PIPELINE_CACHE_BOUND};
use crate::headless::HeadlessFrame;
use crate::renderer::RenderSettings;
use crate::technique::{TechniqueChoice, TechniqueInstance};
use anyhow::{Context, Result};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Orbit steps of [`CameraPath::Orbit`] per soak frame: the camera turns
/// 1° about the target a frame, so every frame sees a new view.
const ORBIT_STEPS_PER_FRAME: u32 = 10;

/// How long each technique is soaked.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SoakLength {
    /// Frames rendered before the first reading (pipelines, first pages).
    pub warmup_frames: u32,
    /// Frames measured at least.
    pub min_frames: u32,
    /// Seconds measured at least (after the warm-up).
    pub seconds: f64,
}

/// The resident memory of this process in bytes (`VmRSS`); `None` where the
/// system does not say (not Linux).
pub fn resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// One technique's soak.
#[derive(Clone, Debug, Serialize)]
pub struct SoakRow {
    pub technique: String,
    /// Frames measured after the warm-up.
    pub frames: u32,
    pub seconds: f64,
    /// Resident memory after the warm-up and after the last frame, MiB.
    pub resident_start_mib: Option<f64>,
    pub resident_end_mib: Option<f64>,
    /// The device's live objects after the warm-up and after the last frame.
    pub live_start: LiveResources,
    pub live_end: LiveResources,
    /// Median frame time of the first and last quarter of the frames, ms.
    pub first_quarter_ms: f64,
    pub last_quarter_ms: f64,
}

impl SoakRow {
    /// Resident memory grown over the measured frames, MiB.
    pub fn resident_growth_mib(&self) -> Option<f64> {
        Some(self.resident_end_mib? - self.resident_start_mib?)
    }

    /// The last quarter's frame time over the first quarter's.
    pub fn time_drift(&self) -> f64 {
        self.last_quarter_ms / self.first_quarter_ms
    }

    /// Live objects whose count changed, as (name, start, end). Pipelines
    /// may be made while the view changes but stay within the cache's
    /// bound ([`PIPELINE_CACHE_BOUND`] per device): they are listed only
    /// past it.
    pub fn grown_objects(&self) -> Vec<(&'static str, isize, isize)> {
        self.live_start
            .counts()
            .into_iter()
            .zip(self.live_end.counts())
            .filter(|((name, a), (_, b))| {
                let pipelines = name.ends_with("_pipelines");
                a != b && !(pipelines && *b <= PIPELINE_CACHE_BOUND as isize)
            })
            .map(|((name, a), (_, b))| (name, a, b))
            .collect()
    }
}

/// Soaks each technique in turn on one frame (fresh instances per
/// technique), the camera orbiting the start view's target.
pub fn run(
    gpu: &GpuContext,
    view: FrameRequest,
    settings: &RenderSettings,
    techniques: &[TechniqueChoice],
    length: SoakLength,
) -> Result<Vec<SoakRow>> {
    let FrameRequest {
        scene,
        camera,
        lights,
        size,
    } = view;
    let mut hf = HeadlessFrame::new(gpu, scene, &techniques[..1], size.0, size.1)?;
    let mut rows = vec![];
    for choice in techniques {
        hf.techniques = TechniqueInstance::per_light(gpu, choice, lights.len())?;
        let mut frame = 0;
        let mut render = |hf: &mut HeadlessFrame| -> Result<f64> {
            let view = path_camera(camera, CameraPath::Orbit, frame * ORBIT_STEPS_PER_FRAME);
            frame += 1;
            Ok(hf.render(gpu, scene, &view, lights, settings)?.total_ms)
        };
        for _ in 0..length.warmup_frames {
            render(&mut hf)?;
        }
        let resident_start = resident_bytes();
        let live_start = LiveResources::of(&gpu.device);
        let started = Instant::now();
        let mut times = vec![];
        while times.len() < length.min_frames as usize
            || started.elapsed().as_secs_f64() < length.seconds
        {
            times.push(render(&mut hf)?);
        }
        let quarter = (times.len() / 4).max(1);
        let median = |v: &[f64]| Stat::of(v.to_vec()).median;
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        rows.push(SoakRow {
            technique: choice_label(choice),
            frames: times.len() as u32,
            seconds: started.elapsed().as_secs_f64(),
            resident_start_mib: resident_start.map(mib),
            resident_end_mib: resident_bytes().map(mib),
            live_start,
            live_end: LiveResources::of(&gpu.device),
            first_quarter_ms: median(&times[..quarter]),
            last_quarter_ms: median(&times[times.len() - quarter..]),
        });
    }
    Ok(rows)
}

/// The soak's table (Markdown).
pub fn markdown(rows: &[SoakRow], adapter: &str) -> String {
    let mut s = format!(
        "Soak on {adapter}: resident memory and live GPU objects after the warm-up and after \
         the last frame, frame time of the first and last quarter (median), camera orbiting.\n\n\
         | technique | frames | s | resident MiB | growth MiB | first ¼ ms | last ¼ ms | drift | objects grown |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---|\n"
    );
    let opt = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.1}"));
    for r in rows {
        let grown: Vec<String> = r
            .grown_objects()
            .iter()
            .map(|(n, a, b)| format!("{n} {a}→{b}"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {} → {} | {} | {:.2} | {:.2} | {:.2}× | {} |",
            r.technique,
            r.frames,
            r.seconds,
            opt(r.resident_start_mib),
            opt(r.resident_end_mib),
            opt(r.resident_growth_mib()),
            r.first_quarter_ms,
            r.last_quarter_ms,
            r.time_drift(),
            if grown.is_empty() {
                "none".into()
            } else {
                grown.join(", ")
            }
        );
    }
    s
}

/// Writes `soak.md` and `soak.json` into `out`.
pub fn write(out: &Path, rows: &[SoakRow], adapter: &str, length: SoakLength) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let md = out.join("soak.md");
    std::fs::write(&md, markdown(rows, adapter))
        .with_context(|| format!("writing {}", md.display()))?;
    let json = serde_json::json!({ "adapter": adapter, "length": length, "rows": rows });
    let path = out.join("soak.json");
    std::fs::write(&path, serde_json::to_string_pretty(&json)?)
        .with_context(|| format!("writing {}", path.display()))
}
