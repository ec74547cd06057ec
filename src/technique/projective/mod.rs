//! `projective`: projective shadow-mask textures ([001] §3.5.3, [002] §1,
//! [003] §2). Per caster, a black-on-white texture is rendered from
//! the light with a frustum fitted around the caster (orthographic for
//! directional lights, perspective otherwise) and projected onto the visible
//! receivers through the texture matrix `bias · P_light · V_light`. There is
//! no depth test, hence no self-shadowing. Preset `projective:alpha-depth` is
//! [003] §4's variant: the caster's depth in an 8-bit channel, compared per
//! receiver, whose low precision gives false self-shadowing.

use super::light_space::{LightFrustum, fit_bounds};
use super::params::Condition;
use super::{Family, MaskContext, ParamSpec, ParamValues, Preset, ShadowTechnique};
use crate::frame::{MASK_FORMAT, VERTEX_LAYOUT};
use crate::gpu::GpuContext;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, UVec4, Vec4};
use std::sync::Arc;

const SIZE: ParamSpec = ParamSpec::int("size", 512, 16, 8192, "texture side in texels, per caster");
const MARGIN: ParamSpec = ParamSpec::float(
    "margin",
    0.05,
    0.0,
    1.0,
    0.01,
    "widening of the frustum fitted around each caster, as a fraction of its bounding radius",
);
const DEPTH_IN_ALPHA: ParamSpec = ParamSpec::boolean(
    "depth_in_alpha",
    false,
    "store the caster's depth in an 8-bit channel and compare it per receiver ([003] §4): shadows on the caster itself, with 8-bit acne",
);
const ALPHA_BIAS: ParamSpec = ParamSpec::float(
    "alpha_bias",
    0.004,
    0.0,
    0.1,
    0.001,
    "depth-in-alpha comparison bias, as a fraction of the fitted depth range",
)
.when(Condition::Is("depth_in_alpha", &["true"]));

/// The projective family's parameters, parsed.
#[derive(Clone, Copy, Debug)]
struct ProjectiveConfig {
    size: u32,
    margin: f32,
    depth_in_alpha: bool,
    alpha_bias: f32,
}

impl ProjectiveConfig {
    fn parse(p: &ParamValues) -> Result<ProjectiveConfig> {
        Ok(ProjectiveConfig {
            size: p.int(&SIZE)?,
            margin: p.float(&MARGIN)?,
            depth_in_alpha: p.flag(&DEPTH_IN_ALPHA)?,
            alpha_bias: p.float(&ALPHA_BIAS)?,
        })
    }
}

pub static FAMILY: Family = Family {
    id: "projective",
    summary: "projective shadow textures: one black-on-white texture per caster, projected onto receivers",
    capabilities: super::Capabilities {
        point_lights: true,
        spot_lights: true,
        directional_lights: true,
        soft_shadows: false,
        self_shadowing: false,
        open_meshes: true,
        curved_receivers: true,
        cutout_casters: true,
    },
    params: &[SIZE, MARGIN, DEPTH_IN_ALPHA, ALPHA_BIAS],
    presets: &[
        Preset {
            name: "default",
            summary: "black-on-white texture per caster, 512²",
            values: &[],
        },
        Preset {
            name: "alpha-depth",
            summary: "caster depth in 8 bits, compared per receiver: shows false self-shadowing",
            values: &[(DEPTH_IN_ALPHA.name, "true")],
        },
    ],
    create: |gpu, params| {
        Ok(Box::new(ProjectiveShadows::new(
            gpu,
            ProjectiveConfig::parse(params)?,
        )))
    },
};

const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
const PROJECTOR_DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ProjectorUniform {
    view_proj: Mat4,
    view: Mat4,
    texture: Mat4,
    params: Vec4,
    info: UVec4,
    _pad: [Vec4; 2],
}

/// One caster's texture.
struct Projector {
    object: u32,
    color: wgpu::TextureView,
    depth: wgpu::TextureView,
}

/// The family's layouts, pipelines and placeholder, shared per device.
struct ProjectiveShared {
    layout: wgpu::BindGroupLayout,
    caster_pipeline: wgpu::RenderPipeline,
    project_pipeline: wgpu::RenderPipeline,
    /// Bound in place of a projector's texture while that texture is rendered.
    placeholder: wgpu::TextureView,
}

pub struct ProjectiveShadows {
    shared: Arc<ProjectiveShared>,
    config: ProjectiveConfig,
    uniforms: Option<wgpu::Buffer>,
    projectors: Vec<Projector>,
    /// (scene fingerprint, texture size) the projectors were made for.
    made_for: Option<(u64, u32)>,
    bytes: u64,
}

