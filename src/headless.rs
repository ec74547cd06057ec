//! Rendering frames headless (no window) and writing them out: `image.png`,
//! `visibility-N.png` (16-bit grey, 65535 = fully lit, background 65535) and
//! `frame.json` (everything needed to reproduce the frame's rays).

use crate::frame::{COLOR_FORMAT, FrameTargets, SceneGpu};
use crate::gpu::GpuContext;
use crate::renderer::{FrameCameras, FrameTimings, RenderSettings, Renderer};
use crate::scene::{Camera, Light, Scene};
use crate::technique::{TechniqueChoice, TechniqueInstance};
use anyhow::{Context, Result};
use serde_json::json;
use std::path::Path;

/// A frame read back from the GPU.
pub struct FrameImages {
    pub width: u32,
    pub height: u32,
    /// sRGB RGBA8.
    pub color: Vec<u8>,
    /// Per light, one visibility value per pixel (row-major, top row first).
    pub masks: Vec<Vec<f32>>,
    /// Per pixel: true where geometry was drawn.
    pub coverage: Vec<bool>,
}

/// Reads the colour image, the masks of `light_count` lights and the
/// G-buffer coverage back from the GPU.
pub fn read_back(
    gpu: &GpuContext,
    frame: &FrameTargets,
    light_count: usize,
) -> Result<FrameImages> {
    let color = frame.read_color_rgba(gpu)?;
    let masks = (0..light_count)
        .map(|i| {
            Ok(decode_mask(&gpu.read_texture(
                frame.masks(),
                i as u32,
                2,
            )?))
        })
        .collect::<Result<Vec<Vec<f32>>>>()?;
    let pos = gpu.read_texture(frame.gbuffer_position(), 0, 16)?;
    let coverage = bytemuck::cast_slice::<u8, [f32; 4]>(&pos)
        .iter()
        .map(|p| p[3] > 0.5)
        .collect();
    Ok(FrameImages {
        width: frame.width(),
        height: frame.height(),
        color,
        masks,
        coverage,
    })
}

/// A mask layer's texels as read back (half floats) as visibilities.
pub fn decode_mask(raw: &[u8]) -> Vec<f32> {
    bytemuck::cast_slice::<u8, half::f16>(raw)
        .iter()
        .map(|h| h.to_f32())
        .collect()
}

/// A mask as bytes, 255 = fully lit.
pub fn mask_to_u8(mask: &[f32]) -> Vec<u8> {
    mask.iter()
        .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect()
}

/// Converts a mask to 16-bit grey: 65535 = fully lit; background pixels 65535.
pub fn mask_to_u16(mask: &[f32], coverage: &[bool]) -> Vec<u16> {
    mask.iter()
        .zip(coverage)
        .map(|(&v, &c)| {
            if c {
                (v.clamp(0.0, 1.0) * 65535.0).round() as u16
            } else {
                65535
            }
        })
        .collect()
}

/// Writes `image.png` and `visibility-N.png` into `dir`.
pub fn write_images(dir: &Path, img: &FrameImages) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    image::save_buffer(
        dir.join("image.png"),
        &img.color,
        img.width,
        img.height,
        image::ExtendedColorType::Rgba8,
    )?;
    for (i, m) in img.masks.iter().enumerate() {
        let grey = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(
            img.width,
            img.height,
            mask_to_u16(m, &img.coverage),
        )
        .expect("mask size matches frame");
        grey.save(dir.join(format!("visibility-{i}.png")))?;
    }
    Ok(())
}

/// Column-major 4×4 matrix as a JSON array of 16 numbers.
fn mat_json(m: glam::Mat4) -> serde_json::Value {
    json!(m.to_cols_array())
}

/// Everything `frame.json` records about a rendered frame.
pub struct FrameRecord<'a> {
    pub scene: &'a Scene,
    pub scene_gpu: &'a SceneGpu,
    pub camera: &'a Camera,
    pub lights: &'a [Light],
    pub techniques: Vec<&'a TechniqueInstance>,
    pub settings: &'a RenderSettings,
    pub frame: &'a FrameTargets,
    pub timings: &'a FrameTimings,
    pub adapter: String,
    /// Anisotropic filtering of the material textures.
    pub anisotropy: u16,
    /// Mip-level blending of the material textures.
    pub mip_filter: crate::renderer::MipFilter,
    pub extra_timings: serde_json::Value,
}

