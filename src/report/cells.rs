//! One cell of the report: one technique preset on one view, its quality
//! against the reference and its cost, cached in `DIR/cells/` as JSON with
//! the binary's source hash and the cell's parameters, so that a second
//! run reuses it and a changed parameter recomputes only its own cells.

use super::matrix::{Matrix, View};
use crate::measure::bench::BenchRow;
use crate::measure::compare::QualityRow;
use crate::measure::flicker::FlickerRow;
use crate::measure::{self, choice_label, file_stem};
use crate::technique::TechniqueChoice;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The hash of every source file of this binary (build.rs).
pub const SOURCE_VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    "+",
    env!("SHADOWLAB_SOURCE_HASH")
);

/// What a cell was measured with: equal keys, equal measurements.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellKey {
    pub version: String,
    pub scene: String,
    pub camera: String,
    pub light: String,
    pub width: u32,
    pub height: u32,
    /// The technique's id with every parameter value.
    pub technique: String,
    pub reference: String,
    pub bench_frames: (u32, u32),
    /// The flicker path and its frames, when measured.
    pub flicker: Option<(String, u32)>,
}

/// Quality against the reference, over the considered pixels (means over
/// the lights of views with more than one, weighted by their pixels).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Quality {
    pub considered_pixels: usize,
    pub reference_shadowed_pct: f64,
    pub total_pct: f64,
    pub false_shadow_pct: f64,
    pub false_lit_pct: f64,
    pub edge_pct: f64,
    pub interior_pct: f64,
    pub interior_false_shadow_pct: f64,
    pub interior_false_lit_pct: f64,
    pub mean_abs_error: f64,
    /// Mean absolute error away from the reference's shadow edges.
    #[serde(default)]
    pub interior_mae: f64,
    /// % of the hard-reference interior pixels whose visibility is graded.
    #[serde(default)]
    pub graded_interior_pct: f64,
    pub flip_p99: f64,
    /// Screen pixels per map texel, 95th percentile (techniques with a map).
    pub footprint_p95: Option<f64>,
    /// Pixels whose shadow state changes between steps of the camera
    /// path, % of the considered pixels, and on shadow edges alone (when
    /// the matrix measures flicker; mean over the lights).
    pub flicker_pct: Option<f64>,
    pub edge_flicker_pct: Option<f64>,
}

/// Cost, from `bench` in one run with `none`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Cost {
    pub frame_ms: f64,
    pub ratio_to_none: f64,
    /// Wall time of the mask stage, waited for (CPU work included: the
    /// reference traces its rays on the CPU).
    pub mask_ms: f64,
    /// GPU time of the mask stage, where the adapter has timestamps.
    pub mask_gpu_ms: Option<f64>,
    /// Fragment and compute invocations of one frame's mask stage per
    /// pixel of the frame (pipeline statistics), where the adapter counts
    /// them: work that does not depend on the adapter.
    pub mask_fragments_per_px: Option<f64>,
    pub mask_compute_per_px: Option<f64>,
    pub shadow_bytes: u64,
    /// The technique's own counters (volume fragments, rays, pages…).
    pub counters: Vec<(String, f64)>,
    /// Frames the median is over (fewer for techniques past the time limit).
    pub frames: usize,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Cell {
    pub key: CellKey,
    /// Family id and preset name (`shadow-map`, `pcf`).
    pub family: String,
    pub preset: String,
    /// The view's light types (`point`, `spot`, `directional`) and whether
    /// one has an area (soft shadows).
    pub light_kinds: Vec<String>,
    pub area_light: bool,
    pub quality: Quality,
    pub cost: Cost,
    /// The technique's image and error heatmap, relative to the report's folder.
    pub image: String,
    pub heatmap: String,
}

impl Cell {
    pub fn view(&self) -> View {
        View::new(&self.key.scene, &self.key.camera, &self.key.light)
    }

    /// `family:preset` plus any changed parameter.
    pub fn technique(&self) -> &str {
        &self.key.technique
    }

    /// A stable anchor for links to this cell's row.
    pub fn anchor(&self) -> String {
        file_stem(&format!("{}-{}", self.view().label(), self.key.technique))
    }
}

impl Matrix {
    pub fn key(&self, view: &View, technique: &TechniqueChoice) -> CellKey {
        CellKey {
            version: SOURCE_VERSION.into(),
            scene: view.scene.clone(),
            camera: view.camera.clone(),
            light: view.light.clone(),
            width: self.size.0,
            height: self.size.1,
            technique: choice_label(technique),
            reference: choice_label(&self.reference),
            bench_frames: (self.bench.warmup, self.bench.measured),
            flicker: self
                .flicker
                .map(|(p, n)| (format!("{p:?}").to_lowercase(), n)),
        }
    }
}

