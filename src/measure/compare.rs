//! `shadowlab compare`: every technique on the same frame against the
//! `raytraced` reference, over pixels that show shadow-receiving geometry
//! facing the light (N·L > 0).

use super::quality::{self, FlipStats, FootprintStats, MaskMetrics, SeamStats};
use super::{FrameRequest, choice_label, file_stem};
use crate::gpu::GpuContext;
use crate::headless::{self, FrameImages, HeadlessFrame};
use crate::renderer::RenderSettings;
use crate::scene::{Light, Scene};
use crate::technique::TechniqueInstance;
use crate::technique::{MapLookup, TechniqueChoice};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// One technique's quality for one light.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct QualityRow {
    pub technique: String,
    pub light: usize,
    pub mask: MaskMetrics,
    /// The same over pixels on a receiver plane (see `scene::planes::receiver_planes`)...
    pub on_planes: MaskMetrics,
    /// ...and over the other pixels.
    pub off_planes: MaskMetrics,
    pub flip: FlipStats,
    /// Screen pixels per shadow-map texel over the considered pixels
    /// (techniques with a map).
    pub aliasing: Option<FootprintStats>,
    /// Mismatch near the borders between the map's cascades or faces
    /// against elsewhere (maps with more than one partition in view).
    pub seams: Option<SeamStats>,
    pub frame_ms: f64,
    pub image: String,
    pub heatmap: String,
}

/// Pixels whose visible surface lies on one of the scene's receiver planes.
pub fn plane_pixels(gpu: &GpuContext, hf: &HeadlessFrame, scene: &Scene) -> Result<Vec<bool>> {
    let planes = crate::scene::planes::receiver_planes(scene);
    let tol = scene.bounds().size().length().max(1e-3) * 1e-4;
    let pos = gpu.read_texture(hf.frame.gbuffer_position(), 0, 16)?;
    Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&pos)
        .iter()
        .map(|p| {
            p[3] > 0.5
                && planes.iter().any(|pl| {
                    pl.equation
                        .dot(glam::Vec4::new(p[0], p[1], p[2], 1.0))
                        .abs()
                        <= tol
                })
        })
        .collect())
}

/// The world positions of the frame's G-buffer (`w` > 0.5 where a surface
/// was drawn), one per pixel.
pub fn gbuffer_positions(gpu: &GpuContext, hf: &HeadlessFrame) -> Result<Vec<[f32; 4]>> {
    let bytes = gpu.read_texture(hf.frame.gbuffer_position(), 0, 16)?;
    Ok(bytemuck::cast_slice(&bytes).to_vec())
}

/// Per light, the pixels that count: geometry drawn that receives shadows
/// and that the light's direct light reaches (facing it, inside a spot's
/// cone, within range).
pub fn considered_pixels(
    gpu: &GpuContext,
    hf: &HeadlessFrame,
    lights: &[Light],
) -> Result<Vec<Vec<bool>>> {
    considered_at(gpu, hf, &gbuffer_positions(gpu, hf)?, lights)
}

/// [`considered_pixels`] for the frame's G-buffer positions `pos`, already
/// read back ([`gbuffer_positions`]).
pub fn considered_at(
    gpu: &GpuContext,
    hf: &HeadlessFrame,
    pos: &[[f32; 4]],
    lights: &[Light],
) -> Result<Vec<Vec<bool>>> {
    let nrm = gpu.read_texture(hf.frame.gbuffer_normal(), 0, 8)?;
    Ok(quality::considered_from_gbuffer(
        pos,
        bytemuck::cast_slice(&nrm),
        lights,
    ))
}

/// What one technique renders for `compare`: its frame, the frame's time,
/// and per light where it looked up its map (when it has one).
struct Rendered {
    images: FrameImages,
    ms: f64,
    lookups: Vec<Option<MapLookup>>,
}

/// Renders one frame of `view` with `choice` for every light; `debug` turns
/// the techniques' debug views on (they carry the map lookups).
fn render_with(
    gpu: &GpuContext,
    hf: &mut HeadlessFrame,
    view: FrameRequest,
    settings: &RenderSettings,
    choice: &TechniqueChoice,
    debug: bool,
) -> Result<Rendered> {
    let FrameRequest {
        scene,
        camera,
        lights,
        ..
    } = view;
    hf.techniques = TechniqueInstance::per_light(gpu, choice, lights.len())?;
    for t in &mut hf.techniques {
        t.technique.enable_debug(debug);
    }
    let t = hf.render(gpu, scene, camera, lights, settings)?;
    let lookups = hf.techniques[..lights.len()]
        .iter()
        .map(|t| t.technique.map_lookup(gpu))
        .collect::<Result<_>>()?;
    Ok(Rendered {
        images: headless::read_back(gpu, &hf.frame, lights.len())?,
        ms: t.total_ms,
        lookups,
    })
}

