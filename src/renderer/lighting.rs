//! The lighting pass, specialised per pipeline: the lights (count, and per
//! light its kind, range window and compose mode), shading mode, specular
//! model and the material's features (diffuse texture, normal map,
//! procedural kind) are pipeline-overridable constants of `scene.wgsl`, so
//! a pixel runs only its own variant's code (lavapipe runs both sides of a
//! branch on a uniform value); Gouraud has its own entry points and is the
//! only variant that carries per-vertex lighting.

use super::{LightingModel, MipFilter, RenderSettings, Shading};
use crate::frame::{
    self, Compose, DrawCall, FrameLayouts, FrameTargets, MAX_LIGHTS, MaterialVariant, SceneGpu,
};
use crate::gpu::GpuContext;
use crate::scene::{AlphaMode, Light, LightType};

/// The light kinds of common.wgsl (`LIGHT_*`) and the flags of scene.wgsl's
/// `LIGHT_SPECS` (`SPEC_*`), checked against the WGSL by a test.
const LIGHT_POINT: u32 = 0;
const LIGHT_SPOT: u32 = 1;
const LIGHT_DIRECTIONAL: u32 = 2;
const SPEC_WINDOWED: u32 = 4;
const SPEC_DARKEN: u32 = 8;

/// The lighting pass's own groups: the material's, and the masks with the
/// material sampler.
const MATERIAL_GROUP: u32 = frame::OWN_GROUP;
const LIGHTING_GROUP: u32 = 3;

/// What the lighting pass specialises on for one light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LitLight {
    pub kind: LightType,
    /// The range window `(1 − (d/range)⁴)²` applies (point and spot lights
    /// with a range).
    pub windowed: bool,
    pub compose: Compose,
}

impl LitLight {
    fn of(light: &Light, compose: Compose) -> LitLight {
        LitLight {
            kind: light.kind,
            windowed: light.kind != LightType::Directional && light.range > 0.0,
            compose,
        }
    }

    /// Four bits of `scene.wgsl`'s `LIGHT_SPECS`: the kind (`LIGHT_*`),
    /// 4 if windowed, 8 if the mask darkens.
    fn spec_bits(&self) -> u32 {
        let kind = match self.kind {
            LightType::Point => LIGHT_POINT,
            LightType::Spot => LIGHT_SPOT,
            LightType::Directional => LIGHT_DIRECTIONAL,
        };
        let windowed = if self.windowed { SPEC_WINDOWED } else { 0 };
        let darken = if self.compose == Compose::Darken {
            SPEC_DARKEN
        } else {
            0
        };
        kind | windowed | darken
    }
}

/// The lights of a frame as the lighting pass specialises on them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LitLights {
    lights: [Option<LitLight>; MAX_LIGHTS],
}

impl LitLights {
    /// `lights` with their masks' compose modes (relight where none is
    /// given); at most [`MAX_LIGHTS`] are taken.
    pub fn of(lights: &[Light], compose: &[Compose]) -> LitLights {
        let mut out = LitLights::default();
        for (i, (slot, l)) in out.lights.iter_mut().zip(lights).enumerate() {
            *slot = Some(LitLight::of(
                l,
                compose.get(i).copied().unwrap_or(Compose::Relight),
            ));
        }
        out
    }

    fn count(&self) -> u32 {
        self.lights.iter().flatten().count() as u32
    }

    /// `LIGHT_SPECS`: light i's [`LitLight::spec_bits`] from bit 4i.
    fn specs(&self) -> u32 {
        self.lights
            .iter()
            .flatten()
            .enumerate()
            .map(|(i, l)| l.spec_bits() << (4 * i))
            .sum()
    }
}

/// Everything a lighting pipeline depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LitKey {
    pub cull_back_faces: bool,
    pub shading: Shading,
    pub specular: LightingModel,
    pub lights: LitLights,
    pub material: MaterialVariant,
}

