//! `shadowlab report`: the comparison of [001] §5.2 measured — every
//! technique preset on a matrix of views, against the ray-traced reference
//! (`compare`) and against `none` (`bench`), written as one self-contained
//! `index.html` (inline SVG charts by `plotters`, embedded images),
//! `report.md`, `results.csv` and `results.json`. Cells are cached in the
//! output folder (`cells`), so a run resumes where the last one stopped.

pub mod cells;
mod charts;
pub mod criteria;
mod html;
mod markdown;
pub mod matrix;
pub mod pareto;
pub mod summary;

use crate::gpu::GpuContext;
use crate::measure;
use crate::renderer::RenderSettings;
use crate::scene::{self, Scene};
use anyhow::{Context, Result};
use cells::Cell;
use matrix::{Matrix, View};
use std::path::Path;
use std::time::Instant;

/// What a run did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunStats {
    /// Cells measured by this run.
    pub computed: usize,
    /// Cells taken from the folder's cache.
    pub reused: usize,
    /// Cells measured by this run whose `compare` rows a stopped run had
    /// kept (only their `bench` was measured again).
    pub quality_kept: usize,
}

impl RunStats {
    /// `N cells measured (K from the compare rows a stopped run kept), R
    /// reused`, the kept part only when there are some.
    pub fn counts(&self) -> String {
        let kept = match self.quality_kept {
            0 => String::new(),
            n => format!(" ({n} from the compare rows a stopped run kept)"),
        };
        format!(
            "{} cells measured{kept}, {} reused",
            self.computed, self.reused
        )
    }
}

/// Measures what `matrix` asks that `out` does not hold yet, then writes
/// the report from every cell.
pub fn run(gpu: &GpuContext, matrix: &Matrix, out: &Path, progress: bool) -> Result<RunStats> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let total = matrix.views.len() * matrix.techniques.len();
    let bar = measure::progress_bar(
        progress,
        total as u64,
        "{msg:>32} [{bar:30}] {pos}/{len} cells, {elapsed} elapsed, {eta} left",
    );
    let started = Instant::now();
    let mut stats = RunStats::default();
    let mut all: Vec<Cell> = vec![];
    let mut loaded: Option<Scene> = None;
    for view in &matrix.views {
        bar.set_message(view.label());
        let mut cached = vec![];
        let mut missing = vec![];
        for t in &matrix.techniques {
            match cells::load(out, &matrix.key(view, t)) {
                Some(c) => cached.push(c),
                None => missing.push(t.clone()),
            }
        }
        stats.reused += cached.len();
        bar.inc(cached.len() as u64);
        if !missing.is_empty() {
            if loaded.as_ref().is_none_or(|s| s.name != view.scene) {
                loaded = Some(scene::load(&view.scene)?);
            }
            let scene = loaded.as_ref().expect("loaded above");
            let fresh = measure_view(gpu, scene, matrix, view, &missing, out, &mut stats)?;
            stats.computed += fresh.len();
            bar.inc(fresh.len() as u64);
            cached.extend(fresh);
        }
        // The matrix's order, whatever came from the cache.
        for t in &matrix.techniques {
            let key = matrix.key(view, t);
            if let Some(i) = cached.iter().position(|c| c.key == key) {
                all.push(cached.swap_remove(i));
            }
        }
    }
    bar.finish_and_clear();
    cells::write_results(out, matrix, &all)?;
    let report = summary::Report::new(matrix, &all, gpu.adapter_summary(), gpu.is_cpu_adapter());
    std::fs::create_dir_all(out.join("charts"))?;
    for i in 0..report.fronts.len() {
        std::fs::write(
            out.join(markdown::chart_name(i)),
            charts::pareto_svg(&report, i)?,
        )?;
    }
    std::fs::write(out.join("report.md"), markdown::write(&report))?;
    std::fs::write(out.join("index.html"), html::write(&report, out)?)?;
    log::info!(
        "report: {}, {:.0} s",
        stats.counts(),
        started.elapsed().as_secs_f64()
    );
    Ok(stats)
}

