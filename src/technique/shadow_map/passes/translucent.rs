//! `blended_casters=transmit`: after a face's opaque depth pass, the
//! translucent casters' two passes into the face's transmittance maps —
//! their nearest depth, and their transmittance in front of the opaque
//! depth (`gpu::transmittance`).

use super::{SamplePasses, slot};
use crate::scene::Aabb;
use crate::technique::MaskContext;
use crate::technique::shadow_map::ShadowMapTechnique;
use crate::technique::shadow_map::gpu::depth_pass::DepthDraw;
use crate::technique::shadow_map::gpu::transmittance::{
    translucent_depth_target, transmittance_target,
};
use crate::technique::shadow_map::projection::setup::LightSetup;

impl ShadowMapTechnique {
    /// Face `face` of light sample `si`: the translucent casters' nearest
    /// depth and their transmittance, where the maps have them. Returns the
    /// triangles drawn.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record_translucent(
        &self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        p: &SamplePasses,
        si: usize,
        setup: &LightSetup,
        face: u32,
        visible: &impl Fn(&Aabb) -> bool,
    ) -> u64 {
        let Some(maps) = p.maps.transmit.as_ref() else {
            return 0;
        };
        let f = face as usize;
        let depth_draw = self
            .shared
            .translucent_depth_pass(ctx.gpu, self.face_depth_key(ctx, p, setup, f));
        let mut pass =
            translucent_depth_target(ctx.gpu, encoder, &maps.depth.0[f], wgpu::LoadOp::Clear(1.0));
        let mut triangles = draw(ctx, &mut pass, p, si, face, &depth_draw, visible);
        drop(pass);
        let transmit = DepthDraw {
            pipeline: self.shared.transmittance_pass(
                ctx.gpu,
                p.depth_key.format.depth_texture(),
                p.depth_key.shape,
                false,
            ),
            ..depth_draw
        };
        let mut pass = transmittance_target(
            ctx.gpu,
            encoder,
            &maps.transmittance.0[f],
            &p.maps.depth_layer_views[f],
            wgpu::LoadOp::Clear(wgpu::Color::WHITE),
        );
        triangles += draw(ctx, &mut pass, p, si, face, &transmit, visible);
        triangles
    }
}

/// `d`'s casters seen from face `face` of sample `si`, drawn into `pass`.
fn draw(
    ctx: &MaskContext,
    pass: &mut wgpu::RenderPass,
    p: &SamplePasses,
    si: usize,
    face: u32,
    d: &DepthDraw,
    visible: &impl Fn(&Aabb) -> bool,
) -> u64 {
    ctx.bind_frame_groups(pass);
    pass.set_bind_group(
        crate::frame::OWN_GROUP,
        &p.render_group,
        &[slot(si, face, 0)],
    );
    pass.set_pipeline(&d.pipeline);
    ctx.scene_gpu.draw_visible(pass, |c| d.takes(c), visible)
}
