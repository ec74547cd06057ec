//! One frame's passes of a shadow map that is not paged, per light sample:
//! the depth pass of every face (casters culled to the face's view and, for
//! a directional light, to those that can shadow what the camera sees),
//! the moment blur, the edge mask's chain and the screen-space lookup.

mod debug;
mod translucent;

use super::gpu::depth_pass::{Casters, DepthDraw, DepthPassKey, Surfaces};
use super::gpu::edge_mask::{ChainInput, ChainSource};
use super::gpu::maps::Maps;
use super::gpu::pipelines::{LookupKey, MapShape};
use super::gpu::uniform::slot_offset;
use super::projection::bias_cap::{BiasCaps, bias_clamp};
use super::projection::caster_cull::CasterCull;
use super::projection::setup::MapProjection;
use super::{CullFace, DepthFormat, LightSetup, ShadowMapConfig, ShadowMapTechnique, clear_op};
use crate::gpu::Stamps;
use crate::scene::{Light, LightType};
use crate::technique::MaskContext;
use crate::technique::light_space::outside_clip_volume;

/// What every light sample's passes share in one frame.
pub(in crate::technique::shadow_map) struct SamplePasses<'a> {
    pub maps: &'a Maps,
    /// The technique's bind group while the maps are rendered (no maps).
    pub render_group: wgpu::BindGroup,
    /// Moment maps A and B as blur sources.
    pub blur_groups: Option<[wgpu::BindGroup; 2]>,
    pub lookup_group: &'a wgpu::BindGroup,
    pub lookup_key: LookupKey,
    /// The depth pass's key but for its bias cap, which is per face.
    pub depth_key: DepthPassKey,
    pub layers: u32,
    /// Moment blur radius in texels (0: none).
    pub blur: u32,
    /// `stage=floor`: bare depth-only passes.
    pub floor: bool,
    /// Light samples (an area light's several, else 1).
    pub samples: usize,
    /// The frame's width over its height.
    pub aspect: f32,
}

/// Uniform slot `k` of face `f` of light sample `s`, as a dynamic offset.
fn slot(s: usize, f: u32, k: u32) -> u32 {
    slot_offset(s, f, k) as u32
}

impl ShadowMapTechnique {
    /// The pipelines that draw face `face` of `setup`, with the casters
    /// each takes.
    fn depth_draws(
        &self,
        ctx: &MaskContext,
        p: &SamplePasses,
        setup: &LightSetup,
        face: usize,
    ) -> Vec<DepthDraw> {
        let shape = p.depth_key.shape;
        if p.floor {
            return vec![DepthDraw {
                pipeline: self
                    .shared
                    .floor(ctx.gpu, p.depth_key.format.depth_texture(), shape),
                casters: Casters::All,
                surfaces: Surfaces::AllSolid,
            }];
        }
        let c = &self.config;
        self.shared.depth_passes(
            ctx.gpu,
            self.face_depth_key(ctx, p, setup, face),
            c.solid_front_bias,
            c.caster_alpha,
            &ctx.scene_gpu.draws,
        )
    }

    /// The depth pass's key for face `face` of `setup`: its bias cap.
    fn face_depth_key(
        &self,
        ctx: &MaskContext,
        p: &SamplePasses,
        setup: &LightSetup,
        face: usize,
    ) -> DepthPassKey {
        let c = &self.config;
        let side = c.map_side(ctx.light, ctx.gpu.max_texture_size());
        let caps = BiasCaps {
            directional: c.slope_bias_clamp,
            local: c.slope_bias_clamp_local,
        };
        DepthPassKey {
            clamp_bits: bias_clamp(setup, face, side, caps).to_bits(),
            ..p.depth_key
        }
    }

