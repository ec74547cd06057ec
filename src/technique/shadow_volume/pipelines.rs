//! The shadow-volume family's GPU programs, shared by every light's
//! instance on a device: the volume shader, the extrusion compute shader,
//! their layouts and fixed pipelines ([`VolumeShared`]), and the
//! stencil-counting pipelines keyed by [`VolumeKey`] from the device's cache.

use crate::frame::MASK_FORMAT;
use crate::gpu::GpuContext;

/// What a volume pipeline depends on.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct VolumeKey {
    pub zfail: bool,
    /// 0: two-sided, one draw; 1 and 2: the increment and decrement draws.
    pub pass: u8,
    pub unclipped: bool,
}

/// The family's shaders, layouts and fixed pipelines, shared per device;
/// the volume pipelines come from the device's cache by [`VolumeKey`].
pub struct VolumeShared {
    pub layout: wgpu::BindGroupLayout,
    pub pipeline_layout: wgpu::PipelineLayout,
    pub module: wgpu::ShaderModule,
    pub shadow_pipeline: wgpu::RenderPipeline,
    pub debug_scene_pipeline: wgpu::RenderPipeline,
    pub extrude_layout: wgpu::BindGroupLayout,
    pub extrude_edges: wgpu::ComputePipeline,
    pub extrude_faces: wgpu::ComputePipeline,
}

/// The stencil operations of one volume pipeline.
fn stencil_state(key: VolumeKey) -> (wgpu::StencilState, Option<wgpu::Face>) {
    use wgpu::StencilOperation as Op;
    let face = |depth_fail_op, pass_op| wgpu::StencilFaceState {
        compare: wgpu::CompareFunction::Always,
        fail_op: Op::Keep,
        depth_fail_op,
        pass_op,
    };
    // The operation on the counted event: depth pass (z-pass) or fail (z-fail).
    let on = |op| {
        if key.zfail {
            face(op, Op::Keep)
        } else {
            face(Op::Keep, op)
        }
    };
    // z-pass counts entries through front faces, z-fail exits through back faces.
    let (increment_face, decrement_face) = if key.zfail {
        (wgpu::Face::Back, wgpu::Face::Front)
    } else {
        (wgpu::Face::Front, wgpu::Face::Back)
    };
    let (front, back, cull) = match key.pass {
        0 => {
            let (inc, dec) = (on(Op::IncrementWrap), on(Op::DecrementWrap));
            if key.zfail {
                (dec, inc, None)
            } else {
                (inc, dec, None)
            }
        }
        // Increments first so that saturation at 0 cannot lose a count.
        1 => (
            on(Op::IncrementClamp),
            on(Op::IncrementClamp),
            Some(decrement_face),
        ),
        _ => (
            on(Op::DecrementClamp),
            on(Op::DecrementClamp),
            Some(increment_face),
        ),
    };
    (
        wgpu::StencilState {
            front,
            back,
            read_mask: 0xff,
            write_mask: 0xff,
        },
        cull,
    )
}

