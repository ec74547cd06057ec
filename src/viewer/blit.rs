//! Putting a frame on the window: the rendered view (or a light's mask)
//! copied into its part of the target, and egui's panels over it, from a
//! cached layer while they do not change.

use crate::gpu::GpuContext;
use egui::ClippedPrimitive;

/// `Blit.mode.x` of blit.wgsl: the view filtered down (supersampling).
pub const BLIT_FILTERED: u32 = 0;
/// A light's mask (layer `mode.y`) in grey.
pub const BLIT_MASK: u32 = 1;
/// A layer of the target's size with its alpha.
const BLIT_LAYER: u32 = 2;
/// The view, one texel per pixel.
pub const BLIT_COPY: u32 = 3;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlitUniform {
    mode: [u32; 4],
}

/// How [`Blit::draw_layer`] puts a layer on its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerBlend {
    /// Blended over what the target holds (premultiplied alpha).
    Over,
    /// Over black, replacing what the target holds.
    Opaque,
}

/// Draws a texture (or a mask layer) over a whole target.
pub struct Blit {
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    module: wgpu::ShaderModule,
    /// By target format and whether the pass blends over the target.
    pipelines: Vec<((wgpu::TextureFormat, bool), wgpu::RenderPipeline)>,
}

impl Blit {
    pub fn new(gpu: &GpuContext) -> Blit {
        let device = &gpu.device;
        let tex = |binding, dim| crate::gpu::texture_entry(binding, dim, binding == 1);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit"),
            entries: &[
                crate::gpu::uniform_entry(gpu, 0, wgpu::ShaderStages::FRAGMENT, false),
                tex(1, wgpu::TextureViewDimension::D2),
                tex(2, wgpu::TextureViewDimension::D2Array),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        Blit {
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            module: crate::gpu::compose_shader(gpu, "blit", &[include_str!("blit.wgsl")]),
            layout,
            pipelines: vec![],
        }
    }

    fn pipeline(
        &mut self,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        over: bool,
    ) -> &wgpu::RenderPipeline {
        let key = (format, over);
        if !self.pipelines.iter().any(|(k, _)| *k == key) {
            let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("blit"),
                bind_group_layouts: &[Some(&self.layout)],
                immediate_size: 0,
            });
            let p = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("blit"),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some("vs_blit"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some("fs_blit"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: over.then_some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            });
            self.pipelines.push((key, p));
        }
        &self
            .pipelines
            .iter()
            .find(|(k, _)| *k == key)
            .expect("inserted above")
            .1
    }

    /// Draws `source` (or a mask) into the `viewport` (x, y, w, h) of
    /// `target`, clearing the rest.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        viewport: [f32; 4],
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        source: &wgpu::TextureView,
        masks: &wgpu::TextureView,
        mode: [u32; 4],
    ) {
        let bind_group = self.bind_group(gpu, source, masks, mode);
        let pipeline = self.pipeline(&gpu.device, format, false).clone();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("blit"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_viewport(viewport[0], viewport[1], viewport[2], viewport[3], 0.0, 1.0);
        pass.draw(0..3, 0..1);
    }

    /// Draws `layer` (premultiplied alpha, the target's size) into the
    /// `scissor` rectangle (x, y, w, h) of `target` (a view and its
    /// format), keeping the rest of the target.
    #[allow(clippy::too_many_arguments)]
    pub fn draw_layer(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scissor: [u32; 4],
        (target, format): (&wgpu::TextureView, wgpu::TextureFormat),
        layer: &wgpu::TextureView,
        masks: &wgpu::TextureView,
        blend: LayerBlend,
    ) {
        let (mode, over) = match blend {
            LayerBlend::Over => (BLIT_LAYER, true),
            LayerBlend::Opaque => (BLIT_COPY, false),
        };
        let bind_group = self.bind_group(gpu, layer, masks, [mode, 0, 0, 0]);
        let pipeline = self.pipeline(&gpu.device, format, over).clone();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("blit over"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_scissor_rect(scissor[0], scissor[1], scissor[2], scissor[3]);
        pass.draw(0..3, 0..1);
    }

    fn bind_group(
        &self,
        gpu: &GpuContext,
        source: &wgpu::TextureView,
        masks: &wgpu::TextureView,
        mode: [u32; 4],
    ) -> wgpu::BindGroup {
        // A buffer per draw: several draws share one encoder, and a queued
        // write to one shared buffer would land before all of them.
        use wgpu::util::DeviceExt;
        let uniform = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("blit"),
                contents: bytemuck::bytes_of(&BlitUniform { mode }),
                usage: gpu.uniform_space.usage(),
            });
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(source),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(masks),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        })
    }
}

