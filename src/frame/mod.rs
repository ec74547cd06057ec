//! The frame layer: what every pass of a frame shares. Target formats, the
//! vertex layout, the scene's GPU buffers ([`SceneGpu`]), the frame's
//! targets ([`FrameTargets`], read-only to techniques), the frame uniform,
//! the bind-group layouts of groups 0 (frame), 1 (objects) and 3 (the
//! G-buffer, one bind group for every technique shader) and the common WGSL.

mod scene_gpu;
mod targets;
mod textures;

pub use scene_gpu::{DrawCall, MaterialVariant, SceneGpu};
pub use targets::{FrameTargets, clear_mask, write_mask};

use crate::gpu::{GpuContext, storage_entry, texture_entry, uniform_entry};
use crate::scene::{Camera, Light, Scene};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};
use serde::Serialize;
use std::sync::Arc;

pub const MAX_LIGHTS: usize = 4;
/// Visibility masks: one layer per light, 1 = fully lit.
pub const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;
/// The camera's depth is reversed (near 1, far or infinity 0: the float
/// format's dense values near 0 then balance the projection's loss of
/// precision with distance; Reed 2015, "Depth precision visualized"): a
/// nearer fragment has the greater depth, and the buffer clears to 0.
pub const DEPTH_NEARER: wgpu::CompareFunction = wgpu::CompareFunction::Greater;
/// [`DEPTH_NEARER`] or at the same depth.
pub const DEPTH_NEARER_OR_EQUAL: wgpu::CompareFunction = wgpu::CompareFunction::GreaterEqual;
/// The depth of nothing drawn (the far end of the reversed range).
pub const DEPTH_CLEAR: f32 = 0.0;
pub const GBUFFER_POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const GBUFFER_NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The G-buffer's convex part IDs (`part_id` in common.wgsl; 0: none).
pub const GBUFFER_PART_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The colour image's format unless a frame asks for another of
/// [`COLOR_FORMATS`] (the viewer takes its window's, so that the view reaches
/// the window by a plain copy).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// The colour formats a frame can have: 8-bit sRGB, RGBA or BGRA order.
pub const COLOR_FORMATS: [wgpu::TextureFormat; 2] = [
    wgpu::TextureFormat::Rgba8UnormSrgb,
    wgpu::TextureFormat::Bgra8UnormSrgb,
];

/// Bind group indices shared by every pass: the frame uniform, the object
/// table, the pass's own resources, the G-buffer (technique passes).
pub const FRAME_GROUP: u32 = 0;
pub const OBJECTS_GROUP: u32 = 1;
pub const OWN_GROUP: u32 = 2;
pub const GBUFFER_GROUP: u32 = 3;

/// WGSL shared by the renderer and the technique shaders.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");
/// WGSL declaring the G-buffer at [`GBUFFER_GROUP`] (technique shaders).
pub const GBUFFER_WGSL: &str = include_str!("gbuffer.wgsl");

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    pub tangent: [f32; 4],
    /// The mesh's convex part the vertex lies on (from 1), or 0
    /// ([`crate::scene::topology::Solidity`]).
    pub part: u32,
    /// The colour that multiplies the material's, sRGB-encoded in 8 bits a
    /// channel (alpha unused): 4 bytes, not 12, in every vertex fetch; white
    /// where the mesh has none.
    pub color: [u8; 4],
}

impl Vertex {
    /// A linear RGB colour as [`Vertex::color`] holds it.
    pub fn encode_color(linear: glam::Vec3) -> [u8; 4] {
        let srgb = |c: f32| {
            let c = c.clamp(0.0, 1.0);
            let s = if c <= 0.003_130_8 {
                12.92 * c
            } else {
                1.055 * c.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0).round() as u8
        };
        [srgb(linear.x), srgb(linear.y), srgb(linear.z), 255]
    }
}

pub const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4, 4 => Uint32, 5 => Unorm8x4],
};

/// A light as the lighting pass reads it (`LightGpu` in common.wgsl). Its
/// kind and compose mode are pipeline constants (`renderer::LitLights`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Default)]
pub struct LightGpu {
    /// xyz world position, w range (0: no falloff).
    pub position: Vec4,
    /// xyz unit direction the light travels, w cos(outer cone).
    pub direction: Vec4,
    /// rgb colour × intensity, w cos(inner cone).
    pub color: Vec4,
}

/// How the lighting pass uses a light's visibility mask `v`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Compose {
    /// `ambient + v · (diffuse + specular)`: the shadow removes the light.
    Relight,
    /// The documents' way: the lit colour (ambient included) times `v`, a
    /// shadow colour blended over the lit image.
    Darken,
}

impl LightGpu {
    pub fn from_light(l: &Light) -> LightGpu {
        LightGpu {
            position: l.position.extend(l.range),
            direction: l
                .direction
                .normalize_or_zero()
                .extend(l.outer_cone_deg.to_radians().cos()),
            color: (l.color * l.intensity).extend(l.inner_cone_deg.to_radians().cos()),
        }
    }
}

/// The per-frame uniform (group 0 of every pass, `Frame` in common.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct FrameUniform {
    pub view_proj: Mat4,
    pub inv_view_proj: Mat4,
    pub view: Mat4,
    pub proj: Mat4,
    pub camera_pos: Vec4,
    pub ambient: Vec4,
    pub size: Vec4,
    pub lights: [LightGpu; MAX_LIGHTS],
}

