//! The real-time renderer: a depth + G-buffer prepass, one visibility mask
//! per light written by that light's shadow technique, and a forward
//! lighting pass (depth test EQUAL against the prepass) that composes
//! `ambient + Σ visibility × (diffuse + specular)`; light icons on top.
//! GPU resources are created once per scene and once per frame size, so a
//! frame only writes one uniform buffer and records passes.

mod icons;
mod lines;
mod textures;

use crate::gpu::GpuContext;
use crate::scene::{Aabb, Camera, Light, LightArea, LightType, Scene};
use crate::technique::{MaskContext, ShadowTechnique, TechniqueChoice};
use anyhow::{Result, bail};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use wgpu::util::DeviceExt;

pub const MAX_LIGHTS: usize = 4;
/// Visibility masks: one layer per light, 1 = fully lit.
pub const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;
/// Scene depth with a stencil for the stencil-based techniques.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;
pub const GBUFFER_POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const GBUFFER_NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// WGSL shared by the renderer and the technique shaders.
pub const COMMON_WGSL: &str = include_str!("common.wgsl");

/// Shading modes of SEEDS §1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// One normal per face.
    Flat,
    /// Intensities per vertex, interpolated.
    Gouraud,
    /// Normals interpolated, lighting per pixel, normal maps applied.
    Pixel,
}

/// Specular model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum LightingModel {
    /// `(V·R)^n`
    Phong,
    /// `(N·H)^n`
    BlinnPhong,
}

/// Renderer-wide settings (not technique parameters).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct RenderSettings {
    pub shading: Shading,
    pub lighting: LightingModel,
    pub cull_back_faces: bool,
    /// Linear RGB; `None` takes the scene's.
    pub background: Option<Vec3>,
    pub show_light_icons: bool,
    /// Measure each pass with GPU timestamp queries (when the adapter has them).
    #[serde(default)]
    pub gpu_timing: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            shading: Shading::Pixel,
            lighting: LightingModel::BlinnPhong,
            cull_back_faces: true,
            background: None,
            show_light_icons: true,
            gpu_timing: false,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    pub tangent: [f32; 4],
}

pub const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4],
};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Default)]
pub struct LightGpu {
    pub position: Vec4,
    pub direction: Vec4,
    pub color: Vec4,
    pub cone: Vec4,
    pub extra: Vec4,
}

/// How the lighting pass uses a light's visibility mask `v`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Compose {
    /// `ambient + v · (diffuse + specular)`: the shadow removes the light.
    Relight,
    /// The documents' way: the lit colour (ambient included) times `v`, a
    /// shadow colour blended over the lit image.
    Darken,
}

impl Compose {
    /// From a technique's parameters: its `compose` choice when it has one.
    pub fn of(params: &crate::technique::ParamValues) -> Compose {
        match params.specs.iter().position(|s| s.name == "compose") {
            Some(i) if params.values[i] == 1.0 => Compose::Darken,
            _ => Compose::Relight,
        }
    }
}

