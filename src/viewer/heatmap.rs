//! The viewer's heatmap: the selected light's mask against `raytraced`,
//! computed from the frame's G-buffer on a background thread so that the
//! view keeps running, then shown as an egui texture.

use super::App;
use crate::scene::{Light, Scene};
use anyhow::Result;
use std::sync::mpsc;

/// A heatmap against `raytraced` computed on a background thread.
pub struct Heatmap {
    pub texture: egui::TextureHandle,
    pub summary: String,
}

impl App {
    /// Starts the heatmap of the selected light's mask against `raytraced`
    /// on a background thread (reads back the frame first).
    pub(super) fn start_heatmap(&mut self) {
        let (Some(gfx), Some(scene)) = (&self.gfx, &self.scene) else {
            return;
        };
        let Some(frame) = &gfx.frame else { return };
        let li = self
            .state
            .selected_light
            .min(scene.lights.len().saturating_sub(1));
        let Some(light) = scene.lights.get(li).copied() else {
            return;
        };
        let read = || -> Result<FrameData> {
            Ok(FrameData {
                width: frame.width() as usize,
                height: frame.height() as usize,
                positions: gfx.gpu.read_texture(frame.gbuffer_position(), 0, 16)?,
                normals: gfx.gpu.read_texture(frame.gbuffer_normal(), 0, 8)?,
                mask: gfx.gpu.read_texture(frame.masks(), li as u32, 2)?,
                color: frame.read_color_rgba(&gfx.gpu)?,
                camera: *frame.uniform(),
            })
        };
        let data = match read() {
            Ok(d) => d,
            Err(e) => {
                self.state.error = Some(format!("{e:#}"));
                return;
            }
        };
        let scene_arc = scene.scene.clone();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(heatmap_job(&scene_arc, &light, &data));
        });
        self.state.heatmap_job = Some(rx);
    }

    /// Takes the heatmap from its thread once it has arrived.
    pub(super) fn poll_heatmap(&mut self) {
        let Some(gfx) = &self.gfx else { return };
        if let Some(rx) = &self.state.heatmap_job {
            match rx.try_recv() {
                Ok(Ok((img, summary))) => {
                    let texture =
                        gfx.egui_ctx
                            .load_texture("heatmap", img, egui::TextureOptions::LINEAR);
                    if let Some(at) = self.heatmap_started_at.take() {
                        println!(
                            "heatmap: {summary} ({} frames rendered while it was computed)",
                            self.frames_rendered - at
                        );
                        self.heatmap_reported = true;
                    }
                    self.state.heatmap = Some(Heatmap { texture, summary });
                    self.state.heatmap_job = None;
                }
                Ok(Err(e)) => {
                    self.state.error = Some(e);
                    self.state.heatmap_job = None;
                }
                Err(mpsc::TryRecvError::Empty) => {}
                Err(mpsc::TryRecvError::Disconnected) => self.state.heatmap_job = None,
            }
        }
    }
}

/// G-buffer, one light's mask and the colour image of a frame, read back.
struct FrameData {
    width: usize,
    height: usize,
    positions: Vec<u8>,
    normals: Vec<u8>,
    mask: Vec<u8>,
    color: Vec<u8>,
    /// The frame's camera and size (its uniform).
    camera: crate::frame::FrameUniform,
}

