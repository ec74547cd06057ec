//! The passes of a paged map's frame: marking the pages the pixels need
//! (and reading the marks back), and rendering new pages into the pool.

use super::VirtualState;
use super::levels::{PageKey, VirtualLayout};
use super::pages::Allocation;
use crate::gpu::FrameFeedback;
use crate::scene::Aabb;
use crate::technique::MaskContext;
use crate::technique::light_space::outside_clip_volume;
use crate::technique::shadow_map::gpu::depth_pass::{DepthDraw, DepthPassKey};
use crate::technique::shadow_map::gpu::pipelines::{LookupKey, MapShape};
use crate::technique::shadow_map::gpu::uniform::{MAX_FACES, STRIDE, ShadowMapUniform};
use crate::technique::shadow_map::projection::bias_cap::texel_bias_clamp;
use crate::technique::shadow_map::{DepthFormat, MapBindings, ShadowMapConfig, ShadowMapTechnique};
use anyhow::Result;
use glam::{Mat4, UVec4};

impl ShadowMapTechnique {
    /// The bind group of a virtual map's passes, its pool as `pool`.
    pub(super) fn page_group(
        &self,
        ctx: &MaskContext,
        state: &VirtualState,
        pool: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        self.bind_group(
            ctx,
            MapBindings {
                depth: pool,
                virtual_buffers: [
                    &state.marks,
                    &state.table,
                    &state.levels,
                    &state.pixel_levels,
                ],
                ..MapBindings::empty(&self.shared, &state.uniforms)
            },
        )
    }

    /// Records the marking pass (`words` words of page bits) and its read
    /// back: this pass's marks when `wait`, else the latest that arrived.
    /// `timed`: the frame's first marking pass, whose GPU time is counter
    /// `page_marking_ms`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn mark_pages(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        state: &mut VirtualState,
        base: &ShadowMapUniform,
        lookup_key: LookupKey,
        words: u64,
        wait: bool,
        timed: bool,
    ) -> Result<Option<Vec<u32>>> {
        let gpu = ctx.gpu;
        gpu.queue
            .write_buffer(&state.uniforms, 0, bytemuck::bytes_of(base));
        let atlas = state.atlas.as_ref().expect("made before marking");
        let mark_group = self.page_group(ctx, state, &atlas.array);
        let mut own = FrameFeedback::own_encoder(gpu, wait);
        {
            let encoder = own.as_mut().unwrap_or(&mut *encoder);
            encoder.clear_buffer(&state.marks, 0, Some(words * 4));
            let mark = |encoder: &mut wgpu::CommandEncoder| {
                let mut pass = crate::technique::mask_pass_with(
                    encoder,
                    ctx,
                    "virtual shadow map marking",
                    wgpu::LoadOp::Load,
                );
                pass.set_pipeline(&self.shared.virtual_mark(
                    gpu,
                    lookup_key,
                    self.config.paging.is_adaptive(),
                ));
                ctx.bind_frame_groups(&mut pass);
                pass.set_bind_group(crate::frame::OWN_GROUP, &mark_group, &[0]);
                pass.draw(0..3, 0..1);
            };
            if timed {
                state.mark_timer.time(gpu, encoder, mark);
            } else {
                mark(encoder);
            }
        }
        Ok(state
            .feedback
            .collect(gpu, own, encoder, &state.marks, words * 4)?
            .map(|bytes| bytemuck::cast_slice(&bytes).to_vec()))
    }

    /// Renders the pages `allocation` made new into their pool slots (each
    /// with the casters that overlap it); returns the triangles drawn.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn render_new_pages(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        state: &mut VirtualState,
        layout: &VirtualLayout,
        allocation: &Allocation,
        base: &ShadowMapUniform,
        lookup_key: LookupKey,
    ) -> u64 {
        let c = self.config;
        let gpu = ctx.gpu;
        let page_matrices = write_page_uniforms(gpu, state, layout, allocation, base);
        if allocation.render.is_empty() {
            return 0;
        }
        let render_group = self.page_group(ctx, state, &self.shared.placeholder_depth);
        // A clipmap level's bias cap follows its texels, as a cascade's
        // does; each level's pipeline is looked up once, when it has pages.
        let mut depth_pipelines: Vec<Option<Vec<DepthDraw>>> = vec![None; layout.levels.len()];
        let mut depth_pipeline = |level: u32| {
            depth_pipelines[level as usize]
                .get_or_insert_with(|| {
                    let clamp = if layout.orthographic {
                        texel_bias_clamp(
                            layout.levels[level as usize].texel_world,
                            layout.far - layout.near,
                            c.slope_bias_clamp,
                        )
                    } else {
                        0.0
                    };
                    self.shared.depth_passes(
                        gpu,
                        page_depth_key(&c, lookup_key.shape, clamp),
                        c.solid_front_bias,
                        c.caster_alpha,
                        &ctx.scene_gpu.draws,
                    )
                })
                .clone()
        };
        let clear_pipeline = self.shared.clear_page(gpu, lookup_key);
        let atlas = state.atlas.as_ref().expect("made before rendering");
        let mut map_triangles = 0;
        for (layer, view) in atlas.layer_views.iter().enumerate() {
            let on_layer: Vec<(usize, &(PageKey, u32))> = allocation
                .render
                .iter()
                .enumerate()
                .filter(|(_, (_, slot))| atlas.place(*slot).0 == layer)
                .collect();
            if on_layer.is_empty() {
                continue;
            }
            let mut pass = gpu.render_pass(
                encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some("virtual shadow map pages"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    ..Default::default()
                },
            );
            ctx.bind_frame_groups(&mut pass);
            for (i, (key, slot)) in on_layer {
                let (_, x, y) = atlas.place(*slot);
                let side = atlas.slot_texels();
                pass.set_viewport(x as f32, y as f32, side as f32, side as f32, 0.0, 1.0);
                pass.set_scissor_rect(x, y, side, side);
                let offset = ((i as u64 + 1) * STRIDE) as u32;
                pass.set_bind_group(crate::frame::OWN_GROUP, &render_group, &[offset]);
                pass.set_pipeline(&clear_pipeline);
                pass.draw(0..3, 0..1);
                let m = page_matrices[i];
                let eye = layout.eye;
                for draw in depth_pipeline(key.level) {
                    pass.set_pipeline(&draw.pipeline);
                    map_triangles += ctx.scene_gpu.draw_visible(
                        &mut pass,
                        |d| draw.takes(d),
                        |b| {
                            !outside_clip_volume(
                                &Aabb {
                                    min: b.min - eye,
                                    max: b.max - eye,
                                },
                                m,
                            )
                        },
                    );
                }
            }
        }
        map_triangles
    }
}

