//! The passes of a paged map's frame: marking the pages the pixels need
//! (and reading the marks back), and rendering new pages into the pool.

use super::VirtualState;
use super::atlas::Atlas;
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
use glam::{Mat4, UVec4, Vec3};

impl ShadowMapTechnique {
    /// The bind group of a virtual map's passes: with `atlas`, its pools
    /// (marking and lookup); without, placeholders (the pages' passes,
    /// which render into them).
    pub(super) fn page_group(
        &self,
        ctx: &MaskContext,
        state: &VirtualState,
        atlas: Option<&Atlas>,
    ) -> wgpu::BindGroup {
        let empty = MapBindings::empty(&self.shared, &state.uniforms);
        let transmit = atlas.and_then(|a| a.transmit.as_ref());
        self.bind_group(
            ctx,
            MapBindings {
                depth: atlas.map_or(empty.depth, |a| &a.array),
                transmit_depth: transmit.map_or(empty.transmit_depth, |t| &t.depth.1),
                transmittance: transmit.map_or(empty.transmittance, |t| &t.transmittance.1),
                virtual_buffers: [
                    &state.marks,
                    &state.table,
                    &state.levels,
                    &state.pixel_levels,
                ],
                ..empty
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
        let mark_group = self.page_group(ctx, state, state.atlas.as_ref());
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
        let render_group = self.page_group(ctx, state, None);
        // A clipmap level's bias cap follows its texels, as a cascade's
        // does; each level's pipelines are looked up once, when it has pages.
        let level_keys = page_depth_keys(&c, layout, lookup_key.shape);
        let mut depth_pipelines: Vec<Option<Vec<DepthDraw>>> = vec![None; layout.levels.len()];
        let mut depth_pipeline = |level: u32| {
            depth_pipelines[level as usize]
                .get_or_insert_with(|| {
                    self.shared.depth_passes(
                        gpu,
                        level_keys[level as usize],
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
            let slots = PageSlots {
                atlas,
                on_layer: &on_layer,
                matrices: &page_matrices,
                eye: layout.eye,
                group: &render_group,
                level_keys: &level_keys,
            };
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
            for &(i, (key, slot)) in &on_layer {
                slots.select(&mut pass, i, *slot);
                pass.set_pipeline(&clear_pipeline);
                pass.draw(0..3, 0..1);
                for draw in depth_pipeline(key.level) {
                    pass.set_pipeline(&draw.pipeline);
                    map_triangles += ctx.scene_gpu.draw_visible(
                        &mut pass,
                        |d| draw.takes(d),
                        page_sees(page_matrices[i], layout.eye),
                    );
                }
            }
            drop(pass);
            if let Some(maps) = &atlas.transmit {
                map_triangles +=
                    self.record_translucent_pages(ctx, encoder, maps, layer, &slots, lookup_key);
            }
        }
        map_triangles
    }
}

/// Whether a caster of world bounds `b` can show in the page of `matrix`
/// (positions relative to the camera at `eye`).
pub(super) fn page_sees(matrix: Mat4, eye: Vec3) -> impl Fn(&Aabb) -> bool + Copy {
    move |b| {
        !outside_clip_volume(
            &Aabb {
                min: b.min - eye,
                max: b.max - eye,
            },
            matrix,
        )
    }
}

/// The pages of one pool layer rendered this frame: their slots, matrices
/// and the bind group their passes draw with.
pub(super) struct PageSlots<'a> {
    pub atlas: &'a Atlas,
    /// Each page's index among the frame's new pages, its key and slot.
    pub on_layer: &'a [(usize, &'a (PageKey, u32))],
    pub matrices: &'a [Mat4],
    pub eye: Vec3,
    pub group: &'a wgpu::BindGroup,
    /// Each level's depth-pass key.
    pub level_keys: &'a [DepthPassKey],
}

impl PageSlots<'_> {
    /// Points `pass` at page `i`'s slot and uniform.
    pub fn select(&self, pass: &mut wgpu::RenderPass, i: usize, slot: u32) {
        let (_, x, y) = self.atlas.place(slot);
        let side = self.atlas.slot_texels();
        pass.set_viewport(x as f32, y as f32, side as f32, side as f32, 0.0, 1.0);
        pass.set_scissor_rect(x, y, side, side);
        let offset = ((i as u64 + 1) * STRIDE) as u32;
        pass.set_bind_group(crate::frame::OWN_GROUP, self.group, &[offset]);
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

/// Each level's page depth pass: a clipmap level's bias cap follows its
/// texels, as a cascade's does.
fn page_depth_keys(
    c: &ShadowMapConfig,
    layout: &VirtualLayout,
    shape: MapShape,
) -> Vec<DepthPassKey> {
    layout
        .levels
        .iter()
        .map(|level| {
            let clamp = if layout.orthographic {
                texel_bias_clamp(
                    level.texel_world,
                    layout.far - layout.near,
                    c.slope_bias_clamp,
                )
            } else {
                0.0
            };
            page_depth_key(c, shape, clamp)
        })
        .collect()
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
