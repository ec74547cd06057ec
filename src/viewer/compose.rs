//! Composing a viewer frame into a window image: the 3D view (copied when
//! it is one texel per pixel in the window's format, else drawn), egui's
//! panel layer beside and over it, and the screenshot texture that receives
//! the same composition once more.

use super::blit::{self, Blit, LayerBlend};
use crate::frame::FrameTargets;
use crate::gpu::GpuContext;
use anyhow::{Context as _, Result};
use std::path::Path;

/// A window image holds sRGB-encoded bytes: the 3D view is written
/// through an sRGB view of it, egui (which blends in gamma space) through a
/// plain one. Frames are composed straight into the surface; a screenshot
/// composes the same frame once more into a texture that can be read.
pub(super) struct WindowTarget<'a> {
    pub texture: &'a wgpu::Texture,
    pub srgb: &'a wgpu::TextureView,
    pub plain: &'a wgpu::TextureView,
}

/// The screenshot texture (the surface's format) with its two views.
pub(super) struct Composite {
    pub texture: wgpu::Texture,
    srgb: wgpu::TextureView,
    plain: wgpu::TextureView,
}

impl Composite {
    /// A `width`×`height` texture in the window's `plain` format, viewed
    /// also as its sRGB twin.
    pub fn new(
        device: &wgpu::Device,
        (width, height): (u32, u32),
        plain: wgpu::TextureFormat,
    ) -> Self {
        let srgb = plain.add_srgb_suffix();
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: plain,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[srgb],
        });
        Composite {
            srgb: texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(srgb),
                ..Default::default()
            }),
            plain: texture.create_view(&Default::default()),
            texture,
        }
    }

    pub fn target(&self) -> WindowTarget<'_> {
        WindowTarget {
            texture: &self.texture,
            srgb: &self.srgb,
            plain: &self.plain,
        }
    }

    /// Reads the composed image back and writes it to `path` as an RGBA
    /// PNG (a BGRA window format swizzled).
    pub fn save_png(&self, gpu: &GpuContext, path: &Path) -> Result<()> {
        let mut rgba = gpu.read_texture(&self.texture, 0, 4)?;
        if self.texture.format() == wgpu::TextureFormat::Bgra8Unorm {
            for p in rgba.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        image::save_buffer(
            path,
            &rgba,
            self.texture.width(),
            self.texture.height(),
            image::ExtendedColorType::Rgba8,
        )
        .with_context(|| format!("writing {}", path.display()))
    }
}

/// One frame's composition: what it draws and where.
pub(super) struct Composer<'a> {
    pub gpu: &'a GpuContext,
    pub blit: &'a mut Blit,
    pub frame: &'a FrameTargets,
    /// egui's panels, drawn into their layer.
    pub layer: &'a wgpu::TextureView,
    /// The frame's masks (the mask overlay reads them).
    pub masks: wgpu::TextureView,
    /// The blit's mode for the 3D view (`blit::BLIT_*`, light, 0, 0).
    pub mode: [u32; 4],
    /// The 3D view's left edge (the panel's width) and the window's size.
    pub left: u32,
    pub size: (u32, u32),
    /// The panels' bounds, where egui drew any.
    pub panels: Option<[u32; 4]>,
    /// The window's format (without sRGB).
    pub plain: wgpu::TextureFormat,
}

impl Composer<'_> {
    /// Composes the frame into `target`.
    pub fn compose(&mut self, enc: &mut wgpu::CommandEncoder, target: WindowTarget) {
        let (width, height) = self.size;
        let (left, srgb) = (self.left, self.plain.add_srgb_suffix());
        // The view one texel per pixel in the window's format is copied (on
        // a CPU adapter a draw costs about as much as the prepass), the panels
        // left of it are drawn opaque and the panels over it blended.
        if self.mode[0] == blit::BLIT_COPY && self.frame.color_format() == srgb {
            enc.copy_texture_to_texture(
                self.frame.color().as_image_copy(),
                wgpu::TexelCopyTextureInfo {
                    texture: target.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: left,
                        y: 0,
                        z: 0,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                self.frame.color().size(),
            );
            if left > 0 {
                self.layer(enc, [0, 0, left, height], &target, LayerBlend::Opaque);
            }
            if let Some(over) = self.panels.and_then(|r| blit::right_of(r, left)) {
                self.layer(enc, over, &target, LayerBlend::Over);
            }
            return;
        }
        let view3d = [left as f32, 0.0, (width - left) as f32, height as f32];
        self.blit.draw(
            self.gpu,
            enc,
            view3d,
            target.srgb,
            srgb,
            self.frame.color_view(),
            &self.masks,
            self.mode,
        );
        if let Some(rect) = self.panels {
            self.layer(enc, rect, &target, LayerBlend::Over);
        }
    }

    /// Draws the panel layer within `rect` of `target`.
    fn layer(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        rect: [u32; 4],
        target: &WindowTarget,
        blend: LayerBlend,
    ) {
        self.blit.draw_layer(
            self.gpu,
            enc,
            rect,
            (target.plain, self.plain),
            self.layer,
            &self.masks,
            blend,
        );
    }
}