impl LightGpu {
    pub fn from_light(l: &Light, compose: Compose) -> LightGpu {
        let kind = match l.kind {
            LightType::Point => 0.0,
            LightType::Spot => 1.0,
            LightType::Directional => 2.0,
        };
        let (a, b, shape) = match l.area {
            None => (0.0, 0.0, 0.0),
            Some(LightArea::Sphere { radius }) => (radius, 0.0, 1.0),
            Some(LightArea::Rect { width, height }) => (width, height, 2.0),
        };
        LightGpu {
            position: l.position.extend(kind),
            direction: l.direction.normalize_or_zero().extend(l.range),
            color: (l.color * l.intensity).extend(l.inner_cone_deg.to_radians().cos()),
            cone: Vec4::new(l.outer_cone_deg.to_radians().cos(), a, b, shape),
            extra: Vec4::new((compose == Compose::Darken) as u32 as f32, 0.0, 0.0, 0.0),
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
    pub settings: [u32; 4],
    pub lights: [LightGpu; MAX_LIGHTS],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ObjectGpu {
    model: Mat4,
    normal_matrix: Mat4,
    info: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MaterialGpu {
    ka: Vec4,
    kd: Vec4,
    ks: Vec4,
    proc_a: Vec4,
    proc_b: Vec4,
    flags: Vec4,
}

/// One indexed draw of one object.
#[derive(Clone, Copy, Debug)]
pub struct DrawCall {
    pub object: u32,
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    pub material: usize,
    pub casts_shadow: bool,
    pub shadow_plane: bool,
}

/// The scene's GPU buffers: all meshes in one vertex and one index buffer,
/// the object table and one bind group per material.
pub struct SceneGpu {
    pub vertex_buffer: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    pub object_buffer: wgpu::Buffer,
    pub object_bind_group: wgpu::BindGroup,
    pub draws: Vec<DrawCall>,
    material_bind_groups: Vec<wgpu::BindGroup>,
    pub triangle_count: usize,
    pub caster_triangle_count: usize,
    pub bounds: Aabb,
}

impl SceneGpu {
    /// Binds the vertex and index buffers and draws every non-plane object
    /// that `filter` accepts, with `instance_index` = object id. The caller
    /// sets pipeline and bind groups 0 and 1.
    pub fn draw_objects(&self, pass: &mut wgpu::RenderPass, filter: impl Fn(&DrawCall) -> bool) {
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for d in self.draws.iter().filter(|d| !d.shadow_plane && filter(d)) {
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                d.base_vertex,
                d.object..d.object + 1,
            );
        }
    }
}

/// Per-frame-size targets and the frame uniform.
pub struct FrameResources {
    pub width: u32,
    pub height: u32,
    pub depth: wgpu::Texture,
    pub depth_view: wgpu::TextureView,
    /// Depth aspect only, for sampling.
    pub depth_sample_view: wgpu::TextureView,
    pub gbuffer_position: wgpu::Texture,
    pub gbuffer_position_view: wgpu::TextureView,
    pub gbuffer_normal: wgpu::Texture,
    pub gbuffer_normal_view: wgpu::TextureView,
    pub masks: wgpu::Texture,
    pub mask_layer_views: Vec<wgpu::TextureView>,
    mask_bind_group: wgpu::BindGroup,
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub frame_buffer: wgpu::Buffer,
    pub frame_bind_group: wgpu::BindGroup,
    /// CPU copy of what the GPU used this frame.
    pub uniform: FrameUniform,
}

/// A technique for one light with its parameter values.
pub struct TechniqueInstance {
    pub choice: TechniqueChoice,
    pub technique: Box<dyn ShadowTechnique>,
}

impl TechniqueInstance {
    pub fn new(gpu: &GpuContext, choice: TechniqueChoice) -> Result<TechniqueInstance> {
        let technique = (choice.family.create)(gpu)?;
        Ok(TechniqueInstance { choice, technique })
    }
}

/// CPU wall times of one frame's stages, milliseconds (each stage waits for
/// the GPU so that the times are the stage's own).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameTimings {
    pub prepass_ms: f64,
    pub masks_ms: f64,
    pub lighting_ms: f64,
    pub total_ms: f64,
    /// GPU time per pass from timestamp queries, when measured.
    pub gpu: Option<GpuPassTimes>,
}

/// GPU time of each pass, milliseconds (timestamp queries).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct GpuPassTimes {
    pub prepass_ms: f64,
    pub masks_ms: f64,
    pub lighting_ms: f64,
    pub total_ms: f64,
}

/// Six timestamps per frame: start and end of the prepass, mask and lighting
/// encoders (bracketing each encoder, so time between submissions, such as
/// CPU-side technique work, is not counted as GPU time).
struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl GpuTimer {
    fn new(device: &wgpu::Device) -> GpuTimer {
        GpuTimer {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 6,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 48,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: 48,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
        }
    }

    fn read(&self, gpu: &GpuContext) -> Result<GpuPassTimes> {
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.wait_idle()?;
        rx.recv()??;
        let t: Vec<u64> = bytemuck::cast_slice::<u8, u64>(&slice.get_mapped_range()?).to_vec();
        self.readback.unmap();
        let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
        let d = |a: usize, b: usize| t[b].saturating_sub(t[a]) as f64 * period;
        Ok(GpuPassTimes {
            prepass_ms: d(0, 1),
            masks_ms: d(2, 3),
            lighting_ms: d(4, 5),
            total_ms: d(0, 1) + d(2, 3) + d(4, 5),
        })
    }
}

/// Pipelines and layouts; created once per device.
pub struct Renderer {
    pub frame_layout: wgpu::BindGroupLayout,
    pub object_layout: wgpu::BindGroupLayout,
    material_layout: wgpu::BindGroupLayout,
    mask_layout: wgpu::BindGroupLayout,
    gbuffer_pipelines: [wgpu::RenderPipeline; 2],
    lit_pipelines: [wgpu::RenderPipeline; 2],
    icons: icons::LightIcons,
    lines: lines::LineRenderer,
    sampler: wgpu::Sampler,
    timer: Option<GpuTimer>,
}

/// A binding of one `T` at a dynamic offset of `buffer`.
pub fn dynamic_uniform<T>(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: wgpu::BufferSize::new(std::mem::size_of::<T>() as u64),
    })
}

