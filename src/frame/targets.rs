//! The targets of one frame size: depth-stencil, G-buffer, one visibility
//! mask layer per light, the colour image and the frame uniform. Passes get
//! `&FrameTargets` and read it through accessors; only the renderer writes
//! the uniform.

use super::{
    COLOR_FORMAT, COLOR_FORMATS, FrameLayouts, FrameUniform, GBUFFER_NORMAL_FORMAT,
    GBUFFER_PART_FORMAT, GBUFFER_POSITION_FORMAT, MASK_FORMAT, MAX_LIGHTS,
};
use crate::gpu::GpuContext;
use anyhow::{Result, bail};
use bytemuck::Zeroable;

/// Per-frame-size targets and the frame uniform.
pub struct FrameTargets {
    width: u32,
    height: u32,
    depth_view: wgpu::TextureView,
    gbuffer_position: wgpu::Texture,
    gbuffer_position_view: wgpu::TextureView,
    gbuffer_normal: wgpu::Texture,
    gbuffer_normal_view: wgpu::TextureView,
    gbuffer_part_view: wgpu::TextureView,
    gbuffer_bind_group: wgpu::BindGroup,
    masks: wgpu::Texture,
    mask_layer_views: Vec<wgpu::TextureView>,
    mask_array_view: wgpu::TextureView,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    frame_buffer: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    /// CPU copy of what the GPU uses this frame.
    uniform: FrameUniform,
}

impl FrameTargets {
    /// Creates the targets for a `width × height` frame with a
    /// [`COLOR_FORMAT`] colour image. Errors on a zero or over-limit size.
    pub fn new(gpu: &GpuContext, width: u32, height: u32) -> Result<FrameTargets> {
        Self::with_color_format(gpu, width, height, COLOR_FORMAT)
    }

