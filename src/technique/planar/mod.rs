//! `planar`: projected planar shadows (Blinn 1988; [000] §2, [001] §2, [003]).
//! Each caster is drawn a second time through the shadow matrix
//! `M = (P·L)·I − L·Pᵀ` onto each receiver plane, into the visibility mask.
//! With `stencil` on, the visible pixels of plane i are first tagged with
//! id i + 1 (001 Algorithm 2.1) and a shadow fragment passes only where the
//! stencil equals the id and zeroes it, so each pixel darkens once and the
//! shadow stays on the plane. Anti-shadows (caster beyond the light) are
//! clipped by the rasterizer (w < 0 after M), false shadows (caster behind the
//! plane) are discarded per fragment.

use super::light_space::shadow_matrix;
use super::{Family, MaskContext, ParamSpec, ParamValues, Preset, ShadowTechnique};
use crate::frame::{Compose, MASK_FORMAT, VERTEX_LAYOUT};
use crate::gpu::GpuContext;
use crate::scene::planes::{MAX_PLANES, ReceiverPlane, receiver_planes};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};
use std::sync::Arc;

const DEPTH_OFFSET: ParamSpec = ParamSpec::float(
    "depth_offset",
    32.0,
    0.0,
    4096.0,
    1.0,
    "offset of the flattened shadows towards the camera, in units of 2^-20 of the depth range, against z-fighting with the receiver",
);
const STENCIL: ParamSpec = ParamSpec::boolean(
    "stencil",
    true,
    "stencil-tag each receiver plane (id = index + 1): each pixel darkens once and shadows stay on the plane; off shows double darkening and spill",
);

pub static FAMILY: Family = Family {
    id: "planar",
    summary: "projected planar shadows: casters flattened onto receiver planes by the shadow matrix",
    capabilities: super::Capabilities {
        point_lights: true,
        spot_lights: true,
        directional_lights: true,
        soft_shadows: false,
        self_shadowing: false,
        open_meshes: true,
        curved_receivers: false,
        cutout_casters: true,
    },
    params: &[
        ParamSpec::DARKENING,
        DEPTH_OFFSET,
        STENCIL,
        ParamSpec::COMPOSE,
    ],
    presets: &[
        Preset {
            name: "default",
            summary: "stencil on, black shadows, relight",
            values: &[],
        },
        Preset {
            name: "no-stencil",
            summary: "no stencil: double darkening where flattened triangles overlap, shadows spill off the plane",
            values: &[(STENCIL.name, "false"), (ParamSpec::DARKENING.name, "0.6")],
        },
        Preset {
            name: "darken",
            summary: "the documents' look: a half-transparent shadow colour blended over the lit image",
            values: &[
                (ParamSpec::DARKENING.name, "0.5"),
                (ParamSpec::COMPOSE.name, "darken"),
            ],
        },
    ],
    create: |gpu, params| {
        Ok(Box::new(PlanarShadows::new(
            gpu,
            PlanarConfig::parse(params)?,
        )))
    },
};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PlanarUniform {
    shadow: Mat4,
    plane: Vec4,
    params: Vec4,
    _pad: [Vec4; 10],
}

/// The planar family's parameters, parsed.
#[derive(Clone, Copy, Debug)]
struct PlanarConfig {
    /// Mask value inside a shadow (1 − darkening).
    visibility: f32,
    /// Offset towards the camera, NDC depth.
    depth_offset: f32,
    stencil: bool,
    compose: Compose,
}

impl PlanarConfig {
    fn parse(p: &ParamValues) -> Result<PlanarConfig> {
        Ok(PlanarConfig {
            visibility: 1.0 - p.float(&ParamSpec::DARKENING)?,
            depth_offset: p.float(&DEPTH_OFFSET)? / (1u32 << 20) as f32,
            stencil: p.flag(&STENCIL)?,
            compose: p.choice(&ParamSpec::COMPOSE)?,
        })
    }
}

/// The family's shader, layouts and pipelines, shared per device.
struct PlanarShared {
    layout: wgpu::BindGroupLayout,
    tag: wgpu::RenderPipeline,
    /// [stencil off, stencil on]
    flatten: [wgpu::RenderPipeline; 2],
}

pub struct PlanarShadows {
    shared: Arc<PlanarShared>,
    config: PlanarConfig,
    uniforms: wgpu::Buffer,
    planes: Option<(u64, Vec<ReceiverPlane>)>,
    drawn_planes: usize,
}