/// Layout entry of a uniform buffer (optionally with a dynamic offset).
pub fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Layout entry of a storage buffer.
pub fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture_entry(
    binding: u32,
    dim: wgpu::TextureViewDimension,
    filterable: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable },
            view_dimension: dim,
            multisampled: false,
        },
        count: None,
    }
}

/// The layouts of group 0 (frame uniform) and group 1 (object table), which
/// every scene and technique pipeline shares (wgpu deduplicates identical
/// layouts, so layouts made here by techniques match the renderer's).
pub fn shared_layouts(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::BindGroupLayout) {
    let frame = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("frame"),
        entries: &[uniform_entry(0, wgpu::ShaderStages::all(), false)],
    });
    let objects = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("objects"),
        entries: &[storage_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
            true,
        )],
    });
    (frame, objects)
}

/// Builds a shader module from `common.wgsl` followed by `sources`.
pub fn shader_module(device: &wgpu::Device, label: &str, sources: &[&str]) -> wgpu::ShaderModule {
    let mut code = String::from(COMMON_WGSL);
    for s in sources {
        code.push('\n');
        code.push_str(s);
    }
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(code.into()),
    })
}

/// Clears a mask layer to `value` (a render pass with a clear and no draw).
pub fn clear_mask(encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView, value: f64) {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("mask clear"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: value,
                    g: value,
                    b: value,
                    a: 1.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    });
}

