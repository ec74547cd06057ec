//! `planar`: projected planar shadows (SEEDS §2; Blinn 1988, 000 §2, 001 §2).
//! Each caster is drawn a second time through the shadow matrix
//! `M = (P·L)·I − L·Pᵀ` onto each receiver plane, into the visibility mask.
//! With `stencil` on, the visible pixels of plane i are first tagged with
//! id i + 1 (001 Algorithm 2.1) and a shadow fragment passes only where the
//! stencil equals the id and zeroes it, so each pixel darkens once and the
//! shadow stays on the plane. Anti-shadows (caster beyond the light) are
//! clipped by the rasterizer (w < 0 after M), false shadows (caster behind the
//! plane) are discarded per fragment.

use super::light_space::shadow_matrix;
use super::{Family, MaskContext, ParamSpec, Preset, ShadowTechnique};
use crate::renderer::{DEPTH_FORMAT, MASK_FORMAT, VERTEX_LAYOUT};
use crate::scene::{Object, Scene};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

pub static FAMILY: Family = Family {
    id: "planar",
    summary: "projected planar shadows: casters flattened onto receiver planes by the shadow matrix",
    params: &[
        ParamSpec::DARKENING,
        ParamSpec::float(
            "depth_offset",
            32.0,
            0.0,
            4096.0,
            1.0,
            "offset of the flattened shadows towards the camera, in units of 2^-20 of the depth range, against z-fighting with the receiver",
        ),
        ParamSpec::boolean(
            "stencil",
            true,
            "stencil-tag each receiver plane (id = index + 1): each pixel darkens once and shadows stay on the plane; off shows double darkening and spill",
        ),
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
            values: &[("stencil", "false"), ("darkening", "0.6")],
        },
        Preset {
            name: "darken",
            summary: "the documents' look: a half-transparent shadow colour blended over the lit image",
            values: &[("darkening", "0.5"), ("compose", "darken")],
        },
    ],
    create: |gpu| Ok(Box::new(PlanarShadows::new(gpu))),
};

/// At most this many receiver planes are used.
pub const MAX_PLANES: usize = 8;

/// A receiver plane `(A, B, C, D)` with unit normal, from a scene object.
#[derive(Clone, Debug, PartialEq)]
pub struct ReceiverPlane {
    pub equation: Vec4,
    pub object: usize,
}

fn plane_of(a: Vec3, b: Vec3, c: Vec3) -> Option<Vec4> {
    let n = (b - a).cross(c - a).try_normalize()?;
    Some(n.extend(-n.dot(a)))
}

fn world_positions(scene: &Scene, o: &Object) -> impl Iterator<Item = Vec3> {
    scene.meshes[o.mesh]
        .positions
        .iter()
        .map(move |&p| o.transform.transform_point3(p))
}