impl ProjectiveShared {
    fn new(gpu: &GpuContext) -> ProjectiveShared {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("projective"),
            entries: &[
                crate::gpu::uniform_entry(gpu, 0, wgpu::ShaderStages::VERTEX_FRAGMENT, true),
                crate::gpu::texture_entry(1, wgpu::TextureViewDimension::D2, false),
            ],
        });
        let module =
            crate::frame::technique_shader(gpu, "projective", &[include_str!("projective.wgsl")]);
        let pl = super::pipeline_layout(gpu, "projective", &layout);
        let caster_pipeline = gpu.cache.render_pipeline("projective caster", &(), || {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("projective caster"),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_caster"),
                    compilation_options: Default::default(),
                    buffers: &[Some(VERTEX_LAYOUT)],
                },
                primitive: Default::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: PROJECTOR_DEPTH,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_caster"),
                    compilation_options: Default::default(),
                    targets: &[Some(TEXTURE_FORMAT.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        });
        let project_pipeline = super::fullscreen_pipeline(
            gpu,
            "projective project",
            &pl,
            super::FragmentEntry::new(&module, "fs_project"),
            &[Some(wgpu::ColorTargetState {
                format: MASK_FORMAT,
                // Multiply: several casters combine.
                blend: Some(wgpu::BlendState {
                    color: wgpu::BlendComponent {
                        src_factor: wgpu::BlendFactor::Zero,
                        dst_factor: wgpu::BlendFactor::Src,
                        operation: wgpu::BlendOperation::Add,
                    },
                    alpha: wgpu::BlendComponent::REPLACE,
                }),
                write_mask: wgpu::ColorWrites::RED,
            })],
            Some(super::frame_depth_read(gpu, Default::default())),
        );
        let placeholder = crate::gpu::texture_2d(
            device,
            "projective placeholder",
            1,
            1,
            1,
            TEXTURE_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING,
        )
        .create_view(&Default::default());
        ProjectiveShared {
            placeholder,
            layout,
            caster_pipeline,
            project_pipeline,
        }
    }
}

impl ProjectiveShadows {
    fn new(gpu: &GpuContext, config: ProjectiveConfig) -> ProjectiveShadows {
        ProjectiveShadows {
            shared: gpu.cache.shared(|| ProjectiveShared::new(gpu)),
            config,
            uniforms: None,
            projectors: vec![],
            made_for: None,
            bytes: 0,
        }
    }

    fn make_projectors(&mut self, ctx: &MaskContext, size: u32) -> Result<()> {
        let casters = ctx
            .scene_gpu
            .draws
            .iter()
            .filter(|d| d.casts_shadow && !d.shadow_plane)
            .count() as u64;
        ctx.gpu.check_allocation(
            &format!(
                "projective: {casters} caster texture(s) of {size}x{size} (--set size=N; largest texture {})",
                ctx.gpu.max_texture_size()
            ),
            (size, size, 1),
            casters * size as u64 * size as u64 * (1 + 4),
        )?;
        // Free the old textures first; keep the new ones only once created.
        self.projectors.clear();
        self.made_for = None;
        let device = &ctx.gpu.device;
        let texture = |format, usage| {
            crate::gpu::texture_2d(device, "projective", size, size, 1, format, usage)
                .create_view(&Default::default())
        };
        use wgpu::TextureUsages as U;
        self.projectors = ctx.gpu.checked("allocating the projective textures", || {
            Ok(ctx
                .scene_gpu
                .draws
                .iter()
                .filter(|d| d.casts_shadow && !d.shadow_plane)
                .map(|d| Projector {
                    object: d.object,
                    color: texture(TEXTURE_FORMAT, U::RENDER_ATTACHMENT | U::TEXTURE_BINDING),
                    depth: texture(PROJECTOR_DEPTH, U::RENDER_ATTACHMENT),
                })
                .collect())
        })?;
        let n = self.projectors.len().max(1);
        self.uniforms = Some(device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("projectors"),
            size: (n * std::mem::size_of::<ProjectorUniform>()) as u64,
            usage: crate::gpu::uniform_usage(ctx.gpu),
            mapped_at_creation: false,
        }));
        self.bytes = (self.projectors.len() as u64) * (size as u64 * size as u64) * (1 + 4);
        Ok(())
    }
}

