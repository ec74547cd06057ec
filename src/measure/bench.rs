//! `shadowlab bench`: frame and pass timings per technique on one frame:
//! warm-up frames, then N measured frames; median, p5, p95; GPU timestamps
//! per pass where the adapter has them, CPU wall time always (each stage
//! waits for the GPU, so CPU-side technique work is included); each
//! technique's frame time as a ratio to `none` measured in the same run,
//! the measured frames taken round-robin so that no technique pays for its
//! place in the order.

use super::{FrameRequest, choice_label};
use crate::gpu::{FrameWork, GpuContext, StageWork};
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
    /// The 5th and 95th percentiles of the ratio of each round's frame to
    /// `none`'s frame of the same round (the frames are measured
    /// round-robin): how far one ratio can be trusted.
    pub ratio_spread: (f64, f64),
    pub triangles_drawn: usize,
    pub caster_triangles: usize,
    pub shadow_resource_bytes: u64,
    /// The techniques' counters: times (names ending in `_ms`) as the
    /// median over the measured frames, the rest as of the last frame.
    pub counters: Vec<(String, f64)>,
    /// Frames measured (fewer than asked when `max_seconds` ran out).
    pub measured_frames: usize,
    /// Invocation counts of one frame after the warm-up, per stage
    /// (pipeline-statistics queries; `None` where the adapter has none).
    pub work: Option<FrameWork>,
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
pub fn run(
    gpu: &GpuContext,
    view: FrameRequest,
    base: &RenderSettings,
    techniques: &[TechniqueChoice],
    counts: BenchFrames,
    out: &Path,
) -> Result<Vec<BenchRow>> {
    let FrameRequest {
        scene,
        camera,
        lights,
        size,
    } = view;
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
    // One frame (scene upload, targets) for every technique; each has its
    // own instances, swapped in for its frames.
    let mut hf = HeadlessFrame::new(gpu, scene, &list[..1], size.0, size.1)?;
    // The shared frame's own first frames (its passes' pipelines, llvmpipe's
    // shader compiles) are nobody's cost: run them before anything is timed,
    // or the first technique — `none`, the baseline — pays for them.
    for _ in 0..warmup.max(1) {
        hf.render(gpu, scene, camera, lights, &settings)?;
    }
    let mut series = list
        .iter()
        .map(|choice| Series::new(gpu, choice, lights.len()))
        .collect::<Result<Vec<_>>>()?;
    // Every technique's warm-up first, then the measured frames round-robin
    // (frame k of each technique in turn, the order turned by one each
    // round): a drift of the machine's speed over the run (caches, clocks,
    // the allocator) falls on every technique alike, whatever its place.
    for s in &mut series {
        bar.set_message(s.label.clone());
        s.render_frames(
            &mut hf,
            (gpu, scene, camera, lights, &settings),
            warmup,
            &counts,
            FrameUse::Warmup,
        )?;
        bar.inc(warmup as u64);
    }
    // One counted frame each, outside the timed ones (the queries cost).
    if gpu.pipeline_statistics {
        let untimed = BenchFrames {
            max_seconds: None,
            ..counts
        };
        for s in &mut series {
            let inputs = (gpu, scene, camera, lights, &settings);
            let work =
                gpu.count_work(|| s.render_frames(&mut hf, inputs, 1, &untimed, FrameUse::Warmup))?;
            s.work = Some(work);
        }
    }
    let n = series.len();
    // A pipeline made while measuring is a compile in a timed frame: the
    // technique's own (a pipeline per bias cap it has not met yet), or the
    // device's cache evicting what the other techniques of the run need.
    let created_before = gpu.cache.pipelines_created();
    for round in 0..frames as usize {
        for k in 0..n {
            let s = &mut series[(k + round) % n];
            if !s.done {
                bar.set_message(s.label.clone());
                s.render_frames(
                    &mut hf,
                    (gpu, scene, camera, lights, &settings),
                    1,
                    &counts,
                    FrameUse::Measured,
                )?;
            }
            bar.inc(1);
        }
    }
    let compiled = gpu.cache.pipelines_created() - created_before;
    if compiled > 0 {
        log::warn!(
            "bench: {compiled} pipeline(s) compiled during the measured frames of `{}`; their frames include the compile",
            view.scene.name
        );
    }
    let per_round: Vec<Vec<f64>> = series
        .iter()
        .map(|s| s.timings.iter().map(|t| t.total_ms).collect())
        .collect();
    bar.finish_and_clear();
    let none = series.iter().position(|s| s.label.starts_with("none:"));
    let mut rows: Vec<BenchRow> = series.into_iter().map(|s| s.row(&hf)).collect();
    set_ratios_to_none(&mut rows, &per_round, none);
    write_tables(gpu, view, (warmup, frames, compiled), &rows, out)?;
    Ok(rows)
}