/// The folder of a view's images and cells inside the report's folder.
pub fn view_dir(view: &View) -> PathBuf {
    PathBuf::from("cells").join(file_stem(&view.label().replace('/', "-")))
}

fn cell_path(root: &Path, key: &CellKey) -> PathBuf {
    root.join(view_dir(&View::new(&key.scene, &key.camera, &key.light)))
        .join(format!("{}.json", file_stem(&key.technique)))
}

/// The cached cell for `key`, if one was measured with the same key.
pub fn load(root: &Path, key: &CellKey) -> Option<Cell> {
    let text = std::fs::read_to_string(cell_path(root, key)).ok()?;
    let cell: Cell = serde_json::from_str(&text).ok()?;
    (cell.key == *key).then_some(cell)
}

pub fn store(root: &Path, cell: &Cell) -> Result<()> {
    write_whole(
        &cell_path(root, &cell.key),
        &serde_json::to_string_pretty(cell)?,
    )
}

/// Writes `text` to `path` whole or not at all: to a file beside it, then
/// renamed over it, so that a run stopped mid-write leaves no truncated
/// cell for the next run to discard (the report resumes stopped runs).
fn write_whole(path: &Path, text: &str) -> Result<()> {
    let partial = path.with_extension("partial");
    std::fs::write(&partial, text).with_context(|| format!("writing {}", partial.display()))?;
    std::fs::rename(&partial, path).with_context(|| format!("writing {}", path.display()))
}

/// A cell's `compare` rows, kept as soon as they are measured so that a
/// run stopped before the view's `bench` reuses them (`NAME.quality.json`
/// beside the cell).
#[derive(Serialize, Deserialize)]
struct MeasuredQuality {
    key: CellKey,
    rows: Vec<QualityRow>,
}

fn quality_path(root: &Path, key: &CellKey) -> PathBuf {
    cell_path(root, key).with_extension("quality.json")
}

/// The `compare` rows measured earlier for `key`, if any.
pub fn load_quality(root: &Path, key: &CellKey) -> Option<Vec<QualityRow>> {
    let text = std::fs::read_to_string(quality_path(root, key)).ok()?;
    let kept: MeasuredQuality = serde_json::from_str(&text).ok()?;
    (kept.key == *key).then_some(kept.rows)
}

pub fn store_quality(root: &Path, key: &CellKey, rows: &[QualityRow]) -> Result<()> {
    let path = quality_path(root, key);
    let kept = MeasuredQuality {
        key: key.clone(),
        rows: rows.to_vec(),
    };
    write_whole(&path, &serde_json::to_string_pretty(&kept)?)
}

/// The cell of `technique` from its `compare` rows (one per light), its
/// `bench` row and its flicker rows (empty when not measured).
pub fn from_rows(
    key: CellKey,
    technique: &TechniqueChoice,
    quality: &[&QualityRow],
    bench: &BenchRow,
    flicker: &[&FlickerRow],
    view_dir: &Path,
    frame_pixels: f64,
) -> Cell {
    let pixels: usize = quality.iter().map(|r| r.mask.considered_pixels).sum();
    let mean = |f: &dyn Fn(&QualityRow) -> f64| {
        if pixels == 0 {
            quality.iter().map(|r| f(r)).sum::<f64>() / quality.len().max(1) as f64
        } else {
            quality
                .iter()
                .map(|r| f(r) * r.mask.considered_pixels as f64)
                .sum::<f64>()
                / pixels as f64
        }
    };
    let footprints: Vec<f64> = quality
        .iter()
        .filter_map(|r| r.aliasing.map(|a| a.p95))
        .collect();
    let q = Quality {
        considered_pixels: pixels,
        reference_shadowed_pct: mean(&|r| r.mask.reference_shadowed_pct),
        total_pct: mean(&|r| r.mask.all.total_pct),
        false_shadow_pct: mean(&|r| r.mask.all.false_shadow_pct),
        false_lit_pct: mean(&|r| r.mask.all.false_lit_pct),
        edge_pct: mean(&|r| r.mask.edge.total_pct),
        interior_pct: mean(&|r| r.mask.interior.total_pct),
        interior_false_shadow_pct: mean(&|r| r.mask.interior.false_shadow_pct),
        interior_false_lit_pct: mean(&|r| r.mask.interior.false_lit_pct),
        mean_abs_error: mean(&|r| r.mask.mean_abs_error),
        interior_mae: mean(&|r| r.mask.interior_mae),
        graded_interior_pct: mean(&|r| r.mask.graded_interior_pct),
        flip_p99: quality.first().map_or(0.0, |r| r.flip.p99),
        footprint_p95: footprints.into_iter().reduce(f64::max),
        flicker_pct: (!flicker.is_empty())
            .then(|| flicker.iter().map(|r| r.flicker_pct).sum::<f64>() / flicker.len() as f64),
        edge_flicker_pct: (!flicker.is_empty()).then(|| {
            flicker.iter().map(|r| r.edge_flicker_pct).sum::<f64>() / flicker.len() as f64
        }),
    };
    let first = quality.first();
    let rel = |name: Option<&String>| {
        name.map_or(String::new(), |n| {
            view_dir.join(n).to_string_lossy().replace('\\', "/")
        })
    };
    Cell {
        key,
        family: technique.family.id.into(),
        preset: technique.preset.to_string(),
        light_kinds: vec![],
        area_light: false,
        quality: q,
        cost: Cost {
            frame_ms: bench.frame_ms.median,
            ratio_to_none: bench.ratio_to_none,
            mask_ms: bench.masks_ms.median,
            mask_gpu_ms: bench.gpu_masks_ms.map(|s| s.median),
            mask_fragments_per_px: bench
                .work
                .map(|w| w.masks.fragment_invocations as f64 / frame_pixels),
            mask_compute_per_px: bench
                .work
                .map(|w| w.masks.compute_invocations as f64 / frame_pixels),
            shadow_bytes: bench.shadow_resource_bytes,
            counters: bench.counters.clone(),
            frames: bench.measured_frames,
        },
        image: rel(first.map(|r| &r.image)),
        heatmap: rel(first.map(|r| &r.heatmap)),
    }
}

