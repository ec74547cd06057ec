//! What light icons and debug lines share: a pipeline drawn over the
//! rendered frame, depth-tested against the scene (LESS_EQUAL, no depth
//! writes), into a colour image of a given format.

use crate::gpu::GpuContext;

/// The parts of an overlay pipeline that differ between overlays.
pub struct OverlayPipeline<'a> {
    pub label: &'static str,
    pub layout: &'a wgpu::PipelineLayout,
    pub module: &'a wgpu::ShaderModule,
    pub vertex_entry: &'static str,
    pub fragment_entry: &'static str,
    pub vertex_buffer: wgpu::VertexBufferLayout<'a>,
    pub topology: wgpu::PrimitiveTopology,
    pub blend: Option<wgpu::BlendState>,
}

impl OverlayPipeline<'_> {
    /// The pipeline for a colour image of `color_format`, from the device's
    /// cache.
    pub fn get(&self, gpu: &GpuContext, color_format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
        gpu.cache.render_pipeline(self.label, &color_format, || {
            gpu.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(self.label),
                    layout: Some(self.layout),
                    vertex: wgpu::VertexState {
                        module: self.module,
                        entry_point: Some(self.vertex_entry),
                        compilation_options: Default::default(),
                        buffers: &[Some(self.vertex_buffer.clone())],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: self.topology,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: gpu.depth_format,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(crate::frame::DEPTH_NEARER_OR_EQUAL),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: self.module,
                        entry_point: Some(self.fragment_entry),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: color_format,
                            blend: self.blend,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        })
    }
}