    /// As [`FrameTargets::new`], with a colour image of `color_format`, one
    /// of [`COLOR_FORMATS`].
    pub fn with_color_format(
        gpu: &GpuContext,
        width: u32,
        height: u32,
        color_format: wgpu::TextureFormat,
    ) -> Result<FrameTargets> {
        if !COLOR_FORMATS.contains(&color_format) {
            bail!("{color_format:?} is not a colour format of frames (one of {COLOR_FORMATS:?})");
        }
        let layouts = FrameLayouts::of(gpu);
        let max = gpu.max_texture_size();
        if width == 0 || height == 0 || width > max || height > max {
            bail!(
                "frame size {width}x{height} is outside 1..={max} (the device's largest texture)"
            );
        }
        // Depth, G-buffer position, normal and part, the mask layers and colour.
        let bytes_per_pixel = 4 + 16 + 8 + 4 + 2 * MAX_LIGHTS as u64 + 4;
        gpu.check_allocation(
            &format!("frame {width}x{height}"),
            (width, height, MAX_LIGHTS as u32),
            width as u64 * height as u64 * bytes_per_pixel,
        )?;
        let device = &gpu.device;
        use wgpu::TextureUsages as U;
        let target = |label: &str, layers: u32, format: wgpu::TextureFormat, usage: U| {
            crate::gpu::texture_2d(device, label, width, height, layers, format, usage)
        };
        let depth = target(
            "depth",
            1,
            gpu.depth_format,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
        );
        let depth_view = depth.create_view(&Default::default());
        let gusage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let gbuffer_position = target("gbuffer position", 1, GBUFFER_POSITION_FORMAT, gusage);
        let gbuffer_normal = target("gbuffer normal", 1, GBUFFER_NORMAL_FORMAT, gusage);
        let gbuffer_part = target("gbuffer part", 1, GBUFFER_PART_FORMAT, gusage);
        let masks = target(
            "visibility masks",
            MAX_LIGHTS as u32,
            MASK_FORMAT,
            gusage | U::COPY_DST,
        );
        let (mask_layer_views, mask_array_view) =
            crate::gpu::layer_views(&masks, MAX_LIGHTS as u32);
        let color = target(
            "color",
            1,
            color_format,
            U::RENDER_ATTACHMENT | U::COPY_SRC | U::TEXTURE_BINDING,
        );
        let color_view = color.create_view(&Default::default());
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniform"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: crate::gpu::uniform_usage(gpu),
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &layouts.frame,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        let gbuffer_position_view = gbuffer_position.create_view(&Default::default());
        let gbuffer_normal_view = gbuffer_normal.create_view(&Default::default());
        let gbuffer_part_view = gbuffer_part.create_view(&Default::default());
        let gbuffer_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gbuffer"),
            layout: &layouts.gbuffer,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&gbuffer_position_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&gbuffer_normal_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&gbuffer_part_view),
                },
            ],
        });
        Ok(FrameTargets {
            width,
            height,
            gbuffer_position_view,
            gbuffer_normal_view,
            gbuffer_part_view,
            gbuffer_bind_group,
            depth_view,
            gbuffer_position,
            gbuffer_normal,
            masks,
            mask_layer_views,
            mask_array_view,
            color,
            color_view,
            frame_buffer,
            frame_bind_group,
            uniform: FrameUniform::zeroed(),
        })
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The frame uniform of the current frame (camera matrices, lights).
    pub fn uniform(&self) -> &FrameUniform {
        &self.uniform
    }

    /// Sets the frame uniform and queues its upload.
    pub fn set_uniform(&mut self, gpu: &GpuContext, uniform: FrameUniform) {
        self.uniform = uniform;
        gpu.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&self.uniform));
    }

    /// Depth-stencil of the prepass (depth and stencil aspects).
    pub fn depth_view(&self) -> &wgpu::TextureView {
        &self.depth_view
    }

    /// The frame's depth as a pass attachment, loaded and kept, without its
    /// stencil (passes that draw over the prepass's depth).
    pub fn kept_depth(&self) -> wgpu::RenderPassDepthStencilAttachment<'_> {
        wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }
    }

    /// Group 0: the frame uniform.
    pub fn frame_bind_group(&self) -> &wgpu::BindGroup {
        &self.frame_bind_group
    }

    /// Group 3 of technique passes: the G-buffer's position, normal and part.
    pub fn gbuffer_bind_group(&self) -> &wgpu::BindGroup {
        &self.gbuffer_bind_group
    }

    pub fn gbuffer_position(&self) -> &wgpu::Texture {
        &self.gbuffer_position
    }

    pub fn gbuffer_normal(&self) -> &wgpu::Texture {
        &self.gbuffer_normal
    }

    /// The G-buffer's position and normal.
    pub fn gbuffer_views(&self) -> [&wgpu::TextureView; 2] {
        [&self.gbuffer_position_view, &self.gbuffer_normal_view]
    }

    /// The G-buffer's convex part IDs.
    pub fn gbuffer_part_view(&self) -> &wgpu::TextureView {
        &self.gbuffer_part_view
    }

    /// The mask array (one layer per light).
    pub fn masks(&self) -> &wgpu::Texture {
        &self.masks
    }

    /// Light `i`'s mask layer as a render target.
    pub fn mask_layer(&self, i: usize) -> &wgpu::TextureView {
        &self.mask_layer_views[i]
    }

    /// The mask array as one view (read by the lighting pass).
    pub fn mask_array_view(&self) -> &wgpu::TextureView {
        &self.mask_array_view
    }

    pub fn color(&self) -> &wgpu::Texture {
        &self.color
    }

    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.color_view
    }

    pub fn color_format(&self) -> wgpu::TextureFormat {
        self.color.format()
    }

    /// The colour image read back as RGBA8 (sRGB-encoded), whatever the
    /// order of its channels on the GPU.
    pub fn read_color_rgba(&self, gpu: &GpuContext) -> Result<Vec<u8>> {
        let mut rgba = gpu.read_texture(&self.color, 0, 4)?;
        self.swap_rgba_order(&mut rgba);
        Ok(rgba)
    }

    /// Reorders colour texels between RGBA and this frame's colour format
    /// (its own inverse: BGRA texels become RGBA and back; nothing for RGBA).
    pub fn swap_rgba_order(&self, texels: &mut [u8]) {
        if self.color_format() == wgpu::TextureFormat::Bgra8UnormSrgb {
            texels.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
    }
}

/// Uploads a CPU-computed visibility mask (row-major, top row first) into
/// layer `layer` of the frame's masks.
pub fn write_mask(gpu: &GpuContext, frame: &FrameTargets, layer: usize, mask: &[f32]) {
    let data: Vec<half::f16> = mask.iter().map(|&v| half::f16::from_f32(v)).collect();
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &frame.masks,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer as u32,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(&data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(frame.width * 2),
            rows_per_image: Some(frame.height),
        },
        wgpu::Extent3d {
            width: frame.width,
            height: frame.height,
            depth_or_array_layers: 1,
        },
    );
}

/// Clears a mask layer to `value` (a render pass with a clear and no draw).
pub fn clear_mask(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    value: f64,
) {
    gpu.render_pass(
        encoder,
        &wgpu::RenderPassDescriptor {
            label: Some("mask clear"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: value,
                        g: value,
                        b: value,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        },
    );
}
