//! The translucent casters' transmittance pass (`blended_casters=transmit`,
//! `transmittance.wgsl`): each translucent caster's fragments in front of
//! the opaque depth map multiply their texel by 1 − opacity, so that each
//! texel holds the product over the translucent surfaces before the
//! nearest opaque caster; their nearest depth comes from
//! [`ShadowMapShared::translucent_depth_pass`].

use super::TRANSMITTANCE_FORMAT;
use super::pipelines::{LookupKey, MapShape, ShadowMapShared};
use crate::frame::VERTEX_LAYOUT;
use crate::gpu::GpuContext;
use crate::gpu::work::CountedRenderPass;

/// The blend that multiplies the target by 1 − the fragment's output.
const MULTIPLY_BY_ONE_MINUS: wgpu::BlendComponent = wgpu::BlendComponent {
    src_factor: wgpu::BlendFactor::Zero,
    dst_factor: wgpu::BlendFactor::OneMinusSrc,
    operation: wgpu::BlendOperation::Add,
};

impl ShadowMapShared {
    /// The transmittance pass into maps of `shape` (the pages of a virtual
    /// map where `virtual_map`), tested against an opaque depth map of
    /// `depth_format` (read only), both faces drawn.
    pub fn transmittance_pass(
        &self,
        gpu: &GpuContext,
        depth_format: wgpu::TextureFormat,
        shape: MapShape,
        virtual_map: bool,
    ) -> wgpu::RenderPipeline {
        let key = (depth_format, shape, virtual_map);
        gpu.cache
            .render_pipeline("shadow map transmittance", &key, || {
                let mut constants = shape.constants().to_vec();
                constants.push(("VIRTUAL", virtual_map as u32 as f64));
                let options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                let target = wgpu::ColorTargetState {
                    format: TRANSMITTANCE_FORMAT,
                    blend: Some(wgpu::BlendState {
                        color: MULTIPLY_BY_ONE_MINUS,
                        alpha: MULTIPLY_BY_ONE_MINUS,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                };
                gpu.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("shadow map transmittance"),
                        layout: Some(&self.pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some("vs_depth"),
                            compilation_options: options.clone(),
                            buffers: &[Some(VERTEX_LAYOUT)],
                        },
                        primitive: Default::default(),
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format: depth_format,
                            depth_write_enabled: Some(false),
                            depth_compare: Some(wgpu::CompareFunction::Less),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &self.module,
                            entry_point: Some("fs_transmittance"),
                            compilation_options: options,
                            targets: &[Some(target)],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
            })
    }

    /// Clears a virtual map page's slot of the transmittance pool to 1,
    /// in a pass whose depth (the pool's, d32f) is read only.
    pub fn transmittance_clear(&self, gpu: &GpuContext, key: LookupKey) -> wgpu::RenderPipeline {
        self.fullscreen(
            gpu,
            "virtual shadow map transmittance clear",
            "fs_clear_transmittance",
            key,
            &[Some(TRANSMITTANCE_FORMAT.into())],
            Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
        )
    }
}

/// The pass that draws the translucent casters' nearest depth into the
/// layer `view`, which starts as `load` says: cleared to the far plane for
/// a whole face, kept for a pool layer whose pages clear their own slots.
pub fn translucent_depth_target<'e>(
    gpu: &GpuContext,
    encoder: &'e mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<f32>,
) -> CountedRenderPass<'e> {
    gpu.render_pass(
        encoder,
        &wgpu::RenderPassDescriptor {
            label: Some("shadow map translucent depth"),
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        },
    )
}

/// The pass that multiplies the translucent casters' transmittance into
/// the layer `view` (starting as `load` says), against the opaque depth
/// layer `opaque`, read only: translucent casters behind it let no light
/// through that reaches a receiver.
pub fn transmittance_target<'e>(
    gpu: &GpuContext,
    encoder: &'e mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    opaque: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) -> CountedRenderPass<'e> {
    gpu.render_pass(
        encoder,
        &wgpu::RenderPassDescriptor {
            label: Some("shadow map transmittance"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: opaque,
                depth_ops: None,
                stencil_ops: None,
            }),
            ..Default::default()
        },
    )
}
