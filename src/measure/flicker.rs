//! `shadowlab compare --path NAME --frames N`: shimmer, measured. The camera
//! follows a short deterministic path. For each step, the surface points
//! seen from the earlier camera are held fixed and every technique renders
//! its mask there twice: with its light views fitted to the earlier camera
//! and to the later one. A point flickers when its shadow state (visibility
//! at 0.5) differs between the two: the shadow moved on the surface because
//! the map moved with the camera — what stabilisation removes. The
//! reference's state at a fixed point never changes, so every change is the
//! technique's. Only points the later camera still sees count: a point
//! hidden behind a nearer surface (or out of the frame) one step later is
//! not on screen in both frames, so it cannot be seen to flicker — the
//! reprojection test of temporal methods. Reported per technique and light
//! as the mean over the path's steps, in % of the considered pixels, and
//! over the reference's shadow edges (2 px band) alone.

use super::compare::{considered_at, gbuffer_positions};
use super::quality::{EDGE_RADIUS, edge_band};
use super::{FrameRequest, choice_label, percent, write_csv};
use crate::gpu::GpuContext;
use crate::headless::{self, HeadlessFrame};
use crate::renderer::{FrameCameras, RenderSettings};
use crate::scene::Camera;
use crate::technique::TechniqueChoice;
use anyhow::{Context, Result, bail};
use glam::{Quat, Vec3, Vec4Swizzles};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// A camera path, one small step per frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum CameraPath {
    /// Forward along the view direction.
    Dolly,
    /// Sideways, to the camera's right.
    Strafe,
    /// Turning left about the up vector, in place.
    Turn,
    /// Around the target, about the up vector.
    Orbit,
}

/// Dolly and strafe step: this fraction of the eye–target distance.
pub const MOVE_STEP: f32 = 0.0025;
/// Turn and orbit step, degrees.
pub const TURN_STEP_DEG: f32 = 0.1;

/// The camera at frame `frame` of `path` from `start`.
pub fn path_camera(start: &Camera, path: CameraPath, frame: u32) -> Camera {
    let f = frame as f32;
    let to_target = start.target - start.eye;
    let forward = to_target.normalize();
    let right = forward.cross(start.up).normalize();
    let step = to_target.length() * MOVE_STEP * f;
    let spin = Quat::from_axis_angle(start.up.normalize(), (TURN_STEP_DEG * f).to_radians());
    match path {
        CameraPath::Dolly => Camera {
            eye: start.eye + forward * step,
            target: start.target + forward * step,
            ..*start
        },
        CameraPath::Strafe => Camera {
            eye: start.eye + right * step,
            target: start.target + right * step,
            ..*start
        },
        CameraPath::Turn => Camera {
            target: start.eye + spin * to_target,
            ..*start
        },
        CameraPath::Orbit => Camera {
            eye: start.target - spin * to_target,
            ..*start
        },
    }
}