    /// Light sample `si`'s maps: each face's depth pass (and, with
    /// `blended_casters=transmit`, its translucent casters' two passes),
    /// then the moment blur. Returns the triangles drawn.
    pub(in crate::technique::shadow_map) fn record_maps(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        p: &SamplePasses,
        si: usize,
        setup: &LightSetup,
        light: &Light,
    ) -> u64 {
        let maps = p.maps;
        let caster_cull = (light.kind == LightType::Directional)
            .then(|| CasterCull::of(light.direction, ctx.camera, p.aspect, &ctx.scene_gpu.bounds))
            .flatten();
        let mut triangles = 0;
        for face in 0..p.layers {
            let f = face as usize;
            // The colour target beside the depth: moments or the 8-bit
            // depth (cleared to the far plane), or part IDs (to none).
            let color = match (&maps.moment, &maps.byte, &maps.part, p.floor) {
                (_, _, _, true) | (None, None, None, _) => None,
                (Some(m), _, _, _) => Some((&m[0].0[f], wgpu::Color::WHITE)),
                (None, Some(b), _, _) => Some((&b.0[f], wgpu::Color::WHITE)),
                (None, None, Some(part), _) => Some((&part.0[f], wgpu::Color::TRANSPARENT)),
            }
            .map(|(view, clear)| wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: clear_op(clear),
            });
            let colors = [color];
            let mut pass = ctx.gpu.render_pass(
                encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some("shadow map depth"),
                    color_attachments: if colors[0].is_some() { &colors } else { &[] },
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &maps.depth_layer_views[f],
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    ..Default::default()
                },
            );
            ctx.bind_frame_groups(&mut pass);
            pass.set_bind_group(
                crate::frame::OWN_GROUP,
                &p.render_group,
                &[slot(si, face, 0)],
            );
            // Casters outside this face's (or cascade's) view are not
            // drawn; paraboloid faces are view matrices, not frusta.
            let view_proj = setup.faces[f];
            let paraboloid = setup.projection == MapProjection::Paraboloid;
            let visible = |b: &crate::scene::Aabb| {
                (paraboloid || !outside_clip_volume(b, view_proj))
                    && caster_cull.as_ref().is_none_or(|c| c.may_shadow(b))
            };
            for draw in self.depth_draws(ctx, p, setup, f) {
                pass.set_pipeline(&draw.pipeline);
                triangles += ctx
                    .scene_gpu
                    .draw_visible(&mut pass, |d| draw.takes(d), visible);
            }
            drop(pass);
            if !p.floor {
                triangles += self.record_translucent(ctx, encoder, p, si, setup, face, &visible);
            }
        }
        self.record_blur(ctx, encoder, p, si);
        triangles
    }

    /// The moment maps' separable blur: A → B along x, B → A along y.
    fn record_blur(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        p: &SamplePasses,
        si: usize,
    ) {
        let (Some(m), Some(groups), true) =
            (&p.maps.moment, &p.blur_groups, p.blur > 0 && !p.floor)
        else {
            return;
        };
        for (k, src, dst) in [(1u32, 0usize, 1usize), (2, 1, 0)] {
            for face in 0..p.layers {
                let mut pass = ctx.gpu.render_pass(
                    encoder,
                    &wgpu::RenderPassDescriptor {
                        label: Some("shadow map blur"),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: &m[dst].0[face as usize],
                            depth_slice: None,
                            resolve_target: None,
                            ops: clear_op(wgpu::Color::WHITE),
                        })],
                        ..Default::default()
                    },
                );
                pass.set_pipeline(&self.shared.blur(ctx.gpu, p.lookup_key));
                ctx.bind_frame_groups(&mut pass);
                pass.set_bind_group(crate::frame::OWN_GROUP, &groups[src], &[slot(si, face, k)]);
                pass.draw(0..3, 0..1);
            }
        }
    }

    /// Light sample `si`'s lookup into the mask, after the edge mask's
    /// chain where there is one; timed by `stamps` (the chain also by
    /// `chain_stamps`). One sample writes the mask; several add 1/N each
    /// onto a cleared mask.
    pub(in crate::technique::shadow_map) fn record_lookup(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        p: &SamplePasses,
        si: usize,
        stamps: Option<&Stamps>,
        chain_stamps: Option<&Stamps>,
    ) {
        let gpu = ctx.gpu;
        if let Some(s) = stamps {
            s.stamp(encoder, si as u32, false);
        }
        if let Some(chain) = self.chain() {
            if let Some(s) = chain_stamps {
                s.stamp(encoder, si as u32, false);
            }
            chain.record(
                gpu,
                encoder,
                ChainInput {
                    depths: match &p.maps.byte {
                        Some(b) => ChainSource::Bytes(&b.1),
                        None => ChainSource::Depth(&p.maps.depth_array),
                    },
                    parts: p.maps.part.as_ref().map(|part| &part.1),
                },
            );
            if let Some(s) = chain_stamps {
                s.stamp(encoder, si as u32, true);
            }
        }
        let (load, accumulate) = match (p.samples, si) {
            (1, _) => (wgpu::LoadOp::Clear(wgpu::Color::WHITE), false),
            (_, 0) => (wgpu::LoadOp::Clear(wgpu::Color::BLACK), true),
            _ => (wgpu::LoadOp::Load, true),
        };
        let mut pass = crate::technique::mask_pass_with(encoder, ctx, "shadow map lookup", load);
        pass.set_pipeline(&self.shared.lookup(
            gpu,
            LookupKey {
                accumulate,
                ..p.lookup_key
            },
        ));
        if accumulate {
            let w = 1.0 / p.samples as f64;
            pass.set_blend_constant(wgpu::Color {
                r: w,
                g: w,
                b: w,
                a: w,
            });
        }
        ctx.bind_frame_groups(&mut pass);
        pass.set_bind_group(crate::frame::OWN_GROUP, p.lookup_group, &[slot(si, 0, 0)]);
        pass.draw(0..3, 0..1);
        drop(pass);
        if let Some(s) = stamps {
            s.stamp(encoder, si as u32, true);
        }
    }
}

/// The depth pass's and the lookup's pipeline keys of a map that is not
/// paged.
pub(super) fn dense_keys(
    c: &ShadowMapConfig,
    cull: CullFace,
    shape: MapShape,
    parts: bool,
    edge_mask: bool,
    transmit: bool,
) -> (DepthPassKey, LookupKey) {
    let (format, moments) = (c.format, c.filter.is_moment());
    let depth_key = DepthPassKey {
        format,
        cull,
        bias: c.depth_bias,
        slope_bits: c.slope_bias.to_bits(),
        clamp_bits: 0,
        moments: moments.then_some(c.filter),
        shape,
        virtual_map: false,
        parts,
        cutout: false,
        hashed: false,
    };
    let lookup_key = LookupKey {
        filter: c.filter,
        taps: if c.filter.uses_taps() { c.samples } else { 0 },
        byte_map: format == DepthFormat::R8,
        receiver_plane: c.receiver_plane,
        accumulate: false,
        edge_mask,
        virtual_map: false,
        marked_resident: false,
        wide_kernel: false,
        parts,
        transmit,
        shape,
    };
    (depth_key, lookup_key)
}