/// The layouts of groups 0, 1 and 3 and the scene materials; one set per
/// device ([`FrameLayouts::of`]).
pub struct FrameLayouts {
    pub frame: wgpu::BindGroupLayout,
    pub objects: wgpu::BindGroupLayout,
    pub gbuffer: wgpu::BindGroupLayout,
    pub material: wgpu::BindGroupLayout,
    /// The lighting pass's group 3: the mask array and the material
    /// textures' sampler (its anisotropy is a render setting).
    pub lighting: wgpu::BindGroupLayout,
}

impl FrameLayouts {
    pub fn of(gpu: &GpuContext) -> Arc<FrameLayouts> {
        gpu.cache.shared(|| {
            let device = &gpu.device;
            let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
            let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
            };
            // The G-buffer and the opacity maps are read by fragment and
            // compute passes (the irregular z-buffer's sample tests).
            let fc = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
            let gbuffer_texture = |binding| {
                crate::gpu::sampled_texture_entry(
                    binding,
                    fc,
                    wgpu::TextureSampleType::Float { filterable: false },
                    wgpu::TextureViewDimension::D2,
                )
            };
            FrameLayouts {
                frame: layout(
                    "frame",
                    // The stages a pipeline here has (WebGPU refuses the
                    // mesh and ray-tracing stages of `ShaderStages::all()`).
                    &[uniform_entry(
                        gpu,
                        0,
                        vf | wgpu::ShaderStages::COMPUTE,
                        false,
                    )],
                ),
                objects: layout(
                    "objects",
                    &[
                        storage_entry(0, vf | wgpu::ShaderStages::COMPUTE, true),
                        storage_entry(1, fc, true),
                    ],
                ),
                gbuffer: layout(
                    "gbuffer",
                    &[
                        gbuffer_texture(0),
                        gbuffer_texture(1),
                        crate::gpu::sampled_texture_entry(
                            2,
                            fc,
                            wgpu::TextureSampleType::Uint,
                            wgpu::TextureViewDimension::D2,
                        ),
                    ],
                ),
                lighting: layout(
                    "lighting",
                    &[
                        texture_entry(0, wgpu::TextureViewDimension::D2Array, false),
                        wgpu::BindGroupLayoutEntry {
                            binding: 1,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                            count: None,
                        },
                    ],
                ),
                material: layout(
                    "material",
                    &[
                        uniform_entry(gpu, 0, vf, false),
                        texture_entry(1, wgpu::TextureViewDimension::D2, true),
                        texture_entry(2, wgpu::TextureViewDimension::D2, true),
                    ],
                ),
            }
        })
    }

    /// Pipeline layout of a technique pass: frame, objects, the pass's own
    /// group `own` and the G-buffer.
    pub fn technique_layout(
        &self,
        device: &wgpu::Device,
        label: &str,
        own: &wgpu::BindGroupLayout,
    ) -> wgpu::PipelineLayout {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[
                Some(&self.frame),
                Some(&self.objects),
                Some(own),
                Some(&self.gbuffer),
            ],
            immediate_size: 0,
        })
    }
}

/// An error naming the first render-target format of a frame that the
/// device cannot render to.
pub fn check_formats(gpu: &GpuContext) -> anyhow::Result<()> {
    for (format, what) in [
        (gpu.depth_format, "the depth buffer"),
        (GBUFFER_POSITION_FORMAT, "the G-buffer's positions"),
        (GBUFFER_NORMAL_FORMAT, "the G-buffer's normals"),
        (GBUFFER_PART_FORMAT, "the G-buffer's convex parts"),
        (MASK_FORMAT, "the visibility masks"),
        (COLOR_FORMAT, "the colour image"),
    ] {
        gpu.require_renderable(format, what)?;
    }
    Ok(())
}

/// A shader module of the renderer: `common.wgsl` followed by `sources`.
pub fn shader_module(gpu: &GpuContext, label: &str, sources: &[&str]) -> wgpu::ShaderModule {
    crate::gpu::compose_shader(gpu, label, &[&[COMMON_WGSL], sources].concat())
}

/// A shader module of a technique: [`technique_source`] of `sources`.
pub fn technique_shader(gpu: &GpuContext, label: &str, sources: &[&str]) -> wgpu::ShaderModule {
    crate::gpu::compose_shader(gpu, label, &[&technique_source(sources)])
}

/// The WGSL of a technique: `common.wgsl`, `gbuffer.wgsl`, `sources` (the
/// WGSL tests reflect the same text).
pub fn technique_source(sources: &[&str]) -> String {
    [&[COMMON_WGSL, GBUFFER_WGSL], sources].concat().join("\n")
}

/// The frame uniform for a camera and lights at a frame size;
/// `infinite_far_plane` for shadow volumes.
pub fn frame_uniform(
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    infinite_far_plane: bool,
    width: u32,
    height: u32,
) -> FrameUniform {
    let view = camera.view();
    let aspect = width as f32 / height as f32;
    let proj = if infinite_far_plane {
        camera.projection_infinite(aspect)
    } else {
        camera.projection(aspect)
    };
    let view_proj = proj * view;
    let mut gl = [LightGpu::default(); MAX_LIGHTS];
    for (g, l) in gl.iter_mut().zip(lights) {
        *g = LightGpu::from_light(l);
    }
    FrameUniform {
        view_proj,
        inv_view_proj: view_proj.inverse(),
        view,
        proj,
        camera_pos: camera.eye.extend(1.0),
        ambient: scene.ambient.extend(0.0),
        size: Vec4::new(
            width as f32,
            height as f32,
            1.0 / width as f32,
            1.0 / height as f32,
        ),
        lights: gl,
    }
}
