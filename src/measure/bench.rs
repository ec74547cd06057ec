//! `shadowlab bench`: frame and pass timings per technique on one frame:
//! warm-up frames, then N measured frames; median, p5, p95; GPU timestamps
//! per pass where the adapter has them, CPU wall time always (each stage
//! waits for the GPU, so CPU-side technique work is included); each
//! technique's frame time as a ratio to `none` measured in the same run.

use super::choice_label;
use crate::gpu::GpuContext;
use crate::headless::HeadlessFrame;
use crate::renderer::{FrameTimings, RenderSettings};
use crate::scene::{Camera, Light, Scene};
use crate::technique::{self, TechniqueChoice};
use anyhow::{Context, Result};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Median and 5th/95th percentiles, milliseconds.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Stat {
    pub median: f64,
    pub p5: f64,
    pub p95: f64,
}

impl Stat {
    pub fn of(mut v: Vec<f64>) -> Stat {
        if v.is_empty() {
            return Stat::default();
        }
        v.sort_by(|a, b| a.total_cmp(b));
        Stat {
            median: super::percentile(&v, 0.5),
            p5: super::percentile(&v, 0.05),
            p95: super::percentile(&v, 0.95),
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    pub technique: String,
    /// Wall time of the whole frame (CPU, waiting for the GPU at each stage).
    pub frame_ms: Stat,
    /// Wall time of the visibility-mask stage (includes CPU-side technique work).
    pub masks_ms: Stat,
    pub gpu_frame_ms: Option<Stat>,
    pub gpu_prepass_ms: Option<Stat>,
    pub gpu_masks_ms: Option<Stat>,
    pub gpu_lighting_ms: Option<Stat>,
    /// Median frame time divided by `none`'s median frame time.
    pub ratio_to_none: f64,
    pub triangles_drawn: usize,
    pub caster_triangles: usize,
    pub shadow_resource_bytes: u64,
    /// The techniques' counters: times (names ending in `_ms`) as the
    /// median over the measured frames, the rest as of the last frame.
    pub counters: Vec<(String, f64)>,
    /// Frames measured (fewer than asked when `max_seconds` ran out).
    pub measured_frames: usize,
}

/// How many frames `bench` renders per technique, and whether it draws its
/// own progress bar (a caller with its own bar turns it off).
#[derive(Clone, Copy, Debug)]
pub struct BenchFrames {
    /// Frames rendered first and not measured.
    pub warmup: u32,
    pub measured: u32,
    pub progress: bool,
    /// Stop a technique's frames once this many seconds have gone by,
    /// after at least one measured frame (a 1024-sample reference takes
    /// minutes a frame on a CPU); `None`: every frame.
    pub max_seconds: Option<f64>,
}

/// Benchmarks `techniques` (with `none` added first when missing) with the
/// render settings `base` (shading, specular model, culling), each stage
/// waited for, GPU timestamps on and light icons off.
#[allow(clippy::too_many_arguments)]
pub fn run(
    gpu: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    size: (u32, u32),
    base: &RenderSettings,
    techniques: &[TechniqueChoice],
    counts: BenchFrames,
    out: &Path,
) -> Result<Vec<BenchRow>> {
    let BenchFrames {
        warmup,
        measured: frames,
        ..
    } = counts;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut list: Vec<TechniqueChoice> = techniques.to_vec();
    if !list.iter().any(|c| c.family.id == "none") {
        list.insert(0, technique::resolve("none")?);
    }
    let settings = RenderSettings {
        show_light_icons: false,
        gpu_timing: true,
        stage_waits: true,
        ..*base
    };
    let total = (list.len() as u32 * (warmup + frames)) as u64;
    let bar = super::progress_bar(
        counts.progress,
        total,
        "{msg:>28} [{bar:30}] {pos}/{len} frames, {elapsed}",
    );
    let mut rows = vec![];
    // One frame (scene upload, targets) for every technique; each gets
    // fresh instances.
    let mut hf = HeadlessFrame::new(gpu, scene, &list[..1], size.0, size.1)?;
    // The shared frame's own first frames (its passes' pipelines, llvmpipe's
    // shader compiles) are nobody's cost: run them before anything is timed,
    // or the first technique — `none`, the baseline — pays for them.
    for _ in 0..warmup.max(1) {
        hf.render(gpu, scene, camera, lights, &settings)?;
    }
    for choice in &list {
        let label = choice_label(choice);
        bar.set_message(label.clone());
        hf.techniques = (0..lights.len().max(1))
            .map(|_| crate::technique::TechniqueInstance::new(gpu, choice.clone()))
            .collect::<Result<_>>()?;
        let mut timings: Vec<FrameTimings> = vec![];
        // Per measured frame, the techniques' counters.
        let mut frame_counters: Vec<Vec<(&'static str, f64)>> = vec![];
        let started = std::time::Instant::now();
        let mut i = 0;
        while i < warmup + frames {
            let out_of_time = counts
                .max_seconds
                .is_some_and(|s| started.elapsed().as_secs_f64() > s);
            if out_of_time && !timings.is_empty() {
                break;
            }
            if out_of_time && i < warmup {
                // Skip the rest of the warm-up: measure one frame.
                bar.inc((warmup - i) as u64);
                i = warmup;
            }
            let t = hf.render(gpu, scene, camera, lights, &settings)?;
            if i >= warmup {
                timings.push(t);
                frame_counters.push(
                    hf.techniques
                        .iter()
                        .flat_map(|t| t.technique.counters())
                        .collect(),
                );
            }
            bar.inc(1);
            i += 1;
        }
        bar.inc((warmup + frames - i) as u64);
        let gpu_stat = |f: fn(&crate::renderer::GpuPassTimes) -> f64| {
            let v: Option<Vec<f64>> = timings.iter().map(|t| t.gpu.as_ref().map(f)).collect();
            v.map(Stat::of)
        };
        let counters = counter_summary(&frame_counters);
        rows.push(BenchRow {
            technique: label,
            frame_ms: Stat::of(timings.iter().map(|t| t.total_ms).collect()),
            masks_ms: Stat::of(timings.iter().map(|t| t.masks_ms).collect()),
            gpu_frame_ms: gpu_stat(|g| g.total_ms),
            gpu_prepass_ms: gpu_stat(|g| g.prepass_ms),
            gpu_masks_ms: gpu_stat(|g| g.masks_ms),
            gpu_lighting_ms: gpu_stat(|g| g.lighting_ms),
            ratio_to_none: 0.0,
            triangles_drawn: hf.scene_gpu.triangle_count,
            caster_triangles: hf.scene_gpu.caster_triangle_count,
            shadow_resource_bytes: hf
                .techniques
                .iter()
                .map(|t| t.technique.resource_bytes())
                .sum(),
            counters,
            measured_frames: timings.len(),
        });
    }
    bar.finish_and_clear();
    let none_ms = rows
        .iter()
        .find(|r| r.technique.starts_with("none:"))
        .map(|r| r.frame_ms.median)
        .unwrap_or(f64::NAN);
    for r in &mut rows {
        r.ratio_to_none = r.frame_ms.median / none_ms;
    }
    let meta = serde_json::json!({
        "scene": scene.name,
        "size": {"width": size.0, "height": size.1},
        "camera": camera,
        "lights": lights,
        "warmup_frames": warmup,
        "measured_frames": frames,
        "adapter": gpu.adapter_summary(),
        "gpu_timestamps": gpu.timestamps,
    });
    std::fs::write(
        out.join("bench.json"),
        serde_json::to_string_pretty(&serde_json::json!({"meta": meta, "rows": rows}))?,
    )?;
    write_csv(&out.join("bench.csv"), &rows)?;
    std::fs::write(out.join("bench.md"), markdown(scene, &meta, &rows))?;
    Ok(rows)
}

fn opt(s: &Option<Stat>) -> String {
    s.map_or("-".into(), |s| format!("{:.2}", s.median))
}

/// `bench.csv`; a GPU time the adapter cannot measure is an empty field.
fn write_csv(path: &Path, rows: &[BenchRow]) -> Result<()> {
    let gpu = |s: &Option<Stat>| s.map_or(String::new(), |s| format!("{:.3}", s.median));
    super::write_csv(
        path,
        &[
            "technique",
            "frame_ms_median",
            "frame_ms_p5",
            "frame_ms_p95",
            "masks_ms_median",
            "gpu_frame_ms_median",
            "gpu_prepass_ms_median",
            "gpu_masks_ms_median",
            "gpu_lighting_ms_median",
            "ratio_to_none",
            "triangles_drawn",
            "caster_triangles",
            "shadow_resource_bytes",
        ],
        rows.iter().map(|r| {
            vec![
                r.technique.clone(),
                format!("{:.3}", r.frame_ms.median),
                format!("{:.3}", r.frame_ms.p5),
                format!("{:.3}", r.frame_ms.p95),
                format!("{:.3}", r.masks_ms.median),
                gpu(&r.gpu_frame_ms),
                gpu(&r.gpu_prepass_ms),
                gpu(&r.gpu_masks_ms),
                gpu(&r.gpu_lighting_ms),
                format!("{:.4}", r.ratio_to_none),
                r.triangles_drawn.to_string(),
                r.caster_triangles.to_string(),
                r.shadow_resource_bytes.to_string(),
            ]
        }),
    )
}

fn markdown(scene: &Scene, meta: &serde_json::Value, rows: &[BenchRow]) -> String {
    let mut s = format!(
        "# Timings on `{}`\n\n{} × {}, adapter {}, {} warm-up + {} measured frames. Frame = wall time (ms) of prepass + masks + lighting, each waited for; GPU = timestamp queries.\n\n",
        scene.name,
        meta["size"]["width"],
        meta["size"]["height"],
        meta["adapter"].as_str().unwrap_or(""),
        meta["warmup_frames"],
        meta["measured_frames"]
    );
    s += "| technique | frame median | p5 | p95 | masks (wall) | GPU frame | GPU prepass | GPU masks | GPU lighting | × none | triangles | casters | shadow bytes |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in rows {
        let _ = writeln!(
            s,
            "| `{}` | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} | {:.2} | {} | {} | {} |",
            r.technique,
            r.frame_ms.median,
            r.frame_ms.p5,
            r.frame_ms.p95,
            r.masks_ms.median,
            opt(&r.gpu_frame_ms),
            opt(&r.gpu_prepass_ms),
            opt(&r.gpu_masks_ms),
            opt(&r.gpu_lighting_ms),
            r.ratio_to_none,
            r.triangles_drawn,
            r.caster_triangles,
            r.shadow_resource_bytes
        );
    }
    s
}

/// [`BenchRow::counters`] from each measured frame's counters.
fn counter_summary(frames: &[Vec<(&'static str, f64)>]) -> Vec<(String, f64)> {
    let Some(last) = frames.last() else {
        return vec![];
    };
    last.iter()
        .enumerate()
        .map(|(i, &(name, value))| {
            let value = if name.ends_with("_ms") {
                // The same counter of each frame (same place, same name).
                let values = frames
                    .iter()
                    .filter_map(|f| f.get(i).filter(|c| c.0 == name));
                Stat::of(values.map(|c| c.1).collect()).median
            } else {
                value
            };
            (name.to_string(), value)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_a_known_series() {
        let s = Stat::of((1..=101).map(f64::from).collect());
        assert_eq!((s.median, s.p5, s.p95), (51.0, 6.0, 96.0));
        assert_eq!(Stat::of(vec![]).median, 0.0);
    }

    #[test]
    fn time_counters_are_medians_and_the_rest_the_last_frame() {
        let frames = [
            vec![("lookup_ms", 9.0), ("pages_rendered", 40.0)],
            vec![("lookup_ms", 1.0), ("pages_rendered", 0.0)],
            vec![("lookup_ms", 4.0), ("pages_rendered", 0.0)],
        ];
        assert_eq!(
            counter_summary(&frames),
            [
                ("lookup_ms".to_string(), 4.0),
                ("pages_rendered".to_string(), 0.0)
            ]
        );
        assert!(counter_summary(&[]).is_empty());
    }
}
