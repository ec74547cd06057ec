//! Putting the frame on the page's canvas: through a WebGPU canvas context
//! (the frame's colour copied into the canvas's texture), or, where the
//! browser cannot composite a WebGPU canvas (headless Chromium on
//! SwiftShader loses the device at the first presented frame: it has no
//! shared-image backing for the swap chain), by reading the colour back
//! and drawing it with a 2D context. The page tests which one works
//! (`web/main.js`) and says which it uses.

use super::readback::map_read;
use crate::gpu::{GpuContext, TextureCopy};
use anyhow::{Result, anyhow};
use wasm_bindgen::{Clamped, JsCast};

/// How the canvas receives frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresentMode {
    /// The canvas's WebGPU context: no copy through the CPU.
    WebGpu,
    /// One colour readback a frame into a 2D context.
    Readback,
}

impl PresentMode {
    pub fn parse(name: &str) -> Result<PresentMode> {
        match name {
            "webgpu" => Ok(PresentMode::WebGpu),
            "readback" => Ok(PresentMode::Readback),
            _ => Err(anyhow!(
                "unknown presentation '{name}' (valid: webgpu, readback)"
            )),
        }
    }
}

/// The canvas, set up for one [`PresentMode`].
pub enum Presenter {
    WebGpu(wgpu::Surface<'static>),
    Readback(web_sys::CanvasRenderingContext2d),
}

impl Presenter {
    /// For [`PresentMode::WebGpu`], the surface the adapter must present to.
    pub fn surface(&self) -> Option<&wgpu::Surface<'static>> {
        match self {
            Presenter::WebGpu(s) => Some(s),
            Presenter::Readback(_) => None,
        }
    }

    /// The 2D context of `canvas` (before any WebGPU context is made).
    pub fn readback(canvas: &web_sys::HtmlCanvasElement) -> Result<Presenter> {
        let context = canvas
            .get_context("2d")
            .map_err(|e| anyhow!("the canvas has no 2D context: {e:?}"))?
            .ok_or_else(|| anyhow!("the canvas has no 2D context"))?
            .dyn_into::<web_sys::CanvasRenderingContext2d>()
            .map_err(|_| anyhow!("the canvas's 2D context has an unexpected type"))?;
        Ok(Presenter::Readback(context))
    }

    /// The colour format frames are rendered in: the sRGB form of the
    /// canvas's preferred format, or RGBA for the 2D context.
    pub fn configure(
        &self,
        gpu: &GpuContext,
        width: u32,
        height: u32,
    ) -> Result<wgpu::TextureFormat> {
        let Presenter::WebGpu(surface) = self else {
            return Ok(wgpu::TextureFormat::Rgba8UnormSrgb);
        };
        let mut config = surface
            .get_default_config(&gpu.adapter, width, height)
            .ok_or_else(|| anyhow!("the canvas has no configuration for this adapter"))?;
        config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST;
        surface.configure(&gpu.device, &config);
        Ok(config.format.add_srgb_suffix())
    }

    /// Shows `source` (the frame's size and colour format) on the canvas:
    /// at once through WebGPU; through the 2D context, once the returned
    /// draw has awaited its readback (which holds nothing of the page).
    pub fn present(&self, gpu: &GpuContext, source: &wgpu::Texture) -> Result<Option<PendingDraw>> {
        match self {
            Presenter::WebGpu(surface) => {
                let texture = match surface.get_current_texture() {
                    wgpu::CurrentSurfaceTexture::Success(t)
                    | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
                    // The canvas is hidden or being resized: nothing to show now.
                    _ => return Ok(None),
                };
                let mut enc = gpu.device.create_command_encoder(&Default::default());
                enc.copy_texture_to_texture(
                    source.as_image_copy(),
                    texture.texture.as_image_copy(),
                    source.size(),
                );
                gpu.queue.submit([enc.finish()]);
                gpu.queue.present(texture);
                Ok(None)
            }
            Presenter::Readback(context) => Ok(Some(PendingDraw {
                copy: gpu.copy_texture(source, 0, 0, 4),
                context: context.clone(),
                size: (source.width(), source.height()),
            })),
        }
    }
}

/// A frame on its way to the 2D context: its colour being copied back.
pub struct PendingDraw {
    copy: TextureCopy,
    context: web_sys::CanvasRenderingContext2d,
    size: (u32, u32),
}

impl PendingDraw {
    pub async fn draw(self) -> Result<()> {
        let rgba = self.copy.unpad(&map_read(&self.copy.buffer).await?);
        let image = web_sys::ImageData::new_with_u8_clamped_array_and_sh(
            Clamped(&rgba),
            self.size.0,
            self.size.1,
        )
        .map_err(|e| anyhow!("drawing the frame: {e:?}"))?;
        self.context
            .put_image_data(&image, 0.0, 0.0)
            .map_err(|e| anyhow!("drawing the frame: {e:?}"))
    }
}