/// The columns of `results.csv` and of the HTML results table, formatted
/// once so that both show the same figures.
pub const COLUMNS: [&str; 27] = [
    "scene",
    "camera",
    "light",
    "technique",
    "family",
    "total_pct",
    "false_shadow_pct",
    "false_lit_pct",
    "edge_pct",
    "interior_pct",
    "interior_false_shadow_pct",
    "interior_false_lit_pct",
    "mean_abs_error",
    "interior_mae",
    "graded_interior_pct",
    "flip_p99",
    "footprint_p95_px",
    "flicker_pct",
    "edge_flicker_pct",
    "frame_ms",
    "ratio_to_none",
    "mask_ms",
    "mask_gpu_ms",
    "mask_fragments_per_px",
    "mask_compute_per_px",
    "shadow_bytes",
    "counters",
];

/// A cell's values in [`COLUMNS`]' order.
pub fn csv_row(c: &Cell) -> Vec<String> {
    let q = &c.quality;
    let pct = |v: f64| format!("{v:.3}");
    vec![
        c.key.scene.clone(),
        c.key.camera.clone(),
        c.key.light.clone(),
        c.key.technique.clone(),
        c.family.clone(),
        pct(q.total_pct),
        pct(q.false_shadow_pct),
        pct(q.false_lit_pct),
        pct(q.edge_pct),
        pct(q.interior_pct),
        pct(q.interior_false_shadow_pct),
        pct(q.interior_false_lit_pct),
        format!("{:.4}", q.mean_abs_error),
        format!("{:.4}", q.interior_mae),
        pct(q.graded_interior_pct),
        format!("{:.4}", q.flip_p99),
        q.footprint_p95.map_or(String::new(), |v| format!("{v:.2}")),
        q.flicker_pct.map_or(String::new(), |v| format!("{v:.4}")),
        q.edge_flicker_pct
            .map_or(String::new(), |v| format!("{v:.4}")),
        format!("{:.2}", c.cost.frame_ms),
        format!("{:.2}", c.cost.ratio_to_none),
        format!("{:.2}", c.cost.mask_ms),
        c.cost
            .mask_gpu_ms
            .map_or(String::new(), |v| format!("{v:.2}")),
        c.cost
            .mask_fragments_per_px
            .map_or(String::new(), |v| format!("{v:.2}")),
        c.cost
            .mask_compute_per_px
            .map_or(String::new(), |v| format!("{v:.2}")),
        c.cost.shadow_bytes.to_string(),
        c.cost
            .counters
            .iter()
            .map(|(k, v)| format!("{k}={v:.1}"))
            .collect::<Vec<_>>()
            .join(" "),
    ]
}

/// `results.csv` and `results.json`.
pub fn write_results(root: &Path, matrix: &Matrix, cells: &[Cell]) -> Result<()> {
    measure::write_csv(
        &root.join("results.csv"),
        &COLUMNS,
        cells.iter().map(csv_row),
    )?;
    let json = serde_json::json!({
        "version": SOURCE_VERSION,
        "size": {"width": matrix.size.0, "height": matrix.size.1},
        "reference": choice_label(&matrix.reference),
        "views": matrix.views.iter().map(View::label).collect::<Vec<_>>(),
        "cells": cells,
    });
    std::fs::write(
        root.join("results.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    Ok(())
}