/// egui's panels drawn once into a texture and blended over each frame
/// while they stay the same: on a CPU adapter drawing the panels' triangles
/// costs more than the blend (on lavapipe about 14 ms against 2 ms for the
/// side panel).
pub struct EguiLayer {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// Hash of the tessellated primitives drawn into the texture.
    drawn: Option<u64>,
}

impl EguiLayer {
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Self {
        let texture = crate::gpu::texture_2d(
            device,
            "egui layer",
            width,
            height,
            1,
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        EguiLayer {
            view: texture.create_view(&Default::default()),
            texture,
            drawn: None,
        }
    }

    pub fn size(&self) -> (u32, u32) {
        (self.texture.width(), self.texture.height())
    }

    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// Whether the layer must be drawn again for `primitives` (a texture
    /// upload also counts as a change); remembers them as drawn.
    fn needs_drawing(&mut self, primitives: &[ClippedPrimitive], textures_changed: bool) -> bool {
        let hash = primitives_hash(primitives);
        let stale = textures_changed || self.drawn != Some(hash);
        self.drawn = Some(hash);
        stale
    }

    /// Draws egui's `primitives` into the layer when they changed
    /// ([`Self::needs_drawing`]); returns the command buffers egui's
    /// callbacks need submitted first (none when nothing was drawn).
    pub fn draw(
        &mut self,
        gpu: &GpuContext,
        renderer: &mut egui_wgpu::Renderer,
        encoder: &mut wgpu::CommandEncoder,
        primitives: &[ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
        textures_changed: bool,
    ) -> Vec<wgpu::CommandBuffer> {
        if !self.needs_drawing(primitives, textures_changed) {
            return vec![];
        }
        let commands =
            renderer.update_buffers(&gpu.device, &gpu.queue, encoder, primitives, screen);
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            })
            .forget_lifetime();
        renderer.render(&mut pass, primitives, screen);
        commands
    }
}

/// Identifies a frame's tessellated egui output.
fn primitives_hash(primitives: &[ClippedPrimitive]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for p in primitives {
        let r = p.clip_rect;
        [r.min.x, r.min.y, r.max.x, r.max.y]
            .map(f32::to_bits)
            .hash(&mut h);
        match &p.primitive {
            egui::epaint::Primitive::Mesh(m) => {
                m.texture_id.hash(&mut h);
                m.indices.hash(&mut h);
                for v in &m.vertices {
                    [v.pos.x, v.pos.y, v.uv.x, v.uv.y]
                        .map(f32::to_bits)
                        .hash(&mut h);
                    v.color.to_array().hash(&mut h);
                }
            }
            egui::epaint::Primitive::Callback(_) => {
                // Drawn by the application every frame: never cached.
                std::time::Instant::now().hash(&mut h);
            }
        }
    }
    h.finish()
}