impl PlanarShared {
    fn new(gpu: &GpuContext) -> PlanarShared {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("planar"),
            entries: &[crate::gpu::uniform_entry(
                gpu,
                0,
                wgpu::ShaderStages::VERTEX_FRAGMENT,
                true,
            )],
        });
        let module = crate::frame::technique_shader(gpu, "planar", &[include_str!("planar.wgsl")]);
        let pl = super::pipeline_layout(gpu, "planar", &layout);
        let stencil_face = |compare, pass_op| wgpu::StencilFaceState {
            compare,
            fail_op: wgpu::StencilOperation::Keep,
            depth_fail_op: wgpu::StencilOperation::Keep,
            pass_op,
        };
        let pipeline = |label: &str,
                        vs: &str,
                        fs: &str,
                        buffers: &[Option<wgpu::VertexBufferLayout>],
                        depth: wgpu::DepthStencilState,
                        target: wgpu::ColorTargetState| {
            gpu.cache.render_pipeline(label, &(vs, fs, &depth), || {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pl),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: Some(depth.clone()),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[Some(target)],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
        };
        let stencil = |face: wgpu::StencilFaceState, write: u32| wgpu::StencilState {
            front: face,
            back: face,
            read_mask: 0xff,
            write_mask: write,
        };
        let tag = pipeline(
            "planar tag",
            "vs_fullscreen",
            "fs_tag",
            &[],
            super::frame_depth_read(
                gpu,
                stencil(
                    stencil_face(
                        wgpu::CompareFunction::Always,
                        wgpu::StencilOperation::Replace,
                    ),
                    0xff,
                ),
            ),
            wgpu::ColorTargetState {
                format: MASK_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            },
        );
        let multiply = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::Src,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::REPLACE,
        };
        let flatten = |with_stencil: bool| {
            let face = if with_stencil {
                stencil_face(wgpu::CompareFunction::Equal, wgpu::StencilOperation::Zero)
            } else {
                stencil_face(wgpu::CompareFunction::Always, wgpu::StencilOperation::Keep)
            };
            pipeline(
                "planar flatten",
                "vs_flatten",
                "fs_flatten",
                &[Some(VERTEX_LAYOUT)],
                wgpu::DepthStencilState {
                    format: gpu.depth_format,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(crate::frame::DEPTH_NEARER_OR_EQUAL),
                    stencil: stencil(face, if with_stencil { 0xff } else { 0 }),
                    bias: Default::default(),
                },
                wgpu::ColorTargetState {
                    format: MASK_FORMAT,
                    blend: Some(multiply),
                    write_mask: wgpu::ColorWrites::RED,
                },
            )
        };
        PlanarShared {
            layout,
            tag,
            flatten: [flatten(false), flatten(true)],
        }
    }
}

impl PlanarShadows {
    fn new(gpu: &GpuContext, config: PlanarConfig) -> PlanarShadows {
        PlanarShadows {
            shared: gpu.cache.shared(|| PlanarShared::new(gpu)),
            config,
            uniforms: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("planar uniforms"),
                size: (std::mem::size_of::<PlanarUniform>() * MAX_PLANES) as u64,
                usage: crate::gpu::uniform_usage(gpu),
                mapped_at_creation: false,
            }),
            planes: None,
            drawn_planes: 0,
        }
    }
}

impl ShadowTechnique for PlanarShadows {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.config = PlanarConfig::parse(params)?;
        Ok(())
    }

    fn compose(&self) -> Compose {
        self.config.compose
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let config = self.config;
        let key = crate::scene::scene_fingerprint(ctx.scene);
        if self.planes.as_ref().is_none_or(|(k, _)| *k != key) {
            let planes = receiver_planes(ctx.scene);
            if planes.is_empty() {
                log::warn!(
                    "planar: the scene has no ShadowPlane object and no planar receiver; no shadows"
                );
            }
            self.planes = Some((key, planes));
        }
        let planes = &self.planes.as_ref().expect("set above").1;
        let l = ctx.light.homogeneous();
        let tol = ctx.scene_gpu.bounds.size().length().max(1e-3) * 1e-4;
        // Orient each plane towards the light; skip planes the light lies in or behind.
        let uniforms: Vec<PlanarUniform> = planes
            .iter()
            .filter_map(|p| {
                let eq = if p.equation.dot(l) < 0.0 {
                    -p.equation
                } else {
                    p.equation
                };
                (eq.dot(l) > 1e-6).then(|| PlanarUniform {
                    shadow: shadow_matrix(eq, l),
                    plane: eq,
                    params: Vec4::new(config.visibility, config.depth_offset, tol, 0.0),
                    _pad: [Vec4::ZERO; 10],
                })
            })
            .collect();
        self.drawn_planes = uniforms.len();
        ctx.gpu
            .queue
            .write_buffer(&self.uniforms, 0, bytemuck::cast_slice(&uniforms));
        let bind_group = ctx
            .gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("planar"),
                layout: &self.shared.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: crate::gpu::dynamic_uniform::<PlanarUniform>(&self.uniforms),
                }],
            });
        let stencil = config.stencil;
        let mut pass = super::mask_pass(encoder, ctx, "planar");
        ctx.bind_frame_groups(&mut pass);
        let stride = std::mem::size_of::<PlanarUniform>() as u32;
        if stencil {
            pass.set_pipeline(&self.shared.tag);
            for i in 0..uniforms.len() {
                pass.set_stencil_reference(i as u32 + 1);
                pass.set_bind_group(crate::frame::OWN_GROUP, &bind_group, &[i as u32 * stride]);
                pass.draw(0..3, 0..1);
            }
        }
        pass.set_pipeline(&self.shared.flatten[stencil as usize]);
        for i in 0..uniforms.len() {
            pass.set_stencil_reference(i as u32 + 1);
            pass.set_bind_group(crate::frame::OWN_GROUP, &bind_group, &[i as u32 * stride]);
            ctx.scene_gpu.draw_objects(&mut pass, |d| d.casts_shadow);
        }
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        vec![("receiver_planes", self.drawn_planes as f64)]
    }

    fn resource_bytes(&self) -> u64 {
        self.uniforms.size()
    }
}

#[cfg(test)]
mod wgsl_tests {
    /// `PlanarUniform` of planar.wgsl is laid out as the Rust struct (up to
    /// its padding to the uniform stride).
    #[test]
    fn the_uniform_matches_its_wgsl_struct() {
        let source = crate::frame::technique_source(&[include_str!("planar.wgsl")]);
        crate::gpu::wgsl_layout::assert_struct_matches(
            &source,
            "PlanarUniform",
            crate::field_offsets!(super::PlanarUniform; shadow, plane, params),
            std::mem::offset_of!(super::PlanarUniform, _pad),
        );
    }
}
