//! Debug lines drawn over a rendered frame, depth-tested against the scene:
//! what techniques offer as debug views (light frusta, silhouette edges).

use super::overlay::OverlayPipeline;
use crate::frame::FrameTargets;
use crate::gpu::GpuContext;
use crate::technique::DebugLine;
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LineVertex {
    position: [f32; 3],
    color: [f32; 4],
}

pub struct LineRenderer {
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
}

impl LineRenderer {
    pub fn new(gpu: &GpuContext, frame_layout: &wgpu::BindGroupLayout) -> LineRenderer {
        let device = &gpu.device;
        let module = crate::frame::shader_module(gpu, "lines", &[include_str!("lines.wgsl")]);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lines"),
            bind_group_layouts: &[Some(frame_layout)],
            immediate_size: 0,
        });
        LineRenderer { module, layout }
    }

    /// The pipeline drawing into a colour image of `color_format`.
    fn pipeline(
        &self,
        gpu: &GpuContext,
        color_format: wgpu::TextureFormat,
    ) -> wgpu::RenderPipeline {
        OverlayPipeline {
            label: "lines",
            layout: &self.layout,
            module: &self.module,
            vertex_entry: "vs_line",
            fragment_entry: "fs_line",
            vertex_buffer: wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<LineVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
            },
            topology: wgpu::PrimitiveTopology::LineList,
            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
        }
        .get(gpu, color_format)
    }

    /// Draws `lines` onto the frame's colour image.
    pub fn draw(&self, gpu: &GpuContext, frame: &FrameTargets, lines: &[DebugLine]) {
        if lines.is_empty() {
            return;
        }
        let vertices: Vec<LineVertex> = lines
            .iter()
            .flat_map(|l| {
                [l.a, l.b].map(|p| LineVertex {
                    position: p.to_array(),
                    color: l.color,
                })
            })
            .collect();
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("debug lines"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("debug lines"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: frame.color_view(),
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(frame.kept_depth()),
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline(gpu, frame.color_format()));
            pass.set_bind_group(0, frame.frame_bind_group(), &[]);
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..vertices.len() as u32, 0..1);
        }
        gpu.queue.submit([enc.finish()]);
    }
}