/// A single-mip 2D texture (array when `layers` > 1).
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl Renderer {
    /// An error naming the first render-target format of a frame that the
    /// device cannot render to (call before [`Renderer::new`]).
    pub fn check_formats(gpu: &GpuContext) -> Result<()> {
        for (format, what) in [
            (DEPTH_FORMAT, "the depth buffer"),
            (GBUFFER_POSITION_FORMAT, "the G-buffer's positions"),
            (GBUFFER_NORMAL_FORMAT, "the G-buffer's normals"),
            (MASK_FORMAT, "the visibility masks"),
            (COLOR_FORMAT, "the colour image"),
        ] {
            gpu.require_renderable(format, what)?;
        }
        Ok(())
    }

    pub fn new(gpu: &GpuContext) -> Renderer {
        let device = &gpu.device;
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let (frame_layout, object_layout) = shared_layouts(device);
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[
                uniform_entry(0, vf, false),
                texture_entry(1, wgpu::TextureViewDimension::D2, true),
                texture_entry(2, wgpu::TextureViewDimension::D2, true),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let mask_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("masks"),
            entries: &[texture_entry(0, wgpu::TextureViewDimension::D2Array, false)],
        });
        let module = shader_module(
            device,
            "scene",
            &[include_str!("procedural.wgsl"), include_str!("scene.wgsl")],
        );
        let gbuffer_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(&frame_layout), Some(&object_layout)],
            immediate_size: 0,
        });
        let lit_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lit"),
            bind_group_layouts: &[
                Some(&frame_layout),
                Some(&object_layout),
                Some(&material_layout),
                Some(&mask_layout),
            ],
            immediate_size: 0,
        });
        let cull = |c: bool| if c { Some(wgpu::Face::Back) } else { None };
        let gbuffer_pipeline = |c: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("gbuffer"),
                layout: Some(&gbuffer_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_gbuffer"),
                    compilation_options: Default::default(),
                    buffers: &[Some(VERTEX_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: cull(c),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_gbuffer"),
                    compilation_options: Default::default(),
                    targets: &[
                        Some(GBUFFER_POSITION_FORMAT.into()),
                        Some(GBUFFER_NORMAL_FORMAT.into()),
                    ],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let lit_pipeline = |c: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("lit"),
                layout: Some(&lit_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_lit"),
                    compilation_options: Default::default(),
                    buffers: &[Some(VERTEX_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: cull(c),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Equal),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_lit"),
                    compilation_options: Default::default(),
                    targets: &[Some(COLOR_FORMAT.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("material"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: 8,
            ..Default::default()
        });
        Renderer {
            gbuffer_pipelines: [gbuffer_pipeline(false), gbuffer_pipeline(true)],
            lit_pipelines: [lit_pipeline(false), lit_pipeline(true)],
            icons: icons::LightIcons::new(device, &frame_layout),
            lines: lines::LineRenderer::new(device, &frame_layout),
            frame_layout,
            object_layout,
            material_layout,
            mask_layout,
            sampler,
            timer: gpu.timestamps.then(|| GpuTimer::new(device)),
        }
    }

    /// Draws debug lines over the frame's colour image (after [`Self::render`]).
    pub fn draw_lines(
        &self,
        gpu: &GpuContext,
        frame: &FrameResources,
        lines: &[crate::technique::DebugLine],
    ) {
        self.lines.draw(gpu, frame, lines);
    }

    /// Uploads a scene: meshes, object table, materials and textures.
    pub fn upload_scene(&self, gpu: &GpuContext, scene: &Scene) -> Result<SceneGpu> {
        let device = &gpu.device;
        let mut vertices: Vec<Vertex> = vec![];
        let mut indices: Vec<u32> = vec![];
        let mut ranges = vec![];
        for m in &scene.meshes {
            let base = vertices.len() as i32;
            let first = indices.len() as u32;
            vertices.extend((0..m.positions.len()).map(|i| Vertex {
                position: m.positions[i].into(),
                normal: m.normals[i].into(),
                uv: m.uvs[i].into(),
                tangent: m.tangents[i].into(),
            }));
            indices.extend_from_slice(&m.indices);
            ranges.push((base, first, m.indices.len() as u32));
        }
        if vertices.is_empty() || indices.is_empty() {
            bail!("scene '{}' has no triangles", scene.name);
        }
        let objects: Vec<ObjectGpu> = scene
            .objects
            .iter()
            .map(|o| ObjectGpu {
                model: o.transform,
                normal_matrix: o.transform.inverse().transpose(),
                info: [
                    o.material as u32,
                    o.casts_shadow as u32,
                    o.receives_shadow as u32,
                    o.shadow_plane as u32,
                ],
            })
            .collect();
        let draws = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let (base_vertex, first_index, index_count) = ranges[o.mesh];
                DrawCall {
                    object: i as u32,
                    first_index,
                    index_count,
                    base_vertex,
                    material: o.material,
                    casts_shadow: o.casts_shadow,
                    shadow_plane: o.shadow_plane,
                }
            })
            .collect();
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let storage_ro = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let vertex_buffer = init(
            "vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX | storage_ro,
        );
        let index_buffer = init(
            "indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX | storage_ro,
        );
        let object_buffer = init("objects", bytemuck::cast_slice(&objects), storage_ro);
        let object_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("objects"),
            layout: &self.object_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: object_buffer.as_entire_binding(),
            }],
        });
        let gpu_textures: Vec<wgpu::TextureView> = scene
            .textures
            .iter()
            .map(|t| textures::upload(gpu, t))
            .collect();
        let white = textures::solid(gpu, [255, 255, 255, 255], true);
        let flat_normal = textures::solid(gpu, [128, 128, 255, 255], false);
        let material_bind_groups = scene
            .materials
            .iter()
            .map(|m| {
                let proc_kind = m.procedural.map_or(0.0, |p| p.kind as u32 as f32 + 1.0);
                let p = m.procedural;
                let data = MaterialGpu {
                    ka: m.ka.extend(m.uv_scale),
                    kd: m.kd.extend(m.diffuse_texture.is_some() as u32 as f32),
                    ks: m.ks.extend(m.shininess.max(1.0)),
                    proc_a: p.map_or(Vec3::ZERO, |p| p.color_a).extend(proc_kind),
                    proc_b: p
                        .map_or(Vec3::ZERO, |p| p.color_b)
                        .extend(p.map_or(1.0, |p| p.scale)),
                    flags: Vec4::new(
                        m.normal_map.is_some() as u32 as f32,
                        p.map_or(0.0, |p| p.octaves as f32),
                        0.0,
                        0.0,
                    ),
                };
                let buf = init(
                    "material",
                    bytemuck::bytes_of(&data),
                    wgpu::BufferUsages::UNIFORM,
                );
                let diffuse = m.diffuse_texture.map_or(&white, |t| &gpu_textures[t]);
                let normal = m.normal_map.map_or(&flat_normal, |t| &gpu_textures[t]);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(&m.name),
                    layout: &self.material_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: buf.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(diffuse),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::TextureView(normal),
                        },
                        wgpu::BindGroupEntry {
                            binding: 3,
                            resource: wgpu::BindingResource::Sampler(&self.sampler),
                        },
                    ],
                })
            })
            .collect();
        Ok(SceneGpu {
            vertex_buffer,
            index_buffer,
            object_buffer,
            object_bind_group,
            draws,
            material_bind_groups,
            triangle_count: scene.triangle_count(),
            caster_triangle_count: scene.caster_triangle_count(),
            bounds: scene.bounds(),
        })
    }

    /// Creates the targets for a `width × height` frame. Errors on a zero
    /// or over-limit size.
    pub fn create_frame(
        &self,
        gpu: &GpuContext,
        width: u32,
        height: u32,
    ) -> Result<FrameResources> {
        let max = gpu.max_texture_size();
        if width == 0 || height == 0 || width > max || height > max {
            bail!(
                "frame size {width}x{height} is outside 1..={max} (the device's largest texture)"
            );
        }
        // Depth, G-buffer position and normal, the mask layers and colour.
        let bytes_per_pixel = 4 + 16 + 8 + 2 * MAX_LIGHTS as u64 + 4;
        gpu.check_allocation(
            &format!("frame {width}x{height}"),
            (width, height, MAX_LIGHTS as u32),
            width as u64 * height as u64 * bytes_per_pixel,
        )?;
        let device = &gpu.device;
        use wgpu::TextureUsages as U;
        let depth = texture_2d(
            device,
            "depth",
            width,
            height,
            1,
            DEPTH_FORMAT,
            U::RENDER_ATTACHMENT | U::TEXTURE_BINDING,
        );
        let depth_view = depth.create_view(&Default::default());
        let depth_sample_view = depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let gusage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let gbuffer_position = texture_2d(
            device,
            "gbuffer position",
            width,
            height,
            1,
            GBUFFER_POSITION_FORMAT,
            gusage,
        );
        let gbuffer_normal = texture_2d(
            device,
            "gbuffer normal",
            width,
            height,
            1,
            GBUFFER_NORMAL_FORMAT,
            gusage,
        );
        let masks = texture_2d(
            device,
            "visibility masks",
            width,
            height,
            MAX_LIGHTS as u32,
            MASK_FORMAT,
            gusage | U::COPY_DST,
        );
        let mask_layer_views = (0..MAX_LIGHTS as u32)
            .map(|i| {
                masks.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: i,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let mask_array_view = masks.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let mask_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("masks"),
            layout: &self.mask_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&mask_array_view),
            }],
        });
        let color = texture_2d(
            device,
            "color",
            width,
            height,
            1,
            COLOR_FORMAT,
            U::RENDER_ATTACHMENT | U::COPY_SRC | U::TEXTURE_BINDING,
        );
        let color_view = color.create_view(&Default::default());
        let frame_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniform"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &self.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        Ok(FrameResources {
            width,
            height,
            gbuffer_position_view: gbuffer_position.create_view(&Default::default()),
            gbuffer_normal_view: gbuffer_normal.create_view(&Default::default()),
            depth,
            depth_view,
            depth_sample_view,
            gbuffer_position,
            gbuffer_normal,
            masks,
            mask_layer_views,
            mask_bind_group,
            color,
            color_view,
            frame_buffer,
            frame_bind_group,
            uniform: FrameUniform::zeroed(),
        })
    }

    /// Renders one frame into `frame.color`: prepass, one mask per light
    /// from `techniques[i]`, lighting, icons.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &self,
        gpu: &GpuContext,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        frame: &mut FrameResources,
        camera: &Camera,
        lights: &[Light],
        techniques: &mut [TechniqueInstance],
        settings: &RenderSettings,
    ) -> Result<FrameTimings> {
        if lights.len() > MAX_LIGHTS {
            bail!(
                "{} lights given; at most {MAX_LIGHTS} are supported",
                lights.len()
            );
        }
        if techniques.len() < lights.len() {
            bail!("one technique instance per light is needed");
        }
        camera.validate()?;
        for l in lights {
            l.validate()?;
        }
        let t0 = Instant::now();
        let needs = TechniqueNeeds::of(techniques)?;
        frame.uniform = frame_uniform(
            scene,
            camera,
            lights,
            &needs,
            settings,
            frame.width,
            frame.height,
        );
        gpu.queue
            .write_buffer(&frame.frame_buffer, 0, bytemuck::bytes_of(&frame.uniform));
        let cull = settings.cull_back_faces as usize;
        let timer = self.timer.as_ref().filter(|_| settings.gpu_timing);
        let stamp = |enc: &mut wgpu::CommandEncoder, i: u32| {
            if let Some(t) = timer {
                enc.write_timestamp(&t.queries, i);
            }
        };

        let mut enc = gpu.device.create_command_encoder(&Default::default());
        stamp(&mut enc, 0);
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("prepass"),
                color_attachments: &[
                    Some(color_attachment(
                        &frame.gbuffer_position_view,
                        wgpu::Color::TRANSPARENT,
                    )),
                    Some(color_attachment(
                        &frame.gbuffer_normal_view,
                        wgpu::Color::TRANSPARENT,
                    )),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &frame.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0),
                        store: wgpu::StoreOp::Store,
                    }),
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.gbuffer_pipelines[cull]);
            pass.set_bind_group(0, &frame.frame_bind_group, &[]);
            pass.set_bind_group(1, &scene_gpu.object_bind_group, &[]);
            scene_gpu.draw_objects(&mut pass, |_| true);
        }
        stamp(&mut enc, 1);
        gpu.queue.submit([enc.finish()]);
        gpu.wait_idle()?;
        let t1 = Instant::now();

        let mut enc = gpu.device.create_command_encoder(&Default::default());
        stamp(&mut enc, 2);
        for (i, light) in lights.iter().enumerate() {
            let inst = &mut techniques[i];
            let ctx = MaskContext {
                gpu,
                scene,
                scene_gpu,
                frame,
                light_index: i,
                light,
                camera,
                params: &inst.choice.params,
                target: &frame.mask_layer_views[i],
            };
            inst.technique.render_mask(&ctx, &mut enc)?;
        }
        stamp(&mut enc, 3);
        gpu.queue.submit([enc.finish()]);
        gpu.wait_idle()?;
        for inst in techniques.iter_mut().take(lights.len()) {
            inst.technique.after_frame(gpu)?;
        }
        let t2 = Instant::now();

        let bg = settings.background.unwrap_or(scene.background);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        stamp(&mut enc, 4);
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lighting"),
                color_attachments: &[Some(color_attachment(
                    &frame.color_view,
                    wgpu::Color {
                        r: bg.x as f64,
                        g: bg.y as f64,
                        b: bg.z as f64,
                        a: 1.0,
                    },
                ))],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &frame.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.lit_pipelines[cull]);
            pass.set_bind_group(0, &frame.frame_bind_group, &[]);
            pass.set_bind_group(1, &scene_gpu.object_bind_group, &[]);
            pass.set_bind_group(3, &frame.mask_bind_group, &[]);
            pass.set_vertex_buffer(0, scene_gpu.vertex_buffer.slice(..));
            pass.set_index_buffer(scene_gpu.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
            let mut bound = usize::MAX;
            for d in scene_gpu.draws.iter().filter(|d| !d.shadow_plane) {
                if d.material != bound {
                    pass.set_bind_group(2, &scene_gpu.material_bind_groups[d.material], &[]);
                    bound = d.material;
                }
                pass.draw_indexed(
                    d.first_index..d.first_index + d.index_count,
                    d.base_vertex,
                    d.object..d.object + 1,
                );
            }
            if settings.show_light_icons {
                self.icons.draw(
                    gpu,
                    &mut pass,
                    &frame.frame_bind_group,
                    lights,
                    &scene_gpu.bounds,
                );
            }
        }
        stamp(&mut enc, 5);
        if let Some(t) = timer {
            enc.resolve_query_set(&t.queries, 0..6, &t.resolve, 0);
            enc.copy_buffer_to_buffer(&t.resolve, 0, &t.readback, 0, 48);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.wait_idle()?;
        let t3 = Instant::now();
        let gpu_times = match timer {
            Some(t) => Some(t.read(gpu)?),
            None => None,
        };
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        Ok(FrameTimings {
            prepass_ms: ms(t0, t1),
            masks_ms: ms(t1, t2),
            lighting_ms: ms(t2, t3),
            total_ms: ms(t0, t3),
            gpu: gpu_times,
        })
    }
}