/// Renders the reference and every technique, writes images, heatmaps and
/// `quality.{md,csv,json}` into `out`, and returns the rows.
pub fn run(
    gpu: &GpuContext,
    view: FrameRequest,
    techniques: &[TechniqueChoice],
    reference: &TechniqueChoice,
    out: &Path,
) -> Result<Vec<QualityRow>> {
    let mut comparison = Comparison::new(gpu, view, reference, out)?;
    let mut rows = vec![];
    for choice in techniques {
        rows.extend(comparison.measure(choice)?);
    }
    comparison.write_tables(&rows)?;
    Ok(rows)
}

/// One frame's reference, rendered once, against which techniques are
/// measured one at a time (so a caller can keep each one's rows as soon as
/// they are measured).
pub struct Comparison<'a> {
    gpu: &'a GpuContext,
    view: FrameRequest<'a>,
    reference: &'a TechniqueChoice,
    out: &'a Path,
    settings: RenderSettings,
    hf: HeadlessFrame,
    reference_images: FrameImages,
    reference_ms: f64,
    /// Per light: the pixels that count, and the reference's edge band.
    considered: Vec<Vec<bool>>,
    edges: Vec<Vec<bool>>,
    /// Pixels on one of the scene's receiver planes.
    on_plane: Vec<bool>,
}

impl<'a> Comparison<'a> {
    /// Renders the reference into `out` and finds the pixels that count.
    pub fn new(
        gpu: &'a GpuContext,
        view: FrameRequest<'a>,
        reference: &'a TechniqueChoice,
        out: &'a Path,
    ) -> Result<Comparison<'a>> {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        if view.lights.is_empty() {
            log::warn!("scene has no light: every technique is trivially exact");
        }
        let settings = RenderSettings {
            show_light_icons: false,
            ..Default::default()
        };
        let (w, h) = view.size;
        let mut hf = HeadlessFrame::new(gpu, view.scene, std::slice::from_ref(reference), w, h)?;
        let (scene, lights) = (view.scene, view.lights);
        let reference_render = render_with(gpu, &mut hf, view, &settings, reference, false)?;
        headless::write_images(&out.join("reference"), &reference_render.images)?;
        let considered = considered_pixels(gpu, &hf, lights)?;
        let edges = considered
            .iter()
            .zip(&reference_render.images.masks)
            .map(|(cons, mask)| {
                quality::edge_band(w as usize, h as usize, cons, mask, quality::EDGE_RADIUS)
            })
            .collect();
        let on_plane = plane_pixels(gpu, &hf, scene)?;
        Ok(Comparison {
            gpu,
            view,
            reference,
            out,
            settings,
            hf,
            reference_images: reference_render.images,
            reference_ms: reference_render.ms,
            considered,
            edges,
            on_plane,
        })
    }

    /// Renders `choice`, writes its image and heatmaps, and returns its rows
    /// (one per light).
    pub fn measure(&mut self, choice: &TechniqueChoice) -> Result<Vec<QualityRow>> {
        let FrameRequest {
            lights,
            size: (w, h),
            ..
        } = self.view;
        let label = choice_label(choice);
        let stem = file_stem(&label);
        let rendered = render_with(
            self.gpu,
            &mut self.hf,
            self.view,
            &self.settings,
            choice,
            true,
        )?;
        let img = &rendered.images;
        let reference = &self.reference_images;
        let image_name = format!("{stem}.png");
        image::save_buffer(
            self.out.join(&image_name),
            &img.color,
            w,
            h,
            image::ExtendedColorType::Rgba8,
        )?;
        let flip = quality::flip(&reference.color, &img.color, w, h);
        let mut rows = vec![];
        for (li, cons) in self.considered.iter().enumerate() {
            let metrics = |c: &[bool]| {
                quality::mask_metrics(
                    w as usize,
                    h as usize,
                    c,
                    &reference.masks[li],
                    &img.masks[li],
                )
            };
            let split = |want: bool| -> Vec<bool> {
                cons.iter()
                    .zip(&self.on_plane)
                    .map(|(&c, &p)| c && p == want)
                    .collect()
            };
            let heat =
                quality::heatmap(&reference.color, cons, &reference.masks[li], &img.masks[li]);
            let heat_name = if lights.len() > 1 {
                format!("heatmap-{stem}-light{li}.png")
            } else {
                format!("heatmap-{stem}.png")
            };
            image::save_buffer(
                self.out.join(&heat_name),
                &heat,
                w,
                h,
                image::ExtendedColorType::Rgba8,
            )?;
            let lookup = rendered.lookups[li].as_ref();
            let aliasing = lookup.and_then(|l| quality::footprint_stats(cons, &l.footprint));
            let seams = lookup.and_then(|l| {
                quality::seam_stats(
                    w as usize,
                    h as usize,
                    cons,
                    &l.partition,
                    &reference.masks[li],
                    &self.edges[li],
                    &img.masks[li],
                )
            });
            rows.push(QualityRow {
                technique: label.clone(),
                light: li,
                aliasing,
                seams,
                mask: metrics(cons),
                on_planes: metrics(&split(true)),
                off_planes: metrics(&split(false)),
                flip,
                frame_ms: rendered.ms,
                image: image_name.clone(),
                heatmap: heat_name,
            });
        }
        Ok(rows)
    }

    /// Writes `quality.{json,csv,md}` of `rows` (measured by this
    /// comparison or by an earlier one of the same frame).
    pub fn write_tables(&self, rows: &[QualityRow]) -> Result<()> {
        let view = self.view;
        let meta = serde_json::json!({
            "scene": view.scene.name,
            "size": {"width": view.size.0, "height": view.size.1},
            "camera": view.camera,
            "lights": view.lights,
            "reference": choice_label(self.reference),
            "reference_frame_ms": self.reference_ms,
            "adapter": self.gpu.adapter_summary(),
            "pixels": format!("considered = geometry that receives shadows with its geometric normal facing the light (N·L > 0); percentages are of considered pixels; edge = within {} px of a reference shadow boundary", quality::EDGE_RADIUS),
        });
        let out = self.out;
        std::fs::write(
            out.join("quality.json"),
            serde_json::to_string_pretty(&serde_json::json!({"meta": meta, "rows": rows}))?,
        )?;
        write_csv(&out.join("quality.csv"), rows)?;
        std::fs::write(out.join("quality.md"), markdown(view.scene, &meta, rows))?;
        Ok(())
    }
}