pub fn frame_json(r: &FrameRecord) -> serde_json::Value {
    let u = r.frame.uniform();
    json!({
        "scene": r.scene.name,
        "scene_source": r.scene.source,
        "adapter": r.adapter,
        "size": {"width": r.frame.width(), "height": r.frame.height()},
        "techniques": r.techniques.iter().enumerate().map(|(i, inst)| {
            let t = &inst.choice;
            json!({
                "light": i,
                "id": t.id(),
                "family": t.family.id,
                "preset": t.preset,
                "parameters": t.params.to_json(),
                "counters": inst.technique.counters().into_iter().collect::<std::collections::BTreeMap<_, _>>(),
                "resource_bytes": inst.technique.resource_bytes(),
            })
        }).collect::<Vec<_>>(),
        "render_settings": r.settings,
        "texture_anisotropy": r.anisotropy,
        "texture_mip_filter": r.mip_filter,
        "camera": {
            "eye": r.camera.eye.to_array(),
            "target": r.camera.target.to_array(),
            "up": r.camera.up.to_array(),
            "fov_y_deg": r.camera.fov_y_deg,
            "near": r.camera.near,
            "far": r.camera.far,
            "aspect": r.frame.width() as f32 / r.frame.height() as f32,
        },
        "matrices": {
            "layout": "column-major, 16 numbers per matrix; clip = projection · view · world",
            "view": mat_json(u.view),
            "projection": mat_json(u.proj),
            "view_projection": mat_json(u.view_proj),
        },
        "conventions": {
            "pixel_centre": "pixel (x, y) covers [x, x+1) × [y, y+1); its centre is (x + 0.5, y + 0.5)",
            "y_axis": "pixel y grows downwards; NDC y grows upwards",
            "ndc_from_pixel": "ndc_x = 2 (x + 0.5) / width − 1, ndc_y = 1 − 2 (y + 0.5) / height",
            "depth_range": "NDC z in [0, 1], reversed: 1 = near plane, 0 = far plane (2^-20 at infinity under an infinite projection); right-handed view space looking down −z",
            "gbuffer": "world position (w = object index + 1, 0 = background) and geometric normal facing the camera (w = receives shadows)",
            "visibility_png": "16-bit grey, 65535 = fully lit, background pixels 65535",
        },
        "lights": r.lights,
        "triangles": {
            "drawn": r.scene_gpu.triangle_count,
            "casters": r.scene_gpu.caster_triangle_count,
        },
        "timings_ms": {
            "prepass": r.timings.prepass_ms,
            "visibility_masks": r.timings.masks_ms,
            "lighting": r.timings.lighting_ms,
            "frame": r.timings.total_ms,
            "other": r.extra_timings,
        },
    })
}

/// A complete headless frame: GPU, renderer, scene upload, per-light
/// technique instances.
pub struct HeadlessFrame {
    pub renderer: Renderer,
    pub scene_gpu: SceneGpu,
    pub frame: FrameTargets,
    pub techniques: Vec<TechniqueInstance>,
}

impl HeadlessFrame {
    pub fn new(
        gpu: &GpuContext,
        scene: &Scene,
        choices: &[TechniqueChoice],
        width: u32,
        height: u32,
    ) -> Result<HeadlessFrame> {
        gpu.checked("creating the renderer", || {
            Self::with_color_format(gpu, scene, choices, (width, height), COLOR_FORMAT)
        })
    }

    /// As [`HeadlessFrame::new`], the colour image in `color_format` (one
    /// of [`crate::frame::COLOR_FORMATS`]: the browser page takes its
    /// canvas's), without error scopes of its own.
    pub fn with_color_format(
        gpu: &GpuContext,
        scene: &Scene,
        choices: &[TechniqueChoice],
        (width, height): (u32, u32),
        color_format: wgpu::TextureFormat,
    ) -> Result<HeadlessFrame> {
        crate::frame::check_formats(gpu)?;
        let renderer = Renderer::new(gpu);
        let scene_gpu = SceneGpu::upload(gpu, scene)?;
        let frame = FrameTargets::with_color_format(gpu, width, height, color_format)?;
        let techniques = choices
            .iter()
            .map(|c| TechniqueInstance::new(gpu, c.clone()))
            .collect::<Result<Vec<_>>>()?;
        Ok(HeadlessFrame {
            renderer,
            scene_gpu,
            frame,
            techniques,
        })
    }

    pub fn render(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        camera: &Camera,
        lights: &[Light],
        settings: &RenderSettings,
    ) -> Result<FrameTimings> {
        let cameras = FrameCameras {
            view: camera,
            fit: camera,
        };
        self.render_fitted(gpu, scene, cameras, lights, settings)
    }

    /// As [`HeadlessFrame::render`], the techniques fitting their light
    /// views to `cameras.fit`.
    pub fn render_fitted(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        cameras: FrameCameras,
        lights: &[Light],
        settings: &RenderSettings,
    ) -> Result<FrameTimings> {
        gpu.checked("rendering", || {
            self.renderer.render_fitted(
                gpu,
                scene,
                &self.scene_gpu,
                &mut self.frame,
                cameras,
                lights,
                &mut self.techniques,
                settings,
            )
        })
    }
}