/// The pixel rectangle (x, y, w, h) that `primitives` can touch, within a
/// `width × height` target at `pixels_per_point`; `None` when empty.
pub fn primitives_bounds(
    primitives: &[ClippedPrimitive],
    pixels_per_point: f32,
    width: u32,
    height: u32,
) -> Option<[u32; 4]> {
    let mut rect = egui::Rect::NOTHING;
    for p in primitives {
        if let egui::epaint::Primitive::Mesh(m) = &p.primitive {
            rect = rect.union(m.calc_bounds().intersect(p.clip_rect));
        }
    }
    if !rect.is_positive() {
        return None;
    }
    let x0 = ((rect.min.x * pixels_per_point).floor().max(0.0) as u32).min(width);
    let y0 = ((rect.min.y * pixels_per_point).floor().max(0.0) as u32).min(height);
    let x1 = ((rect.max.x * pixels_per_point).ceil().max(0.0) as u32).min(width);
    let y1 = ((rect.max.y * pixels_per_point).ceil().max(0.0) as u32).min(height);
    (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
}

/// The part of `rect` (x, y, w, h) right of column `x0`; `None` when empty.
pub fn right_of(rect: [u32; 4], x0: u32) -> Option<[u32; 4]> {
    let [x, y, w, h] = rect;
    let start = x.max(x0);
    let end = x + w;
    (end > start).then(|| [start, y, end - start, h])
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui::{Color32, Pos2, Rect, epaint::Mesh};

    /// `Blit` of blit.wgsl is laid out as `BlitUniform`.
    #[test]
    fn the_uniform_matches_its_wgsl_struct() {
        crate::gpu::wgsl_layout::assert_struct_matches(
            include_str!("blit.wgsl"),
            "Blit",
            crate::field_offsets!(BlitUniform; mode),
            std::mem::size_of::<BlitUniform>(),
        );
    }

    fn quad(min: Pos2, max: Pos2, color: Color32, clip: Rect) -> ClippedPrimitive {
        let mut mesh = Mesh::default();
        mesh.add_colored_rect(Rect::from_min_max(min, max), color);
        ClippedPrimitive {
            clip_rect: clip,
            primitive: egui::epaint::Primitive::Mesh(mesh),
        }
    }

    #[test]
    fn the_layer_is_drawn_again_only_when_the_panels_change() {
        let clip = Rect::from_min_max(Pos2::ZERO, Pos2::new(100.0, 100.0));
        let a = vec![quad(
            Pos2::new(1.0, 2.0),
            Pos2::new(30.0, 40.0),
            Color32::RED,
            clip,
        )];
        let same = a.clone();
        let recoloured = vec![quad(
            Pos2::new(1.0, 2.0),
            Pos2::new(30.0, 40.0),
            Color32::BLUE,
            clip,
        )];
        let moved = vec![quad(
            Pos2::new(2.0, 2.0),
            Pos2::new(30.0, 40.0),
            Color32::RED,
            clip,
        )];
        assert_eq!(primitives_hash(&a), primitives_hash(&same));
        assert_ne!(primitives_hash(&a), primitives_hash(&recoloured));
        assert_ne!(primitives_hash(&a), primitives_hash(&moved));
        assert_ne!(primitives_hash(&a), primitives_hash(&[]));
    }

    #[test]
    fn panel_bounds_are_clipped_and_scaled_to_pixels() {
        let clip = Rect::from_min_max(Pos2::ZERO, Pos2::new(20.0, 100.0));
        let p = vec![quad(
            Pos2::new(1.0, 2.0),
            Pos2::new(30.0, 40.0),
            Color32::RED,
            clip,
        )];
        // Clipped at x = 20 points, 2 pixels per point.
        assert_eq!(primitives_bounds(&p, 2.0, 1000, 1000), Some([2, 4, 38, 76]));
        // Within the target.
        assert_eq!(primitives_bounds(&p, 2.0, 30, 50), Some([2, 4, 28, 46]));
        assert_eq!(primitives_bounds(&[], 1.0, 100, 100), None);
    }

    #[test]
    fn the_part_right_of_a_column_is_clipped_or_empty() {
        assert_eq!(right_of([0, 5, 300, 40], 250), Some([250, 5, 50, 40]));
        assert_eq!(right_of([260, 5, 30, 40], 250), Some([260, 5, 30, 40]));
        assert_eq!(right_of([0, 5, 250, 40], 250), None);
        assert_eq!(right_of([0, 5, 100, 40], 250), None);
    }
}