impl LitKey {
    /// The values of `scene.wgsl`'s pipeline-overridable constants.
    fn constants(&self) -> [(&'static str, f64); 8] {
        let b = |v: bool| v as u32 as f64;
        [
            ("LIGHT_COUNT", self.lights.count() as f64),
            ("LIGHT_SPECS", self.lights.specs() as f64),
            (
                "SHADING",
                match self.shading {
                    Shading::Flat => 0.0,
                    Shading::Gouraud => 1.0,
                    Shading::Pixel => 2.0,
                },
            ),
            (
                "SPECULAR",
                match self.specular {
                    LightingModel::Phong => 0.0,
                    LightingModel::BlinnPhong => 1.0,
                },
            ),
            ("DIFFUSE_TEXTURE", b(self.material.diffuse_texture)),
            ("NORMAL_MAP", b(self.material.normal_map)),
            ("PROCEDURAL", self.material.procedural as f64),
            ("TRANSLUCENT", b(self.material.translucent)),
        ]
    }

    /// Vertex and fragment entry points of the key's shading mode.
    fn entry_points(&self) -> (&'static str, &'static str) {
        match self.shading {
            Shading::Gouraud => ("vs_lit_gouraud", "fs_lit_gouraud"),
            Shading::Flat | Shading::Pixel => ("vs_lit", "fs_lit"),
        }
    }
}

/// The scene shader module (prepass and lighting) of a device.
pub fn scene_module(gpu: &GpuContext) -> wgpu::ShaderModule {
    struct SceneModule(wgpu::ShaderModule);
    gpu.cache
        .shared(|| {
            SceneModule(frame::shader_module(
                gpu,
                "scene",
                &[include_str!("procedural.wgsl"), include_str!("scene.wgsl")],
            ))
        })
        .0
        .clone()
}

pub struct Lighting {
    layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    group_layout: wgpu::BindGroupLayout,
    /// Material samplers by anisotropy and mip filter.
    samplers: std::sync::Mutex<std::collections::HashMap<(u16, MipFilter), wgpu::Sampler>>,
}

impl Lighting {
    pub fn new(gpu: &GpuContext, layouts: &FrameLayouts) -> Lighting {
        Lighting {
            layout: gpu
                .device
                .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("lighting"),
                    bind_group_layouts: &[
                        Some(&layouts.frame),
                        Some(&layouts.objects),
                        Some(&layouts.material),
                        Some(&layouts.lighting),
                    ],
                    immediate_size: 0,
                }),
            module: scene_module(gpu),
            group_layout: layouts.lighting.clone(),
            samplers: Default::default(),
        }
    }

    /// Group 3: the frame's masks and the material sampler of `anisotropy`.
    fn bind_group(
        &self,
        gpu: &GpuContext,
        frame: &FrameTargets,
        anisotropy: u16,
        mip_filter: MipFilter,
    ) -> wgpu::BindGroup {
        let mut samplers = self.samplers.lock().unwrap_or_else(|e| e.into_inner());
        let sampler = samplers.entry((anisotropy, mip_filter)).or_insert_with(|| {
            gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("material"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: match mip_filter {
                    MipFilter::Nearest => wgpu::MipmapFilterMode::Nearest,
                    MipFilter::Linear => wgpu::MipmapFilterMode::Linear,
                },
                anisotropy_clamp: anisotropy,
                ..Default::default()
            })
        });
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lighting"),
            layout: &self.group_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(frame.mask_array_view()),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
            ],
        })
    }

    fn pipeline(
        &self,
        gpu: &GpuContext,
        key: LitKey,
        color_format: wgpu::TextureFormat,
    ) -> wgpu::RenderPipeline {
        gpu.cache
            .render_pipeline("lighting", &(key, color_format), || {
                let constants = key.constants();
                let options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                let (vs, fs) = key.entry_points();
                gpu.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("lighting"),
                        layout: Some(&self.layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some(vs),
                            compilation_options: options.clone(),
                            buffers: &[Some(frame::VERTEX_LAYOUT)],
                        },
                        primitive: wgpu::PrimitiveState {
                            cull_mode: key.cull_back_faces.then_some(wgpu::Face::Back),
                            ..Default::default()
                        },
                        // Opaque surfaces shade the prepass's depth; translucent
                        // ones (not in it) are blended over what lies behind.
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format: gpu.depth_format,
                            depth_write_enabled: Some(false),
                            depth_compare: Some(if key.material.translucent {
                                frame::DEPTH_NEARER
                            } else {
                                wgpu::CompareFunction::Equal
                            }),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &self.module,
                            entry_point: Some(fs),
                            compilation_options: options,
                            targets: &[Some(wgpu::ColorTargetState {
                                format: color_format,
                                blend: key
                                    .material
                                    .translucent
                                    .then_some(wgpu::BlendState::ALPHA_BLENDING),
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
            })
    }

    /// Draws every object with its material's variant: opaque ones first,
    /// then translucent ones back to front.
    pub fn draw(
        &self,
        gpu: &GpuContext,
        pass: &mut wgpu::RenderPass,
        scene_gpu: &SceneGpu,
        frame: &FrameTargets,
        lights: LitLights,
        settings: &RenderSettings,
    ) {
        pass.set_bind_group(frame::FRAME_GROUP, frame.frame_bind_group(), &[]);
        pass.set_bind_group(frame::OBJECTS_GROUP, &scene_gpu.object_bind_group, &[]);
        pass.set_bind_group(
            LIGHTING_GROUP,
            &self.bind_group(
                gpu,
                frame,
                settings.texture_anisotropy(gpu),
                settings.texture_mip_filter(gpu),
            ),
            &[],
        );
        pass.set_vertex_buffer(0, scene_gpu.vertex_buffer.slice(..));
        pass.set_index_buffer(scene_gpu.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        let mut bound_material = usize::MAX;
        let mut bound_key = None;
        let eye = frame.uniform().camera_pos.truncate();
        let translucent = |d: &&DrawCall| d.alpha_mode == AlphaMode::Blend;
        let mut behind_first: Vec<&DrawCall> = scene_gpu.draws.iter().filter(translucent).collect();
        behind_first.sort_by(|a, b| {
            let distance = |d: &DrawCall| d.bounds.center().distance_squared(eye);
            distance(b).total_cmp(&distance(a))
        });
        let opaque = scene_gpu.draws.iter().filter(|d| !translucent(d));
        for d in opaque.chain(behind_first).filter(|d| !d.shadow_plane) {
            if d.material != bound_material {
                let key = LitKey {
                    cull_back_faces: settings.cull_back_faces,
                    shading: settings.shading,
                    specular: settings.lighting,
                    lights,
                    material: scene_gpu.material_variants[d.material],
                };
                if bound_key != Some(key) {
                    pass.set_pipeline(&self.pipeline(gpu, key, frame.color_format()));
                    bound_key = Some(key);
                }
                pass.set_bind_group(
                    MATERIAL_GROUP,
                    &scene_gpu.material_bind_groups[d.material],
                    &[],
                );
                bound_material = d.material;
            }
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                d.base_vertex,
                d.object..d.object + 1,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The light kinds and spec flags the lighting pass packs are the ones
    /// its WGSL tests.
    #[test]
    fn light_spec_constants_match_the_wgsl() {
        let source = [
            crate::frame::COMMON_WGSL,
            include_str!("procedural.wgsl"),
            include_str!("scene.wgsl"),
        ]
        .join("\n");
        crate::gpu::wgsl_layout::assert_consts_match(
            &source,
            &[
                ("LIGHT_POINT", LIGHT_POINT),
                ("LIGHT_SPOT", LIGHT_SPOT),
                ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
                ("SPEC_WINDOWED", SPEC_WINDOWED),
                ("SPEC_DARKEN", SPEC_DARKEN),
                ("MAX_LIGHTS", crate::frame::MAX_LIGHTS as u32),
            ],
        );
    }

    #[test]
    fn light_specs_pack_four_bits_per_light() {
        let mut point = Light::point(Vec3::Y, 1.0);
        point.range = 5.0;
        let spot = Light::spot(Vec3::Y, Vec3::ZERO, 1.0, 20.0, 30.0);
        let mut sun = Light::point(Vec3::Y, 1.0);
        sun.kind = LightType::Directional;
        sun.range = 5.0; // no window for a directional light
        let lit = LitLights::of(&[point, spot, sun], &[Compose::Relight, Compose::Darken]);
        assert_eq!(lit.count(), 3);
        // point 0 | windowed 4; spot 1 | darken 8; directional 2, relight by default
        assert_eq!(lit.specs(), 4 | (1 | 8) << 4 | 2 << 8);
        assert_eq!(LitLights::of(&[], &[]).count(), 0);
    }
}
