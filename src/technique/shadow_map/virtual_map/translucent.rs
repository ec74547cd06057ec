//! `blended_casters=transmit` on a paged map: after a pool layer's new
//! pages are rendered, each page's translucent casters into the two pools
//! beside it — their nearest depth, and their transmittance in front of the
//! page's opaque depth (`gpu::transmittance`) — so that a cached page keeps
//! its translucent casters with its depth.

use super::passes::{PageSlots, page_sees};
use crate::technique::MaskContext;
use crate::technique::shadow_map::ShadowMapTechnique;
use crate::technique::shadow_map::gpu::maps::TransmitMaps;
use crate::technique::shadow_map::gpu::pipelines::LookupKey;

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
        let mut pass = gpu.render_pass(
            encoder,
            &wgpu::RenderPassDescriptor {
                label: Some("virtual shadow map translucent depth"),
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &maps.depth.0[layer],
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
        let colors = [Some(wgpu::RenderPassColorAttachment {
            view: &maps.transmittance.0[layer],
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })];
        let mut pass = gpu.render_pass(
            encoder,
            &wgpu::RenderPassDescriptor {
                label: Some("virtual shadow map transmittance"),
                color_attachments: &colors,
                // The pages' opaque depth, read only.
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &slots.atlas.layer_views[layer],
                    depth_ops: None,
                    stencil_ops: None,
                }),
                ..Default::default()
            },
        );
        ctx.bind_frame_groups(&mut pass);
        let clear = self.shared.transmittance_clear(gpu, lookup_key);
        let transmit = self.shared.transmittance_pass(
            gpu,
            wgpu::TextureFormat::Depth32Float,
            lookup_key.shape,
            true,
        );
        for &(i, (key, slot)) in slots.on_layer {
            slots.select(&mut pass, i, *slot);
            pass.set_pipeline(&clear);
            pass.draw(0..3, 0..1);
            pass.set_pipeline(&transmit);
            let draw = self
                .shared
                .translucent_depth_pass(gpu, slots.level_keys[key.level as usize]);
            let sees = page_sees(slots.matrices[i], slots.eye);
            triangles += ctx
                .scene_gpu
                .draw_visible(&mut pass, |d| draw.takes(d), sees);
        }
        triangles
    }
}
