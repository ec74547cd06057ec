//! `blended_casters=transmit` on a paged map: after a pool layer's new
//! pages are rendered, each page's translucent casters into the two pools
//! beside it — their nearest depth, and their transmittance in front of the
//! page's opaque depth (`gpu::transmittance`) — so that a cached page keeps
//! its translucent casters with its depth.

use super::passes::{PageSlots, page_sees};
use crate::technique::MaskContext;
use crate::technique::shadow_map::ShadowMapTechnique;
use crate::technique::shadow_map::gpu::depth_pass::{Casters, DepthDraw, Surfaces};
use crate::technique::shadow_map::gpu::maps::TransmitMaps;
use crate::technique::shadow_map::gpu::pipelines::LookupKey;
use crate::technique::shadow_map::gpu::transmittance::{
    translucent_depth_target, transmittance_target,
};

impl ShadowMapTechnique {
    /// The translucent passes of the pages `slots` holds on pool layer
    /// `layer` (each clears its own slot; the layer's other pages stay);
    /// returns the triangles drawn.
    pub(super) fn record_translucent_pages(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        maps: &TransmitMaps,
        layer: usize,
        slots: &PageSlots,
        lookup_key: LookupKey,
    ) -> u64 {
        let gpu = ctx.gpu;
        let mut triangles = 0;
        let mut pass =
            translucent_depth_target(gpu, encoder, &maps.depth.0[layer], wgpu::LoadOp::Load);
        ctx.bind_frame_groups(&mut pass);
        let clear_depth = self.shared.clear_page(gpu, lookup_key);
        for &(i, (key, slot)) in slots.on_layer {
            slots.select(&mut pass, i, *slot);
            pass.set_pipeline(&clear_depth);
            pass.draw(0..3, 0..1);
            let draw = self
                .shared
                .translucent_depth_pass(gpu, slots.level_keys[key.level as usize]);
            pass.set_pipeline(&draw.pipeline);
            let sees = page_sees(slots.matrices[i], slots.eye);
            triangles += ctx
                .scene_gpu
                .draw_visible(&mut pass, |d| draw.takes(d), sees);
        }
        drop(pass);
        let mut pass = transmittance_target(
            gpu,
            encoder,
            &maps.transmittance.0[layer],
            &slots.atlas.layer_views[layer],
            wgpu::LoadOp::Load,
        );
        ctx.bind_frame_groups(&mut pass);
        let clear = self.shared.transmittance_clear(gpu, lookup_key);
        let transmit = DepthDraw {
            pipeline: self.shared.transmittance_pass(
                gpu,
                wgpu::TextureFormat::Depth32Float,
                lookup_key.shape,
                true,
            ),
            casters: Casters::All,
            surfaces: Surfaces::Translucent,
        };
        for &(i, (_, slot)) in slots.on_layer {
            slots.select(&mut pass, i, *slot);
            pass.set_pipeline(&clear);
            pass.draw(0..3, 0..1);
            pass.set_pipeline(&transmit.pipeline);
            let sees = page_sees(slots.matrices[i], slots.eye);
            triangles += ctx
                .scene_gpu
                .draw_visible(&mut pass, |d| transmit.takes(d), sees);
        }
        triangles
    }
}