impl VolumeShared {
    pub fn new(gpu: &GpuContext) -> VolumeShared {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow volume"),
            entries: &[
                crate::gpu::uniform_entry(gpu, 0, wgpu::ShaderStages::VERTEX_FRAGMENT, false),
                crate::gpu::storage_entry(1, wgpu::ShaderStages::VERTEX, true),
            ],
        });
        let module =
            crate::frame::technique_shader(gpu, "shadow volume", &[include_str!("volume.wgsl")]);
        let pipeline_layout = crate::technique::pipeline_layout(gpu, "shadow volume", &layout);
        let fullscreen =
            |label: &str, fs: &str, target: wgpu::ColorTargetState, stencil: wgpu::StencilState| {
                crate::technique::fullscreen_pipeline(
                    gpu,
                    label,
                    &pipeline_layout,
                    crate::technique::FragmentEntry::new(&module, fs),
                    &[Some(target)],
                    Some(crate::technique::frame_depth_read(gpu, stencil)),
                )
            };
        let not_zero = wgpu::StencilFaceState {
            compare: wgpu::CompareFunction::NotEqual,
            ..wgpu::StencilFaceState::IGNORE
        };
        let shadow_pipeline = fullscreen(
            "shadow volume: stencil to mask",
            "fs_shadow",
            MASK_FORMAT.into(),
            wgpu::StencilState {
                front: not_zero,
                back: not_zero,
                read_mask: 0xff,
                write_mask: 0,
            },
        );
        let debug_scene_pipeline = fullscreen(
            "shadow volume debug: scene",
            "fs_debug_scene",
            wgpu::TextureFormat::Rgba8Unorm.into(),
            Default::default(),
        );
        let extrude_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow volume extrusion"),
            entries: &[
                crate::gpu::uniform_entry(gpu, 0, wgpu::ShaderStages::COMPUTE, false),
                crate::gpu::storage_entry(1, wgpu::ShaderStages::COMPUTE, true),
                crate::gpu::storage_entry(2, wgpu::ShaderStages::COMPUTE, true),
                crate::gpu::storage_entry(3, wgpu::ShaderStages::COMPUTE, true),
                crate::gpu::storage_entry(4, wgpu::ShaderStages::COMPUTE, false),
                crate::gpu::storage_entry(5, wgpu::ShaderStages::COMPUTE, false),
            ],
        });
        let extrude_module = crate::gpu::compose_shader(
            gpu,
            "shadow volume extrusion",
            &[include_str!("extrude.wgsl")],
        );
        let extrude_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shadow volume extrusion"),
                bind_group_layouts: &[Some(&extrude_layout)],
                immediate_size: 0,
            });
        let compute = |entry: &str| {
            gpu.cache
                .compute_pipeline("shadow volume extrusion", &entry, || {
                    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&extrude_pipeline_layout),
                        module: &extrude_module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
                })
        };
        VolumeShared {
            extrude_edges: compute("cs_edges"),
            extrude_faces: compute("cs_faces"),
            extrude_layout,
            layout,
            pipeline_layout,
            module,
            shadow_pipeline,
            debug_scene_pipeline,
        }
    }

    /// The stencil-counting pipeline of `key`.
    pub fn volume_pipeline(&self, gpu: &GpuContext, key: VolumeKey) -> wgpu::RenderPipeline {
        let (module, layout) = (&self.module, &self.pipeline_layout);
        let device = &gpu.device;
        gpu.cache.render_pipeline("shadow volume", &key, || {
            let (stencil, cull_mode) = stencil_state(key);
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("shadow volume"),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_volume"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode,
                    unclipped_depth: key.unclipped,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: gpu.depth_format,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(crate::frame::DEPTH_NEARER),
                    stencil,
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some("fs_volume"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: MASK_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }

    /// The debug view's pipeline drawing the volumes translucent.
    pub fn debug_volume_pipeline(&self, gpu: &GpuContext, unclipped: bool) -> wgpu::RenderPipeline {
        let (module, layout) = (&self.module, &self.pipeline_layout);
        let device = &gpu.device;
        gpu.cache
            .render_pipeline("shadow volume debug: volumes", &unclipped, || {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("shadow volume debug: volumes"),
                    layout: Some(layout),
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: Some("vs_volume"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        unclipped_depth: unclipped,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: gpu.depth_format,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(crate::frame::DEPTH_NEARER),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: Some("fs_debug_volume"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: wgpu::TextureFormat::Rgba8Unorm,
                            blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stencil_operations_count_entries_and_exits() {
        use wgpu::StencilOperation as Op;
        let (s, cull) = stencil_state(VolumeKey {
            zfail: false,
            pass: 0,
            unclipped: false,
        });
        assert_eq!(
            (s.front.pass_op, s.back.pass_op, cull),
            (Op::IncrementWrap, Op::DecrementWrap, None)
        );
        let (s, _) = stencil_state(VolumeKey {
            zfail: true,
            pass: 0,
            unclipped: false,
        });
        assert_eq!(
            (s.front.depth_fail_op, s.back.depth_fail_op),
            (Op::DecrementWrap, Op::IncrementWrap)
        );
        // Two passes: back faces increment first for z-fail (front culled).
        let (s, cull) = stencil_state(VolumeKey {
            zfail: true,
            pass: 1,
            unclipped: false,
        });
        assert_eq!(
            (s.back.depth_fail_op, cull),
            (Op::IncrementClamp, Some(wgpu::Face::Front))
        );
        let (s, cull) = stencil_state(VolumeKey {
            zfail: false,
            pass: 2,
            unclipped: false,
        });
        assert_eq!(
            (s.back.pass_op, cull),
            (Op::DecrementClamp, Some(wgpu::Face::Front))
        );
    }
}