/// The work of the heatmap thread.
fn heatmap_job(
    scene: &Scene,
    light: &Light,
    data: &FrameData,
) -> Result<(egui::ColorImage, String), String> {
    let (w, h) = (data.width, data.height);
    let (pos, nrm, mask, color) = (&data.positions, &data.normals, &data.mask, &data.color);
    use crate::technique::raytraced::ReferenceSettings;
    let test: Vec<f32> = bytemuck::cast_slice::<u8, half::f16>(mask)
        .iter()
        .map(|v| v.to_f32())
        .collect();
    let settings = ReferenceSettings::defaults();
    let bvh = settings
        .casters(scene, None)
        .map_err(|e| format!("{e:#}"))?;
    let reference = settings.mask_from_gbuffer_bytes(&bvh, light, (pos, nrm), &data.camera);
    let considered = crate::measure::quality::considered_from_gbuffer(
        bytemuck::cast_slice(pos),
        bytemuck::cast_slice(nrm),
        std::slice::from_ref(light),
    )
    .remove(0);
    let m = crate::measure::quality::mask_metrics(w, h, &considered, &reference, &test);
    let rgba = crate::measure::quality::heatmap(color, &considered, &reference, &test);
    let summary = format!(
        "false shadow {:.3} %, false lit {:.3} % (edge {:.3} %, interior {:.3} %), MAE {:.4}, interior MAE {:.4}, graded interior {:.2} %",
        m.all.false_shadow_pct,
        m.all.false_lit_pct,
        m.edge.total_pct,
        m.interior.total_pct,
        m.mean_abs_error,
        m.interior_mae,
        m.graded_interior_pct
    );
    Ok((
        egui::ColorImage::from_rgba_unmultiplied([w, h], &rgba),
        summary,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, shapes};
    use crate::technique::raytraced::{PixelSampling, ReferenceSettings, mask_from_gbuffer};
    use glam::{Mat4, Vec3};

    /// A floor at y = 30 and a box whose top edge, under a sun 3° above the
    /// horizon, casts a shadow boundary onto the floor; a one-row G-buffer
    /// of floor points across that boundary, 0.5 mm apart.
    fn grazing_boundary() -> (Scene, Light, Vec<[f32; 4]>, Vec<Vec3>) {
        let mut s = Scene::new("grazing");
        let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
        let floor = s.add_mesh(shapes::plane(20.0, 20.0, 2));
        s.add_object(
            "Floor",
            floor,
            grey,
            Mat4::from_translation(Vec3::new(0.0, 30.0, 0.0)),
        );
        let cube = s.add_mesh(shapes::cuboid(Vec3::new(0.2, 0.1, 4.0)));
        s.add_object(
            "Box",
            cube,
            grey,
            Mat4::from_translation(Vec3::new(0.0, 30.0, 0.0)),
        );
        let angle = 3f32.to_radians();
        let light = Light::directional(Vec3::new(angle.cos(), -angle.sin(), 0.0), 1.0);
        s.lights = vec![light];
        s.finalize().unwrap();
        // The box's top edge at x = 0.1, height 0.05: the boundary lies
        // 0.05 / tan 3° past it.
        let boundary = 0.1 + 0.05 / angle.tan();
        let positions: Vec<[f32; 4]> = (0..400)
            .map(|i| [boundary - 0.1 + i as f32 * 0.0005, 30.0, 0.0, 1.0])
            .collect();
        let normals = vec![Vec3::Y; positions.len()];
        (s, light, positions, normals)
    }

    /// The heatmap measures a technique against the reference as `compare`
    /// does, with the reference's own ray offset: the ray-traced mask itself
    /// shows no error, although a different offset (the 512 ULPs once
    /// hard-coded here) moves this boundary by several samples.
    #[test]
    fn the_heatmap_uses_the_reference_settings() {
        let (scene, light, positions, normals) = grazing_boundary();
        let settings = ReferenceSettings::defaults();
        let bvh = settings.casters(&scene, None).unwrap();
        let centre = &PixelSampling::CENTRE;
        let ulps = settings.offset_ulps;
        let mask = mask_from_gbuffer(&bvh, &light, &positions, &normals, 1, ulps, centre);
        let other = mask_from_gbuffer(&bvh, &light, &positions, &normals, 1, 512.0, centre);
        let moved = mask.iter().zip(&other).filter(|(a, b)| a != b).count();
        assert!(moved >= 5, "a 512-ULP offset moves {moved} samples");
        assert!(mask.contains(&0.0) && mask.contains(&1.0));
        let f16s = |v: &[f32]| -> Vec<u8> {
            v.iter()
                .flat_map(|x| half::f16::from_f32(*x).to_le_bytes())
                .collect()
        };
        let data = FrameData {
            width: positions.len(),
            height: 1,
            positions: bytemuck::cast_slice(&positions).to_vec(),
            normals: f16s(
                &normals
                    .iter()
                    .flat_map(|n| [n.x, n.y, n.z, 1.0])
                    .collect::<Vec<_>>(),
            ),
            mask: f16s(&mask),
            color: vec![128; positions.len() * 4],
            camera: crate::frame::FrameUniform {
                size: glam::Vec4::new(positions.len() as f32, 1.0, 0.0, 0.0),
                ..bytemuck::Zeroable::zeroed()
            },
        };
        let (_, summary) = heatmap_job(&scene, &light, &data).unwrap();
        assert!(
            summary.starts_with("false shadow 0.000 %, false lit 0.000 %"),
            "{summary}"
        );
        let data = FrameData {
            mask: f16s(&other),
            ..data
        };
        let (_, summary) = heatmap_job(&scene, &light, &data).unwrap();
        assert!(
            !summary.starts_with("false shadow 0.000 %, false lit 0.000 %"),
            "{summary}"
        );
    }
}
