//! The shadow volumes' debug views: the volumes drawn translucent over the
//! scene, and the silhouette edges as lines.

use super::silhouette::{CasterPlan, VolumeKind, VolumeMesh};
use super::{ShadowVolumeRenderer, ZFAIL_ARGS};
use crate::technique::{DebugLine, MaskContext};

impl ShadowVolumeRenderer {
    /// The debug view: the scene with the volumes over it, translucent.
    pub(super) fn render_debug(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        unclipped: bool,
    ) {
        let (w, h) = (ctx.frame.width(), ctx.frame.height());
        if self
            .debug
            .as_ref()
            .is_none_or(|t| (t.width(), t.height()) != (w, h))
        {
            self.debug = Some(crate::gpu::texture_2d(
                &ctx.gpu.device,
                "shadow volume debug",
                w,
                h,
                1,
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            ));
        }
        let volume_pipeline = self.shared.debug_volume_pipeline(ctx.gpu, unclipped);
        let view = self
            .debug
            .as_ref()
            .expect("made above")
            .create_view(&Default::default());
        let mut pass = crate::technique::pass_over_frame_depth(
            encoder,
            ctx,
            "shadow volume debug",
            &view,
            wgpu::LoadOp::Clear(wgpu::Color::BLACK),
            false,
        );
        ctx.bind_frame_groups(&mut pass);
        pass.set_bind_group(crate::frame::OWN_GROUP, group, &[]);
        pass.set_pipeline(&self.shared.debug_scene_pipeline);
        pass.draw(0..3, 0..1);
        pass.set_pipeline(&volume_pipeline);
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed_indirect(&self.args, 0);
        pass.draw_indexed_indirect(&self.args, ZFAIL_ARGS);
    }
}

/// World-space silhouette edges of the silhouette casters, for the debug view.
pub(super) fn silhouette_lines(vm: &VolumeMesh, plans: &[CasterPlan]) -> Vec<DebugLine> {
    let mut lines = vec![];
    for (c, plan) in vm.casters.iter().zip(plans) {
        if plan.kind != VolumeKind::Silhouette {
            continue;
        }
        let world = |v: u32| {
            c.model
                .transform_point3(vm.positions[v as usize].truncate())
        };
        lines.extend(plan.extruded_edges(vm, c).map(|(e, _)| DebugLine {
            a: world(e.a),
            b: world(e.b),
            color: [0.2, 1.0, 0.3, 1.0],
        }));
    }
    lines
}