/// Writes the paged frame's uniforms — slot 0 for marking and lookup, then
/// one per page rendered — and returns each new page's matrix.
fn write_page_uniforms(
    gpu: &crate::gpu::GpuContext,
    state: &mut VirtualState,
    layout: &VirtualLayout,
    allocation: &Allocation,
    base: &ShadowMapUniform,
) -> Vec<Mat4> {
    // Uniforms: slot 0 marking and lookup, then one per page rendered.
    let slots = 1 + allocation.render.len() as u64;
    crate::gpu::grow_buffer(
        &gpu.device,
        &mut state.uniforms,
        slots * STRIDE,
        "virtual map uniforms",
    );
    let page_matrices: Vec<Mat4> = allocation
        .render
        .iter()
        .map(|(k, _)| layout.page_view_proj(*k))
        .collect();
    let mut data = vec![0u8; (slots * STRIDE) as usize];
    data[..std::mem::size_of::<ShadowMapUniform>()].copy_from_slice(bytemuck::bytes_of(base));
    for (i, m) in page_matrices.iter().enumerate() {
        let mut faces = [Mat4::IDENTITY; MAX_FACES];
        faces[0] = *m;
        let u = ShadowMapUniform {
            faces,
            face: UVec4::ZERO,
            ..*base
        };
        let at = ((i as u64 + 1) * STRIDE) as usize;
        data[at..at + std::mem::size_of::<ShadowMapUniform>()]
            .copy_from_slice(bytemuck::bytes_of(&u));
    }
    gpu.queue.write_buffer(&state.uniforms, 0, &data);
    page_matrices
}

/// The depth pass of a page: 32-bit depth, the level's bias cap `clamp`.
fn page_depth_key(c: &ShadowMapConfig, shape: MapShape, clamp: f32) -> DepthPassKey {
    DepthPassKey {
        format: DepthFormat::D32f,
        cull: c.cull.for_shape(shape),
        bias: c.depth_bias,
        slope_bits: c.slope_bias.to_bits(),
        clamp_bits: clamp.to_bits(),
        moments: None,
        shape,
        virtual_map: true,
        parts: false,
        cutout: false,
        hashed: false,
    }
}