/// `quality.csv`.
fn write_csv(path: &Path, rows: &[QualityRow]) -> Result<()> {
    let pct = |v: f64| format!("{v:.4}");
    let err = |v: f64| format!("{v:.5}");
    let footprint = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.3}"));
    super::write_csv(
        path,
        &[
            "technique",
            "light",
            "considered_pixels",
            "reference_shadowed_pct",
            "false_shadow_pct",
            "false_lit_pct",
            "total_pct",
            "edge_false_shadow_pct",
            "edge_false_lit_pct",
            "interior_false_shadow_pct",
            "interior_false_lit_pct",
            "mean_abs_error",
            "rms_error",
            "interior_mae",
            "graded_interior_pct",
            "fractional_mae",
            "flip_mean",
            "flip_p95",
            "flip_p99",
            "footprint_mean_px",
            "footprint_p95_px",
            "footprint_max_px",
            "seam_pixels",
            "seam_mismatch_pct",
            "elsewhere_mismatch_pct",
            "seam_same_partitions_pct",
            "seam_at_edges_pct",
            "elsewhere_at_edges_pct",
            "seam_interior_pct",
            "elsewhere_interior_pct",
            "frame_ms",
        ],
        rows.iter().map(|r| {
            let m = &r.mask;
            vec![
                r.technique.clone(),
                r.light.to_string(),
                m.considered_pixels.to_string(),
                pct(m.reference_shadowed_pct),
                pct(m.all.false_shadow_pct),
                pct(m.all.false_lit_pct),
                pct(m.all.total_pct),
                pct(m.edge.false_shadow_pct),
                pct(m.edge.false_lit_pct),
                pct(m.interior.false_shadow_pct),
                pct(m.interior.false_lit_pct),
                err(m.mean_abs_error),
                err(m.rms_error),
                err(m.interior_mae),
                pct(m.graded_interior_pct),
                m.fractional_mae.map_or(String::new(), err),
                err(r.flip.mean),
                err(r.flip.p95),
                err(r.flip.p99),
                footprint(r.aliasing.map(|a| a.mean)),
                footprint(r.aliasing.map(|a| a.p95)),
                footprint(r.aliasing.map(|a| a.max)),
                r.seams.map_or(String::new(), |s| s.seam_pixels.to_string()),
                r.seams.map_or(String::new(), |s| pct(s.seam_mismatch_pct)),
                r.seams
                    .map_or(String::new(), |s| pct(s.elsewhere_mismatch_pct)),
                r.seams
                    .map_or(String::new(), |s| pct(s.same_partitions_pct)),
                r.seams.map_or(String::new(), |s| pct(s.seam_at_edges_pct)),
                r.seams
                    .map_or(String::new(), |s| pct(s.elsewhere_at_edges_pct)),
                r.seams.map_or(String::new(), |s| pct(s.seam_interior_pct)),
                r.seams
                    .map_or(String::new(), |s| pct(s.elsewhere_interior_pct)),
                format!("{:.2}", r.frame_ms),
            ]
        }),
    )
}