/// Measures `techniques` on `view`: `compare` against the reference (each
/// technique's rows kept as soon as measured, and those kept by a stopped
/// run reused), then `bench` with `none` in the same run; stores and
/// returns their cells.
fn measure_view(
    gpu: &GpuContext,
    scene: &Scene,
    matrix: &Matrix,
    view: &View,
    techniques: &[crate::technique::TechniqueChoice],
    out: &Path,
    stats: &mut RunStats,
) -> Result<Vec<Cell>> {
    let camera = scene.camera_preset(&view.camera)?;
    let lights = scene.light_preset(&view.light)?;
    let rel = cells::view_dir(view);
    let dir = out.join(&rel);
    let request = measure::FrameRequest {
        scene,
        camera: &camera,
        lights: &lights,
        size: matrix.size,
    };
    let mut quality = vec![];
    // The point-sampled reference's comparison and, for sub-pixel
    // techniques, the supersampled one's (in `sub-pixel/`), each made when
    // first needed, with the rows measured against it.
    let references = [false, true].map(|sub| matrix.reference(sub));
    let dirs = [dir.clone(), dir.join("sub-pixel")];
    let mut comparisons: [Option<(measure::compare::Comparison, Vec<_>)>; 2] = [None, None];
    for t in techniques {
        let key = matrix.key(view, t);
        if let Some(rows) = cells::load_quality(out, &key) {
            stats.quality_kept += 1;
            quality.extend(rows);
            continue;
        }
        let sub = measure::is_sub_pixel(t) as usize;
        if comparisons[sub].is_none() {
            let c = measure::compare::Comparison::new(gpu, request, &references[sub], &dirs[sub])?;
            comparisons[sub] = Some((c, vec![]));
        }
        let (comparison, measured) = comparisons[sub].as_mut().expect("made above");
        let mut rows = comparison.measure(t)?;
        measured.extend(rows.iter().cloned());
        // The cells name their images from the view's folder.
        if sub == 1 {
            for r in &mut rows {
                r.image = format!("sub-pixel/{}", r.image);
                r.heatmap = format!("sub-pixel/{}", r.heatmap);
            }
        }
        cells::store_quality(out, &key, &rows)?;
        quality.extend(rows);
    }
    for (c, rows) in comparisons.iter().flatten() {
        c.write_tables(rows)?;
    }
    let bench = measure::bench::run(
        gpu,
        request,
        &RenderSettings::default(),
        techniques,
        matrix.bench,
        &dir.join("bench"),
    )?;
    let flicker = match matrix.flicker {
        Some((path, frames)) => measure::flicker::run(
            gpu,
            request,
            techniques,
            &matrix.reference,
            path,
            frames,
            &dir.join("flicker"),
        )?,
        None => vec![],
    };
    let light_kinds: Vec<String> = lights
        .iter()
        .map(|l| format!("{:?}", l.kind).to_lowercase())
        .collect();
    let area = lights.iter().any(|l| l.area.is_some());
    let mut fresh = vec![];
    for t in techniques {
        let label = measure::choice_label(t);
        let rows: Vec<&measure::compare::QualityRow> =
            quality.iter().filter(|r| r.technique == label).collect();
        let b = bench
            .iter()
            .find(|r| r.technique == label)
            .with_context(|| format!("bench has no row for {label}"))?;
        let shimmer: Vec<&measure::flicker::FlickerRow> =
            flicker.iter().filter(|r| r.technique == label).collect();
        let pixels = matrix.size.0 as f64 * matrix.size.1 as f64;
        let mut cell = cells::from_rows(matrix.key(view, t), t, &rows, b, &shimmer, &rel, pixels);
        cell.light_kinds = light_kinds.clone();
        cell.area_light = area;
        cells::store(out, &cell)?;
        fresh.push(cell);
    }
    Ok(fresh)
}