/// Each projector's uniform: its caster's frustum from the light (an
/// identity where the caster contains the light and is skipped).
fn projector_uniforms(
    projectors: &[Projector],
    frusta: &[Option<LightFrustum>],
    config: &ProjectiveConfig,
) -> Vec<ProjectorUniform> {
    let ProjectiveConfig {
        size,
        depth_in_alpha: depth_mode,
        alpha_bias,
        ..
    } = *config;
    projectors
        .iter()
        .zip(frusta)
        .map(|(p, f)| {
            let f = f.unwrap_or(LightFrustum {
                view: Mat4::IDENTITY,
                proj: Mat4::IDENTITY,
                near: 0.0,
                far: 1.0,
                orthographic: true,
            });
            ProjectorUniform {
                view_proj: f.view_proj(),
                view: f.view,
                texture: f.texture_matrix(),
                params: Vec4::new(f.near, f.far, alpha_bias, depth_mode as u32 as f32),
                info: UVec4::new(p.object, size, 0, 0),
                _pad: [Vec4::ZERO; 2],
            }
        })
        .collect()
}

impl ShadowTechnique for ProjectiveShadows {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.config = ProjectiveConfig::parse(params)?;
        Ok(())
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let ProjectiveConfig { size, margin, .. } = self.config;
        let key = (crate::scene::scene_fingerprint(ctx.scene), size);
        if self.made_for != Some(key) {
            self.make_projectors(ctx, size)?;
            self.made_for = Some(key);
        }
        // One frustum per caster; casters that contain a local light are skipped.
        let frusta: Vec<Option<LightFrustum>> = self
            .projectors
            .iter()
            .map(|p| {
                let o = &ctx.scene.objects[p.object as usize];
                let b = ctx.scene.meshes[o.mesh].bounds().transformed(o.transform);
                fit_bounds(ctx.light, &b, margin)
            })
            .collect();
        let uniforms = projector_uniforms(&self.projectors, &frusta, &self.config);
        let Some(ubuf) = &self.uniforms else {
            return Ok(());
        };
        ctx.gpu
            .queue
            .write_buffer(ubuf, 0, bytemuck::cast_slice(&uniforms));
        let stride = std::mem::size_of::<ProjectorUniform>() as u32;
        let bind_group = |texture: &wgpu::TextureView| {
            ctx.gpu
                .device
                .create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("projector"),
                    layout: &self.shared.layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: crate::gpu::dynamic_uniform::<ProjectorUniform>(ubuf),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(texture),
                        },
                    ],
                })
        };
        let caster_group = bind_group(&self.shared.placeholder);
        let bind_groups: Vec<wgpu::BindGroup> = self
            .projectors
            .iter()
            .map(|p| bind_group(&p.color))
            .collect();
        // Render each caster's texture from the light.
        for (i, p) in self.projectors.iter().enumerate() {
            if frusta[i].is_none() {
                continue;
            }
            let mut pass = ctx.gpu.render_pass(
                encoder,
                &wgpu::RenderPassDescriptor {
                    label: Some("projective caster"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &p.color,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &p.depth,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    ..Default::default()
                },
            );
            pass.set_pipeline(&self.shared.caster_pipeline);
            ctx.bind_frame_groups(&mut pass);
            pass.set_bind_group(crate::frame::OWN_GROUP, &caster_group, &[i as u32 * stride]);
            ctx.scene_gpu
                .draw_objects(&mut pass, |d| d.object == p.object);
        }
        // Project every texture onto the receivers, multiplying into the mask.
        let mut pass = super::mask_pass(encoder, ctx, "projective");
        pass.set_pipeline(&self.shared.project_pipeline);
        ctx.bind_frame_groups(&mut pass);
        for (i, bg) in bind_groups.iter().enumerate() {
            if frusta[i].is_some() {
                pass.set_bind_group(crate::frame::OWN_GROUP, bg, &[i as u32 * stride]);
                pass.draw(0..3, 0..1);
            }
        }
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        vec![("projectors", self.projectors.len() as f64)]
    }

    fn resource_bytes(&self) -> u64 {
        self.bytes
    }
}

#[cfg(test)]
mod wgsl_tests {
    /// `Projector` of projective.wgsl is laid out as `ProjectorUniform` (up
    /// to its padding to the uniform stride).
    #[test]
    fn the_uniform_matches_its_wgsl_struct() {
        let source = crate::frame::technique_source(&[include_str!("projective.wgsl")]);
        crate::gpu::wgsl_layout::assert_struct_matches(
            &source,
            "Projector",
            crate::field_offsets!(super::ProjectorUniform; view_proj, view, texture, params, info),
            std::mem::offset_of!(super::ProjectorUniform, _pad),
        );
    }
}