fn markdown(scene: &Scene, meta: &serde_json::Value, rows: &[QualityRow]) -> String {
    let mut s = format!(
        "# Quality on `{}` against `{}`\n\n{} × {}, adapter {}. Mismatch at visibility 0.5, in % of considered pixels ({}); interior MAE: mean absolute error of the pixels farther than {} px from a reference shadow edge; graded interior: of those where the reference is exactly lit or shadowed, the % with visibility strictly between {} and {}; fractional MAE: the interior MAE where the reference itself lies strictly between them (light through translucent casters, penumbrae).\n\n",
        scene.name,
        meta["reference"].as_str().unwrap_or(""),
        meta["size"]["width"],
        meta["size"]["height"],
        meta["adapter"].as_str().unwrap_or(""),
        meta["pixels"].as_str().unwrap_or(""),
        quality::EDGE_RADIUS,
        quality::GRADED_LOW,
        quality::GRADED_HIGH
    );
    s += "| technique | light | ref. shadowed % | false shadow % | false lit % | total % | edge FS % | edge FL % | interior FS % | interior FL % | MAE | RMSE | interior MAE | graded interior % | fractional MAE | FLIP mean | FLIP p95 | FLIP p99 | px/texel mean | p95 | max |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    let px = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.2}"));
    for r in rows {
        let m = &r.mask;
        let _ = writeln!(
            s,
            "| `{}` | {} | {:.2} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} | {:.4} | {:.4} | {:.2} | {} | {:.4} | {:.4} | {:.4} | {} | {} | {} |",
            r.technique,
            r.light,
            m.reference_shadowed_pct,
            m.all.false_shadow_pct,
            m.all.false_lit_pct,
            m.all.total_pct,
            m.edge.false_shadow_pct,
            m.edge.false_lit_pct,
            m.interior.false_shadow_pct,
            m.interior.false_lit_pct,
            m.mean_abs_error,
            m.rms_error,
            m.interior_mae,
            m.graded_interior_pct,
            m.fractional_mae
                .map_or("–".to_string(), |e| format!("{e:.4}")),
            r.flip.mean,
            r.flip.p95,
            r.flip.p99,
            px(r.aliasing.map(|a| a.mean)),
            px(r.aliasing.map(|a| a.p95)),
            px(r.aliasing.map(|a| a.max))
        );
    }
    if rows.iter().any(|r| r.seams.is_some()) {
        s += &format!(
            "\nSeams: mismatch within {} px of a border between the map's cascades or faces, against elsewhere (% of each region's considered pixels); against what the band's pixels would show at their own partition's rate outside the band (same partitions); and both regions split at {} px from the reference's shadow edges (cascade borders lie far off, where shadow edges crowd: at edges compares like with like, interior shows bands of acne or light).\n\n",
            quality::SEAM_RADIUS,
            quality::EDGE_RADIUS
        );
        s += "| technique | light | seam pixels | seam mismatch % | elsewhere % | ratio | same partitions % | ratio | seam at edges % | elsewhere at edges % | ratio | seam interior % | elsewhere interior % |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        let ratio = |of: f64, to: f64| {
            if to > 0.0 {
                format!("{:.2}", of / to)
            } else {
                "–".into()
            }
        };
        for r in rows {
            if let Some(seam) = r.seams {
                let _ = writeln!(
                    s,
                    "| `{}` | {} | {} | {:.3} | {:.3} | {} | {:.3} | {} | {:.3} | {:.3} | {} | {:.3} | {:.3} |",
                    r.technique,
                    r.light,
                    seam.seam_pixels,
                    seam.seam_mismatch_pct,
                    seam.elsewhere_mismatch_pct,
                    ratio(seam.seam_mismatch_pct, seam.elsewhere_mismatch_pct),
                    seam.same_partitions_pct,
                    ratio(seam.seam_mismatch_pct, seam.same_partitions_pct),
                    seam.seam_at_edges_pct,
                    seam.elsewhere_at_edges_pct,
                    ratio(seam.seam_at_edges_pct, seam.elsewhere_at_edges_pct),
                    seam.seam_interior_pct,
                    seam.elsewhere_interior_pct
                );
            }
        }
    }
    s += "\nSplit by receiver planes (the scene's ShadowPlane objects, else its largest planar receiver); % of the pixels of each region.\n\n";
    s += "| technique | light | plane pixels | plane FS % | plane FL % | plane total % | plane edge % | other pixels | other FS % | other FL % | other total % | other edge % |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in rows {
        let (p, o) = (&r.on_planes, &r.off_planes);
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
            r.technique,
            r.light,
            p.considered_pixels,
            p.all.false_shadow_pct,
            p.all.false_lit_pct,
            p.all.total_pct,
            p.edge.total_pct,
            o.considered_pixels,
            o.all.false_shadow_pct,
            o.all.false_lit_pct,
            o.all.total_pct,
            o.edge.total_pct
        );
    }
    s
}