/// `bench.{json,csv,md}` of `rows` measured on `view` with `warmup` and
/// `measured` frames per technique, `compiled` pipelines made while
/// measuring.
fn write_tables(
    gpu: &GpuContext,
    view: FrameRequest,
    (warmup, measured, compiled): (u32, u32, u64),
    rows: &[BenchRow],
    out: &Path,
) -> Result<()> {
    let meta = serde_json::json!({
        "scene": view.scene.name,
        "size": {"width": view.size.0, "height": view.size.1},
        "camera": view.camera,
        "lights": view.lights,
        "warmup_frames": warmup,
        "measured_frames": measured,
        "pipelines_compiled_while_measuring": compiled,
        "adapter": gpu.adapter_summary(),
        "cpu_adapter": gpu.is_cpu_adapter(),
        "gpu_timestamps": gpu.timestamps,
        "pipeline_statistics": gpu.pipeline_statistics,
        "depth_format": format!("{:?}", gpu.depth_format),
    });
    std::fs::write(
        out.join("bench.json"),
        serde_json::to_string_pretty(&serde_json::json!({"meta": meta, "rows": rows}))?,
    )?;
    write_csv(&out.join("bench.csv"), rows)?;
    std::fs::write(out.join("bench.md"), markdown(view.scene, &meta, rows))?;
    Ok(())
}

/// Each row's median frame over `none`'s (row `none`), and the 5th–95th
/// percentile of the ratio of the same round's frames.
fn set_ratios_to_none(rows: &mut [BenchRow], per_round: &[Vec<f64>], none: Option<usize>) {
    let none_frames: Vec<f64> = none.map(|i| per_round[i].clone()).unwrap_or_default();
    let none_ms = Stat::of(none_frames.clone()).median;
    for (r, frames) in rows.iter_mut().zip(per_round) {
        r.ratio_to_none = r.frame_ms.median / none_ms;
        let ratios: Vec<f64> = frames
            .iter()
            .zip(&none_frames)
            .map(|(t, n)| t / n)
            .collect();
        let spread = Stat::of(ratios);
        r.ratio_spread = (spread.p5, spread.p95);
    }
}

/// One technique's instances and measured frames in a round-robin run.
struct Series {
    label: String,
    instances: Vec<crate::technique::TechniqueInstance>,
    timings: Vec<FrameTimings>,
    /// Per measured frame, the techniques' counters.
    frame_counters: Vec<Vec<(&'static str, f64)>>,
    /// Wall time spent in this technique's frames so far.
    spent: std::time::Duration,
    /// Out of time ([`BenchFrames::max_seconds`]): no more frames.
    done: bool,
    work: Option<FrameWork>,
}

/// Whether a bench frame is a warm-up (not kept) or measured.
#[derive(Clone, Copy, PartialEq, Eq)]
enum FrameUse {
    Warmup,
    Measured,
}

/// What every frame of a bench renders with.
type FrameInputs<'a> = (
    &'a GpuContext,
    &'a Scene,
    &'a Camera,
    &'a [Light],
    &'a RenderSettings,
);

impl Series {
    fn new(gpu: &GpuContext, choice: &TechniqueChoice, lights: usize) -> Result<Series> {
        Ok(Series {
            label: choice_label(choice),
            instances: crate::technique::TechniqueInstance::per_light(gpu, choice, lights)?,
            timings: vec![],
            frame_counters: vec![],
            spent: Default::default(),
            done: false,
            work: None,
        })
    }

    /// Renders `n` frames of this technique in `hf` (its instances swapped
    /// in), their timings kept when they are measured. Past `max_seconds` of its own
    /// frames it stops: a warm-up is cut short, and measuring ends after at
    /// least one measured frame.
    fn render_frames(
        &mut self,
        hf: &mut HeadlessFrame,
        (gpu, scene, camera, lights, settings): FrameInputs,
        n: u32,
        counts: &BenchFrames,
        kind: FrameUse,
    ) -> Result<()> {
        std::mem::swap(&mut hf.techniques, &mut self.instances);
        let result = (|| {
            for _ in 0..n {
                let out_of_time = counts
                    .max_seconds
                    .is_some_and(|s| self.spent.as_secs_f64() > s);
                if out_of_time && (kind == FrameUse::Warmup || !self.timings.is_empty()) {
                    self.done = kind == FrameUse::Measured;
                    break;
                }
                let started = std::time::Instant::now();
                let t = hf.render(gpu, scene, camera, lights, settings)?;
                self.spent += started.elapsed();
                if kind == FrameUse::Measured {
                    self.timings.push(t);
                    self.frame_counters.push(
                        hf.techniques
                            .iter()
                            .flat_map(|t| t.technique.counters())
                            .collect(),
                    );
                }
            }
            Ok(())
        })();
        std::mem::swap(&mut hf.techniques, &mut self.instances);
        result
    }

