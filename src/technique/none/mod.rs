//! `none`: every surface fully lit. It still goes through the whole mask
//! path (a clear of the mask layer to 1), so its cost is the baseline that
//! the other techniques' frame times are divided by.

use super::{Family, MaskContext, Preset, ShadowTechnique};
use anyhow::Result;

pub static FAMILY: Family = Family {
    id: "none",
    summary: "no shadows: the visibility mask is 1 everywhere",
    capabilities: super::Capabilities {
        point_lights: false,
        spot_lights: false,
        directional_lights: false,
        soft_shadows: false,
        self_shadowing: false,
        open_meshes: false,
        curved_receivers: false,
        cutout_casters: false,
    },
    params: &[],
    presets: &[Preset {
        name: "default",
        summary: "all lit",
        values: &[],
    }],
    create: |_, _| Ok(Box::new(NoShadows)),
};

pub struct NoShadows;

impl ShadowTechnique for NoShadows {
    fn configure(&mut self, _params: &super::ParamValues) -> Result<()> {
        Ok(())
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        crate::frame::clear_mask(ctx.gpu, encoder, ctx.target, 1.0);
        Ok(())
    }
}