/// One technique's flicker for one light along the path.
#[derive(Clone, Debug, Serialize)]
pub struct FlickerRow {
    pub technique: String,
    pub light: usize,
    /// Mean over the path's steps of the flickering pixels, % of the
    /// considered pixels.
    pub flicker_pct: f64,
    /// The same over the reference's shadow edges.
    pub edge_flicker_pct: f64,
    /// Per step, `flicker_pct`'s terms.
    pub per_step_pct: Vec<f64>,
    /// Per step, the technique's counters after the frame of that step's
    /// camera (a virtual map's pages rendered and cached, …).
    pub per_step_counters: Vec<Vec<(&'static str, f64)>>,
}

/// How far (relative view depth) a point may lie behind the surface the
/// later camera sees there and still count as that surface: rounding of
/// the stored positions, not geometry.
const SEEN_DEPTH_TOLERANCE: f32 = 1e-3;

/// Which of `positions` (world positions, `w` > 0.5 where a surface was
/// seen, one per pixel of a `width`-wide frame) the camera `later` still
/// sees, given the world positions `later_positions` of its own frame of
/// the same size: the point projects into the frame and is not behind all
/// of the 2×2 surface samples around where it lands (a nearer surface
/// there hides it; background or a farther sample means it is in view).
pub fn seen_from(
    positions: &[[f32; 4]],
    later: &Camera,
    later_positions: &[[f32; 4]],
    width: usize,
) -> Vec<bool> {
    let height = positions.len() / width.max(1);
    let view = later.view();
    let view_proj = later.projection(width as f32 / height as f32) * view;
    let depth = |p: Vec3| -view.transform_point3(p).z;
    positions
        .iter()
        .map(|p| {
            if p[3] <= 0.5 {
                return false;
            }
            let point = Vec3::new(p[0], p[1], p[2]);
            let clip = view_proj * point.extend(1.0);
            if clip.w <= 0.0 {
                return false;
            }
            let ndc = clip.xy() / clip.w;
            if ndc.x.abs() > 1.0 || ndc.y.abs() > 1.0 {
                return false;
            }
            let x = (ndc.x * 0.5 + 0.5) * width as f32 - 0.5;
            let y = (0.5 - ndc.y * 0.5) * height as f32 - 0.5;
            let (x0, y0) = (x.floor().max(0.0) as usize, y.floor().max(0.0) as usize);
            let mut farthest = 0.0f32;
            for yi in y0..=(y0 + 1).min(height - 1) {
                for xi in x0..=(x0 + 1).min(width - 1) {
                    let q = later_positions[yi * width + xi];
                    if q[3] <= 0.5 {
                        return true;
                    }
                    farthest = farthest.max(depth(Vec3::new(q[0], q[1], q[2])));
                }
            }
            depth(point) <= farthest * (1.0 + SEEN_DEPTH_TOLERANCE)
        })
        .collect()
}

/// Flicker of one step: of the `considered` pixels, the percentage whose
/// shadow state differs between the masks `before` and `after` (the same
/// surface points), over all of them and over the `edges`.
pub fn step_flicker(
    considered: &[bool],
    before: &[f32],
    after: &[f32],
    edges: &[bool],
) -> (f64, f64) {
    let (mut n, mut flicker, mut edge_n, mut edge_flicker) = (0usize, 0usize, 0usize, 0usize);
    for i in 0..considered.len() {
        if !considered[i] {
            continue;
        }
        let flickers = (before[i] < 0.5) != (after[i] < 0.5);
        n += 1;
        flicker += flickers as usize;
        if edges[i] {
            edge_n += 1;
            edge_flicker += flickers as usize;
        }
    }
    (percent(flicker, n), percent(edge_flicker, edge_n))
}

/// Follows `frames` frames of `path` with the reference and every
/// technique, writes `flicker.{md,csv,json}` into `out` and returns the rows.
/// The path starts at `view`'s camera.
pub fn run(
    gpu: &GpuContext,
    view: FrameRequest,
    techniques: &[TechniqueChoice],
    reference: &TechniqueChoice,
    path: CameraPath,
    frames: u32,
    out: &Path,
) -> Result<Vec<FlickerRow>> {
    let FrameRequest {
        scene,
        camera: start,
        lights,
        size,
    } = view;
    if !(2..=1000).contains(&frames) {
        bail!("--frames {frames}: a path needs 2 to 1000 frames");
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let cameras: Vec<Camera> = (0..frames).map(|f| path_camera(start, path, f)).collect();
    for c in &cameras {
        c.validate()?;
    }
    let settings = RenderSettings {
        show_light_icons: false,
        ..Default::default()
    };
    let (w, h) = (size.0 as usize, size.1 as usize);
    let frame_of = |choice: &TechniqueChoice| {
        let choices = vec![choice.clone(); lights.len().max(1)];
        HeadlessFrame::new(gpu, scene, &choices, size.0, size.1)
    };
    // Per camera: the surface positions; per step: the considered pixels
    // (seen from both cameras) and the reference's edges, per light.
    let mut reference_frame = frame_of(reference)?;
    let mut positions = vec![];
    let mut considered = vec![];
    let mut edges = vec![];
    for (frame, camera) in cameras.iter().enumerate() {
        reference_frame.render(gpu, scene, camera, lights, &settings)?;
        positions.push(gbuffer_positions(gpu, &reference_frame)?);
        if frame + 1 == cameras.len() {
            break;
        }
        let cons = considered_at(gpu, &reference_frame, &positions[frame], lights)?;
        let images = headless::read_back(gpu, &reference_frame.frame, lights.len())?;
        edges.push(
            cons.iter()
                .zip(&images.masks)
                .map(|(c, m)| edge_band(w, h, c, m, EDGE_RADIUS))
                .collect::<Vec<_>>(),
        );
        considered.push(cons);
    }
    let hidden_pct = keep_seen(&mut considered, &positions, &cameras, w);
    let mut rows = vec![];
    for choice in techniques {
        let mut hf = frame_of(choice)?;
        let mut per_light: Vec<(Vec<f64>, Vec<f64>)> = vec![(vec![], vec![]); lights.len()];
        let mut counters: Vec<Vec<Vec<(&'static str, f64)>>> = vec![vec![]; lights.len()];
        for step in 0..cameras.len() - 1 {
            let view = &cameras[step];
            let mut masks = vec![];
            for fit in [view, &cameras[step + 1]] {
                hf.render_fitted(gpu, scene, FrameCameras { view, fit }, lights, &settings)?;
                masks.push(headless::read_back(gpu, &hf.frame, lights.len())?.masks);
                if std::ptr::eq(fit, view) {
                    for (li, c) in counters.iter_mut().enumerate() {
                        c.push(hf.techniques[li].technique.counters());
                    }
                }
            }
            for (li, (all, edge)) in per_light.iter_mut().enumerate() {
                let (a, e) = step_flicker(
                    &considered[step][li],
                    &masks[0][li],
                    &masks[1][li],
                    &edges[step][li],
                );
                all.push(a);
                edge.push(e);
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        for ((li, (all, edge)), per_step_counters) in
            per_light.into_iter().enumerate().zip(counters)
        {
            rows.push(FlickerRow {
                technique: choice_label(choice),
                light: li,
                flicker_pct: mean(&all),
                edge_flicker_pct: mean(&edge),
                per_step_pct: all,
                per_step_counters,
            });
        }
    }
    let meta = serde_json::json!({
        "scene": scene.name,
        "size": {"width": size.0, "height": size.1},
        "path": path,
        "frames": frames,
        "move_step": format!("{MOVE_STEP} of the eye–target distance per frame"),
        "turn_step_deg": TURN_STEP_DEG,
        "start_camera": start,
        "lights": lights,
        "reference": choice_label(reference),
        "adapter": gpu.adapter_summary(),
        "pixels": "per step, the surface points seen from the earlier camera are held fixed; a pixel flickers when the technique's shadow state (visibility < 0.5) there differs between light views fitted to the earlier and to the later camera; % of considered pixels (receiving, N·L > 0, still seen by the later camera), mean over the steps; edge = within 2 px of a reference shadow boundary",
        "hidden_pct_per_step": hidden_pct,
    });
    write_tables(out, &meta, path, &rows)?;
    Ok(rows)
}

/// Per step, keeps the considered pixels whose surface point the later
/// camera still sees; returns the % of surface points hidden per step.
fn keep_seen(
    considered: &mut [Vec<Vec<bool>>],
    positions: &[Vec<[f32; 4]>],
    cameras: &[Camera],
    w: usize,
) -> Vec<f64> {
    let mut hidden_pct = vec![];
    for (step, cons) in considered.iter_mut().enumerate() {
        let seen = seen_from(
            &positions[step],
            &cameras[step + 1],
            &positions[step + 1],
            w,
        );
        let surface = positions[step].iter().filter(|p| p[3] > 0.5).count();
        hidden_pct.push(percent(
            surface - seen.iter().filter(|s| **s).count(),
            surface,
        ));
        for c in cons.iter_mut() {
            c.iter_mut().zip(&seen).for_each(|(c, s)| *c &= *s);
        }
    }
    hidden_pct
}

/// `flicker.{json,csv,md}` of `rows`, described by `meta`.
fn write_tables(
    out: &Path,
    meta: &serde_json::Value,
    path: CameraPath,
    rows: &[FlickerRow],
) -> Result<()> {
    let text = |key: &str| meta[key].as_str().unwrap_or("").to_string();
    std::fs::write(
        out.join("flicker.json"),
        serde_json::to_string_pretty(&serde_json::json!({"meta": meta, "rows": rows}))?,
    )?;
    write_csv(
        &out.join("flicker.csv"),
        &["technique", "light", "flicker_pct", "edge_flicker_pct"],
        rows.iter().map(|r| {
            vec![
                r.technique.clone(),
                r.light.to_string(),
                format!("{:.4}", r.flicker_pct),
                format!("{:.4}", r.edge_flicker_pct),
            ]
        }),
    )?;
    let mut md = format!(
        "# Flicker on `{}` along `{:?}` ({} frames) against `{}`\n\n{} × {}, adapter {}. {}.\n\n| technique | light | flicker % | edge flicker % |\n|---|---:|---:|---:|\n",
        text("scene"),
        path,
        meta["frames"],
        text("reference"),
        meta["size"]["width"],
        meta["size"]["height"],
        text("adapter"),
        text("pixels")
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| `{}` | {} | {:.4} | {:.4} |",
            r.technique, r.light, r.flicker_pct, r.edge_flicker_pct
        );
    }
    // Counters that change along the path, per step.
    for r in rows {
        let Some(first) = r.per_step_counters.first() else {
            continue;
        };
        for (i, (name, _)) in first.iter().enumerate() {
            let values: Vec<f64> = r
                .per_step_counters
                .iter()
                .filter_map(|c| c.get(i).map(|v| v.1))
                .collect();
            if values.iter().any(|v| *v != values[0]) {
                let list: Vec<String> = values.iter().map(|v| format!("{v}")).collect();
                let _ = writeln!(
                    md,
                    "\n`{}` light {}, `{name}` per step: {}",
                    r.technique,
                    r.light,
                    list.join(", ")
                );
            }
        }
    }
    std::fs::write(out.join("flicker.md"), md)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn camera() -> Camera {
        Camera::new(Vec3::new(0.0, 2.0, 10.0), Vec3::new(0.0, 2.0, 0.0))
    }

    #[test]
    fn paths_step_as_documented() {
        let c = camera();
        assert_eq!(path_camera(&c, CameraPath::Dolly, 0).eye, c.eye);
        let d = path_camera(&c, CameraPath::Dolly, 4);
        assert!((d.eye - Vec3::new(0.0, 2.0, 10.0 - 4.0 * 10.0 * MOVE_STEP)).length() < 1e-5);
        assert!(((d.target - d.eye).length() - 10.0).abs() < 1e-4);
        let s = path_camera(&c, CameraPath::Strafe, 2);
        assert!(
            (s.eye - Vec3::new(2.0 * 10.0 * MOVE_STEP, 2.0, 10.0)).length() < 1e-5,
            "{}",
            s.eye
        );
        let t = path_camera(&c, CameraPath::Turn, 10);
        assert_eq!(t.eye, c.eye);
        let angle = (t.target - t.eye)
            .angle_between(c.target - c.eye)
            .to_degrees();
        assert!((angle - 10.0 * TURN_STEP_DEG).abs() < 1e-3, "{angle}");
        let o = path_camera(&c, CameraPath::Orbit, 10);
        assert_eq!(o.target, c.target);
        assert!(((o.eye - o.target).length() - 10.0).abs() < 1e-4);
    }

    /// The plane z = `z` seen through each pixel centre of a `w`×`h` frame.
    fn plane_positions(c: &Camera, w: usize, h: usize, z: f32) -> Vec<[f32; 4]> {
        let inverse = (c.projection(w as f32 / h as f32) * c.view()).inverse();
        (0..w * h)
            .map(|i| {
                let ndc_x = ((i % w) as f32 + 0.5) / w as f32 * 2.0 - 1.0;
                let ndc_y = 1.0 - ((i / w) as f32 + 0.5) / h as f32 * 2.0;
                let on_ray = inverse.project_point3(Vec3::new(ndc_x, ndc_y, 0.5));
                let dir = on_ray - c.eye;
                let p = c.eye + dir * ((z - c.eye.z) / dir.z);
                [p.x, p.y, p.z, 1.0]
            })
            .collect()
    }

    #[test]
    fn points_count_only_where_the_later_camera_still_sees_them() {
        let (w, h) = (8, 6);
        let c = camera();
        let wall = plane_positions(&c, w, h, 0.0);
        assert!(seen_from(&wall, &c, &wall, w).iter().all(|s| *s));
        // A nearer surface in front of every pixel hides the wall.
        let screen = plane_positions(&c, w, h, 1.0);
        assert!(seen_from(&wall, &c, &screen, w).iter().all(|s| !*s));
        // A farther surface or background does not.
        let far = plane_positions(&c, w, h, -1.0);
        assert!(seen_from(&wall, &c, &far, w).iter().all(|s| *s));
        let sky = vec![[0.0; 4]; w * h];
        assert!(seen_from(&wall, &c, &sky, w).iter().all(|s| *s));
        // Points out of the later frame, behind the camera, or no surface.
        let turned = Camera {
            target: c.eye + Vec3::X,
            ..c
        };
        assert!(seen_from(&wall, &turned, &wall, w).iter().all(|s| !*s));
        let mut odd = wall.clone();
        odd[0] = [0.0, 2.0, 20.0, 1.0];
        odd[1][3] = 0.0;
        let seen = seen_from(&odd, &c, &wall, w);
        assert!(!seen[0] && !seen[1] && seen[2]);
    }

    #[test]
    fn a_pixel_flickers_when_its_shadow_state_changes() {
        let considered = [true, true, true, false];
        let before = [0.0, 1.0, 0.4, 0.0];
        let after = [1.0, 1.0, 0.45, 1.0];
        let edges = [true, false, true, false];
        // Pixel 0 changes; 1 and 2 keep their state; 3 is not considered.
        let (all, edge) = step_flicker(&considered, &before, &after, &edges);
        assert!((all - 100.0 / 3.0).abs() < 1e-9, "{all}");
        assert_eq!(edge, 50.0);
        assert_eq!(
            step_flicker(&[false; 4], &before, &after, &edges),
            (0.0, 0.0)
        );
    }
}