    fn row(self, hf: &HeadlessFrame) -> BenchRow {
        let timings = &self.timings;
        let gpu_stat = |f: fn(&crate::renderer::GpuPassTimes) -> f64| {
            let v: Option<Vec<f64>> = timings.iter().map(|t| t.gpu.as_ref().map(f)).collect();
            v.map(Stat::of)
        };
        BenchRow {
            technique: self.label,
            frame_ms: Stat::of(timings.iter().map(|t| t.total_ms).collect()),
            masks_ms: Stat::of(timings.iter().map(|t| t.masks_ms).collect()),
            gpu_frame_ms: gpu_stat(|g| g.total_ms),
            gpu_prepass_ms: gpu_stat(|g| g.prepass_ms),
            gpu_masks_ms: gpu_stat(|g| g.masks_ms),
            gpu_lighting_ms: gpu_stat(|g| g.lighting_ms),
            ratio_to_none: 0.0,
            ratio_spread: (0.0, 0.0),
            triangles_drawn: hf.scene_gpu.triangle_count,
            caster_triangles: hf.scene_gpu.caster_triangle_count,
            shadow_resource_bytes: self
                .instances
                .iter()
                .map(|t| t.technique.resource_bytes())
                .sum(),
            counters: counter_summary(&self.frame_counters),
            measured_frames: timings.len(),
            work: self.work,
        }
    }
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
            "ratio_p5",
            "ratio_p95",
            "triangles_drawn",
            "caster_triangles",
            "shadow_resource_bytes",
            "masks_vertex_invocations",
            "masks_fragment_invocations",
            "masks_compute_invocations",
            "masks_clipper_primitives",
            "frame_fragment_invocations",
        ],
        rows.iter().map(|r| {
            let work = |f: fn(&FrameWork) -> u64| {
                r.work.as_ref().map_or(String::new(), |w| f(w).to_string())
            };
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
                format!("{:.4}", r.ratio_spread.0),
                format!("{:.4}", r.ratio_spread.1),
                r.triangles_drawn.to_string(),
                r.caster_triangles.to_string(),
                r.shadow_resource_bytes.to_string(),
                work(|w| w.masks.vertex_invocations),
                work(|w| w.masks.fragment_invocations),
                work(|w| w.masks.compute_invocations),
                work(|w| w.masks.clipper_primitives),
                work(FrameWork::fragment_invocations),
            ]
        }),
    )
}

fn markdown(scene: &Scene, meta: &serde_json::Value, rows: &[BenchRow]) -> String {
    let mut s = format!(
        "# Timings on `{}`\n\n{} × {}, adapter {}, {} warm-up + {} measured frames, the measured ones round-robin across the techniques; {} pipeline(s) compiled during the measured frames. Frame = wall time (ms) of prepass + masks + lighting, each waited for; GPU = timestamp queries; × none: median frame over `none`'s, and the 5th–95th percentile of the ratio of each round's frames. Work: invocations of one frame's mask stage per pixel of the frame (pipeline-statistics queries), the same on any adapter.{}\n\n",
        scene.name,
        meta["size"]["width"],
        meta["size"]["height"],
        meta["adapter"].as_str().unwrap_or(""),
        meta["warmup_frames"],
        meta["measured_frames"],
        meta["pipelines_compiled_while_measuring"],
        if meta["cpu_adapter"].as_bool() == Some(true) {
            " **The adapter is a CPU rasterizer: its times rank techniques as a CPU does (filling pixels is cheap beside a GPU's, depth-only passes are not); the work columns do not depend on it.**"
        } else {
            ""
        }
    );
    let pixels = meta["size"]["width"].as_f64().unwrap_or(1.0)
        * meta["size"]["height"].as_f64().unwrap_or(1.0);
    let per_px = |r: &BenchRow, f: fn(&StageWork) -> u64| {
        r.work.as_ref().map_or("–".into(), |w| {
            format!("{:.2}", f(&w.masks) as f64 / pixels)
        })
    };
    s += "| technique | frame median | p5 | p95 | masks (wall) | GPU frame | GPU prepass | GPU masks | GPU lighting | × none | × none p5–p95 | masks fragments/px | masks vertices/px | masks compute/px | triangles | casters | shadow bytes |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in rows {
        let _ = writeln!(
            s,
            "| `{}` | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} | {:.2} | {:.2}–{:.2} | {} | {} | {} | {} | {} | {} |",
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
            r.ratio_spread.0,
            r.ratio_spread.1,
            per_px(r, |w| w.fragment_invocations),
            per_px(r, |w| w.vertex_invocations),
            per_px(r, |w| w.compute_invocations),
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