/// Uploads a CPU-computed visibility mask (row-major, top row first) into
/// layer `layer` of the frame's masks.
pub fn write_mask(gpu: &GpuContext, frame: &FrameResources, layer: usize, mask: &[f32]) {
    let data: Vec<half::f16> = mask.iter().map(|&v| half::f16::from_f32(v)).collect();
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &frame.masks,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer as u32,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(&data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(frame.width * 2),
            rows_per_image: Some(frame.height),
        },
        wgpu::Extent3d {
            width: frame.width,
            height: frame.height,
            depth_or_array_layers: 1,
        },
    );
}

fn color_attachment(
    view: &wgpu::TextureView,
    clear: wgpu::Color,
) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            store: wgpu::StoreOp::Store,
        },
    }
}

/// What the lights' techniques ask of the frame.
#[derive(Clone, Debug, Default)]
pub struct TechniqueNeeds {
    /// Per light: how its mask is composed.
    pub compose: Vec<Compose>,
    /// Some technique needs the far plane at infinity (shadow volumes).
    pub infinite_far_plane: bool,
}

impl TechniqueNeeds {
    pub fn of(techniques: &[TechniqueInstance]) -> Result<TechniqueNeeds> {
        let mut infinite_far_plane = false;
        for t in techniques {
            infinite_far_plane |= t.technique.infinite_far_plane(&t.choice.params)?;
        }
        Ok(TechniqueNeeds {
            compose: techniques
                .iter()
                .map(|t| Compose::of(&t.choice.params))
                .collect(),
            infinite_far_plane,
        })
    }
}

/// The frame uniform for a camera and lights (each with its mask's compose
/// mode) at a frame size.
pub fn frame_uniform(
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    needs: &TechniqueNeeds,
    settings: &RenderSettings,
    width: u32,
    height: u32,
) -> FrameUniform {
    let view = camera.view();
    let aspect = width as f32 / height as f32;
    let proj = if needs.infinite_far_plane {
        camera.projection_infinite(aspect)
    } else {
        camera.projection(aspect)
    };
    let view_proj = proj * view;
    let mut gl = [LightGpu::default(); MAX_LIGHTS];
    for (i, (g, l)) in gl.iter_mut().zip(lights).enumerate() {
        *g = LightGpu::from_light(l, needs.compose.get(i).copied().unwrap_or(Compose::Relight));
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
        settings: [
            settings.shading as u32,
            settings.lighting as u32,
            lights.len().min(MAX_LIGHTS) as u32,
            0,
        ],
        lights: gl,
    }
}