/// The receiver planes of a scene: its `shadow_plane` objects (plane of the
/// first triangle), else the largest planar shadow-receiving object.
pub fn receiver_planes(scene: &Scene) -> Vec<ReceiverPlane> {
    let mut planes = vec![];
    for (i, o) in scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.shadow_plane)
    {
        let m = &scene.meshes[o.mesh];
        if let Some(t) = m.indices.chunks_exact(3).next() {
            let p = |k: usize| o.transform.transform_point3(m.positions[t[k] as usize]);
            if let Some(eq) = plane_of(p(0), p(1), p(2)) {
                planes.push(ReceiverPlane {
                    equation: eq,
                    object: i,
                });
            }
        }
    }
    if !planes.is_empty() {
        planes.truncate(MAX_PLANES);
        return planes;
    }
    let tol = scene.bounds().size().length().max(1e-3) * 1e-5;
    let mut best: Option<(f32, ReceiverPlane)> = None;
    for (i, o) in scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.receives_shadow)
    {
        let m = &scene.meshes[o.mesh];
        let Some(t) = m.indices.chunks_exact(3).next() else {
            continue;
        };
        let p = |k: u32| o.transform.transform_point3(m.positions[k as usize]);
        let Some(eq) = plane_of(p(t[0]), p(t[1]), p(t[2])) else {
            continue;
        };
        if world_positions(scene, o).any(|v| eq.dot(v.extend(1.0)).abs() > tol) {
            continue;
        }
        let area: f32 = m
            .indices
            .chunks_exact(3)
            .map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length() * 0.5)
            .sum();
        if best.as_ref().is_none_or(|(a, _)| area > *a) {
            best = Some((
                area,
                ReceiverPlane {
                    equation: eq,
                    object: i,
                },
            ));
        }
    }
    match best {
        Some((area, p)) => {
            log::info!(
                "planar: no ShadowPlane object; using the largest planar receiver '{}' (area {area:.2})",
                scene.objects[p.object].name
            );
            vec![p]
        }
        None => {
            log::warn!(
                "planar: the scene has no ShadowPlane object and no planar receiver; no shadows"
            );
            vec![]
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PlanarUniform {
    shadow: Mat4,
    plane: Vec4,
    params: Vec4,
    _pad: [Vec4; 10],
}

pub struct PlanarShadows {
    uniforms: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    tag: wgpu::RenderPipeline,
    /// [stencil off, stencil on]
    flatten: [wgpu::RenderPipeline; 2],
    planes: Option<(u64, Vec<ReceiverPlane>)>,
    drawn_planes: usize,
}

impl PlanarShadows {
    pub fn new(gpu: &crate::gpu::GpuContext) -> PlanarShadows {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("planar"),
            entries: &[
                crate::renderer::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT, true),
                super::gbuffer_entry(1),
                super::gbuffer_entry(2),
            ],
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("planar uniforms"),
            size: (std::mem::size_of::<PlanarUniform>() * MAX_PLANES) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module =
            crate::renderer::shader_module(device, "planar", &[include_str!("planar.wgsl")]);
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
                depth_stencil: Some(depth),
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
            super::frame_depth_read(stencil(
                stencil_face(
                    wgpu::CompareFunction::Always,
                    wgpu::StencilOperation::Replace,
                ),
                0xff,
            )),
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
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
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
        PlanarShadows {
            uniforms,
            layout,
            tag,
            flatten: [flatten(false), flatten(true)],
            planes: None,
            drawn_planes: 0,
        }
    }
}

impl ShadowTechnique for PlanarShadows {
    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let key = super::scene_fingerprint(ctx.scene);
        if self.planes.as_ref().is_none_or(|(k, _)| *k != key) {
            self.planes = Some((key, receiver_planes(ctx.scene)));
        }
        let planes = &self.planes.as_ref().expect("set above").1;
        let l = ctx.light.homogeneous();
        let tol = ctx.scene_gpu.bounds.size().length().max(1e-3) * 1e-4;
        let vis = 1.0 - ctx.params.get_f32("darkening")?;
        let offset = ctx.params.get_f32("depth_offset")? / (1u32 << 20) as f32;
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
                    params: Vec4::new(vis, offset, tol, 0.0),
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
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: crate::renderer::dynamic_uniform::<PlanarUniform>(&self.uniforms),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(
                            &ctx.frame.gbuffer_position_view,
                        ),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(
                            &ctx.frame.gbuffer_normal_view,
                        ),
                    },
                ],
            });
        let stencil = ctx.params.get_bool("stencil")?;
        let mut pass = super::mask_pass(encoder, ctx, "planar");
        pass.set_bind_group(0, &ctx.frame.frame_bind_group, &[]);
        pass.set_bind_group(1, &ctx.scene_gpu.object_bind_group, &[]);
        let stride = std::mem::size_of::<PlanarUniform>() as u32;
        if stencil {
            pass.set_pipeline(&self.tag);
            for i in 0..uniforms.len() {
                pass.set_stencil_reference(i as u32 + 1);
                pass.set_bind_group(2, &bind_group, &[i as u32 * stride]);
                pass.draw(0..3, 0..1);
            }
        }
        pass.set_pipeline(&self.flatten[stencil as usize]);
        for i in 0..uniforms.len() {
            pass.set_stencil_reference(i as u32 + 1);
            pass.set_bind_group(2, &bind_group, &[i as u32 * stride]);
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
