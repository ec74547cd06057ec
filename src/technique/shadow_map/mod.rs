//! `shadow-map`: shadow maps (Williams 1978; SEEDS §5, 000 §4, 001 §3,
//! 002 §2). Depth from the light — perspective for spot lights, six 90°
//! faces for point lights, orthographic for directional lights fitted to the
//! scene and clipped to what the camera sees — then a screen-space lookup
//! that moves each G-buffer point along its normal (normal offset), projects
//! it with the light's matrices (wgpu: NDC z in [0,1], texture v down, see
//! `light_space::bias_matrix`), compares depths (`z ≤ stored` is lit,
//! outside the map is lit) and filters: nearest, hardware 2×2 PCF, N×N grid,
//! rotated Vogel disk, PCSS, or the documents' variable-width PCF.

use super::{Family, MaskContext, ParamSpec, Preset, ShadowTechnique};
use crate::renderer::{MASK_FORMAT, VERTEX_LAYOUT};
use crate::scene::{Aabb, Camera, Light, LightType};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, UVec4, Vec3, Vec4};
use std::collections::HashMap;

const FILTERS: &[&str] = &[
    "hard", "pcf2x2", "grid", "disk", "pcss", "varwidth", "vsm", "esm", "evsm2", "evsm4", "msm",
];
/// Index of the first moment-based filter in [`FILTERS`].
const FIRST_MOMENT_FILTER: usize = 6;
const FORMATS: &[&str] = &["d16", "d24", "d32f", "r8"];

pub static FAMILY: Family = Family {
    id: "shadow-map",
    summary: "shadow maps: depth from the light, compared per pixel, with the PCF family of filters",
    params: &[
        ParamSpec::choice(
            "filter",
            FILTERS,
            2,
            "hard: nearest texel; pcf2x2: hardware bilinear comparison; grid: N×N 2×2-PCF taps; disk: N² taps on a rotated Vogel disk; pcss: blocker search + penumbra from the light size; varwidth: radius ∝ |d_blocker − d_receiver|^exponent (002); vsm: variance (Chebyshev) with light-bleeding reduction; esm: exponential; evsm2/evsm4: exponential variance, 2 or 4 moments; msm: 4-moment Hamburger (Peters & Klein 2015)",
        ),
        ParamSpec::int(
            "samples",
            3,
            1,
            16,
            "taps per side: grid N×N (up to 16×16), disk N²",
        ),
        ParamSpec::float(
            "radius",
            1.5,
            0.0,
            32.0,
            0.25,
            "filter radius in texels (grid and disk)",
        ),
        ParamSpec::int(
            "size",
            2048,
            64,
            16384,
            "map side in texels (per cube face for point lights)",
        ),
        ParamSpec::choice(
            "format",
            FORMATS,
            2,
            "depth format; r8 stores depth in 8 bits and shows the low-precision failure",
        ),
        ParamSpec::float(
            "depth_bias",
            2.0,
            0.0,
            100000.0,
            1.0,
            "constant depth bias of the depth pass, in the format's smallest steps",
        ),
        ParamSpec::float(
            "slope_bias",
            2.0,
            0.0,
            20.0,
            0.1,
            "slope-scaled depth bias (polygon offset factor)",
        ),
        ParamSpec::float(
            "normal_offset_directional",
            1.0,
            0.0,
            10.0,
            0.1,
            "directional lights: lookup point moved along the geometric normal, in shadow-map texels",
        ),
        ParamSpec::float(
            "normal_offset_local",
            0.5,
            0.0,
            10.0,
            0.1,
            "point and spot lights: lookup point moved along the geometric normal, in shadow-map texels at the point's distance",
        ),
        ParamSpec::boolean(
            "receiver_plane",
            false,
            "receiver-plane depth bias (Isidoro 2006): each tap compares against the receiver's plane at the tap, from screen derivatives of the light-space position",
        ),
        ParamSpec::choice(
            "cull",
            &["back", "front", "none"],
            2,
            "faces culled in the depth pass; back or front culling leaks light through open meshes (bunny, teapot)",
        ),
        ParamSpec::choice(
            "omni",
            &["cube", "dual-paraboloid"],
            0,
            "point lights: six 90° faces (cube) or two paraboloid hemispheres (Brabec 2002; distorts large triangles)",
        ),
        ParamSpec::float(
            "near",
            0.0,
            0.0,
            10000.0,
            0.01,
            "near plane of the light frustum (0 = fitted to the scene)",
        ),
        ParamSpec::float(
            "far",
            0.0,
            0.0,
            100000.0,
            0.1,
            "far plane of the light frustum (0 = fitted to the scene)",
        ),
        ParamSpec::float(
            "fov",
            0.0,
            0.0,
            170.0,
            1.0,
            "spot light frustum angle in degrees (0 = the cone plus 4°); precision degrades above 90°",
        ),
        ParamSpec::float(
            "light_size",
            24.0,
            0.0,
            400.0,
            1.0,
            "pcss: light size, as the penumbra width in texels per unit of (d_receiver − d_blocker)/d_blocker",
        ),
        ParamSpec::float(
            "blocker_search",
            12.0,
            1.0,
            64.0,
            1.0,
            "pcss and varwidth: blocker-search radius in texels",
        ),
        ParamSpec::float(
            "varwidth_scale",
            8.0,
            0.0,
            200.0,
            0.5,
            "varwidth: texels of radius per unit of |d_blocker − d_receiver|^exponent",
        ),
        ParamSpec::float(
            "varwidth_exponent",
            1.0,
            0.1,
            4.0,
            0.1,
            "varwidth: the exponent",
        ),
        ParamSpec::int(
            "blur",
            2,
            0,
            16,
            "moment filters: separable box blur radius in texels (0 = none)",
        ),
        ParamSpec::boolean(
            "area",
            false,
            "lights with an area size: accumulate `area_maps` shadow maps rendered from stratified points of the area",
        ),
        ParamSpec::int(
            "area_maps",
            16,
            1,
            64,
            "area: number of shadow maps (the documents use the 4 corners)",
        ),
        ParamSpec::float(
            "bleeding_reduction",
            0.2,
            0.0,
            0.95,
            0.01,
            "vsm and evsm: light-bleeding reduction, the lower cut of the Chebyshev bound",
        ),
        ParamSpec::float(
            "exponent",
            40.0,
            1.0,
            80.0,
            1.0,
            "esm and evsm: exponent c of the positive warp exp(c(z − 1))",
        ),
        ParamSpec::float(
            "exponent_negative",
            5.0,
            1.0,
            40.0,
            1.0,
            "evsm4: exponent of the negative warp −exp(−c z)",
        ),
        ParamSpec::float(
            "moment_bias",
            3e-5,
            0.0,
            0.01,
            1e-5,
            "msm: moment bias α towards (0.5, 0.5, 0.5, 0.5)",
        ),
        ParamSpec::choice(
            "stage",
            &["full", "maps", "floor"],
            0,
            "full: maps and lookup; maps: the shadow-map pass alone (mask = 1); floor: a bare depth-only render of the same casters into the same map (position-only, no bias, no colour; mask = 1), what a shadow map cannot beat",
        ),
    ],
    presets: &[
        Preset {
            name: "pcf",
            summary: "3×3 grid of hardware 2×2 PCF taps over ±1.5 texels, 2048², d32f",
            values: &[],
        },
        Preset {
            name: "hard",
            summary: "nearest texel, no filtering",
            values: &[("filter", "hard")],
        },
        Preset {
            name: "pcf2x2",
            summary: "one hardware bilinear comparison",
            values: &[("filter", "pcf2x2")],
        },
        Preset {
            name: "pcf-disk",
            summary: "16 taps on a per-pixel rotated Vogel disk of radius 2.5 texels",
            values: &[("filter", "disk"), ("samples", "4"), ("radius", "2.5")],
        },
        Preset {
            name: "pcss",
            summary: "percentage-closer soft shadows",
            values: &[("filter", "pcss"), ("samples", "5")],
        },
        Preset {
            name: "varwidth",
            summary: "the documents' variable-width PCF",
            values: &[("filter", "varwidth"), ("samples", "4")],
        },
        Preset {
            name: "vsm",
            summary: "variance shadow map, 1024², blurred",
            values: &[("filter", "vsm"), ("size", "1024")],
        },
        Preset {
            name: "esm",
            summary: "exponential shadow map, 1024², blurred",
            values: &[("filter", "esm"), ("size", "1024")],
        },
        Preset {
            name: "evsm2",
            summary: "exponential variance shadow map, positive warp only",
            values: &[("filter", "evsm2"), ("size", "1024")],
        },
        Preset {
            name: "evsm4",
            summary: "exponential variance shadow map, both warps",
            values: &[("filter", "evsm4"), ("size", "1024")],
        },
        Preset {
            name: "msm",
            summary: "4-moment Hamburger shadow map",
            values: &[("filter", "msm"), ("size", "1024")],
        },
        Preset {
            name: "area",
            summary: "soft shadows: 16 maps from stratified points of the light's area, averaged",
            values: &[("area", "true"), ("filter", "pcf2x2"), ("size", "1024")],
        },
        Preset {
            name: "8bit",
            summary: "depth stored in 8 bits: acne everywhere",
            values: &[("format", "r8"), ("filter", "hard")],
        },
    ],
    create: |gpu| Ok(Box::new(ShadowMapTechnique::new(gpu))),
};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShadowMapUniform {
    faces: [Mat4; 6],
    light: Vec4,
    kernel: Vec4,
    map: Vec4,
    soft: Vec4,
    depth: Vec4,
    face: UVec4,
    moments: Vec4,
}

/// The light's matrices for one frame.
#[derive(Clone, Debug)]
pub struct LightSetup {
    pub faces: Vec<Mat4>,
    pub near: f32,
    pub far: f32,
    pub orthographic: bool,
    /// `faces` are the two hemispheres' view matrices of a dual paraboloid.
    pub paraboloid: bool,
    /// World size of a texel at unit distance (perspective) or anywhere (orthographic), for a 1-texel map.
    pub texel_scale: f32,
}

fn up_for(dir: Vec3) -> Vec3 {
    if dir.normalize().dot(Vec3::Y).abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// Near/far of a local light around `bounds`, unless given.
fn near_far(pos: Vec3, bounds: &Aabb, near: f32, far: f32) -> (f32, f32) {
    let auto_far = bounds
        .corners()
        .iter()
        .map(|c| c.distance(pos))
        .fold(0.0f32, f32::max)
        .max(1e-3)
        * 1.01;
    let f = if far > 0.0 { far } else { auto_far };
    let closest = pos.clamp(bounds.min, bounds.max).distance(pos);
    let n = if near > 0.0 {
        near
    } else {
        (closest * 0.95).max(f * 2e-3)
    };
    (n, f.max(n * 1.01))
}

/// The six 90° views of a point light: +X, −X, +Y, −Y, +Z, −Z.
pub fn cube_views(pos: Vec3) -> [Mat4; 6] {
    let v = |d: Vec3, up: Vec3| glam::camera::rh::view::look_to_mat4(pos, d, up);
    [
        v(Vec3::X, Vec3::NEG_Y),
        v(Vec3::NEG_X, Vec3::NEG_Y),
        v(Vec3::Y, Vec3::Z),
        v(Vec3::NEG_Y, Vec3::NEG_Z),
        v(Vec3::Z, Vec3::NEG_Y),
        v(Vec3::NEG_Z, Vec3::NEG_Y),
    ]
}

/// The user's choices for the light frustum (0 = fitted).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrustumParams {
    pub near: f32,
    pub far: f32,
    pub fov_deg: f32,
    /// Point lights: two paraboloid hemispheres instead of six faces.
    pub paraboloid: bool,
}

/// Light matrices: spot (perspective over the cone), point (six faces),
/// directional (orthographic around the scene, its xy clipped to the
/// camera's view of the scene).
pub fn light_setup(
    light: &Light,
    scene_bounds: &Aabb,
    camera: &Camera,
    aspect: f32,
    fp: &FrustumParams,
) -> LightSetup {
    let FrustumParams {
        near,
        far,
        fov_deg,
        paraboloid,
    } = *fp;
    use glam::camera::rh::proj::directx::{orthographic, perspective};
    match light.kind {
        LightType::Spot => {
            let (n, f) = near_far(light.position, scene_bounds, near, far);
            let fov = if fov_deg > 0.0 {
                fov_deg
            } else {
                (2.0 * light.outer_cone_deg + 4.0).min(170.0)
            }
            .to_radians();
            let view = glam::camera::rh::view::look_to_mat4(
                light.position,
                light.direction,
                up_for(light.direction),
            );
            LightSetup {
                faces: vec![perspective(fov, 1.0, n, f) * view],
                near: n,
                far: f,
                orthographic: false,
                paraboloid: false,
                texel_scale: 2.0 * (fov * 0.5).tan(),
            }
        }
        LightType::Point if paraboloid => {
            let (n, f) = near_far(light.position, scene_bounds, near, far);
            let v = |d: Vec3| glam::camera::rh::view::look_to_mat4(light.position, d, Vec3::Z);
            LightSetup {
                faces: vec![v(Vec3::NEG_Y), v(Vec3::Y)],
                near: n,
                far: f,
                orthographic: false,
                paraboloid: true,
                // At the centre of a hemisphere, uv changes by 1/2 per radian.
                texel_scale: 4.0,
            }
        }
        LightType::Point => {
            let (n, f) = near_far(light.position, scene_bounds, near, far);
            let proj = perspective(std::f32::consts::FRAC_PI_2, 1.0, n, f);
            LightSetup {
                faces: cube_views(light.position)
                    .iter()
                    .map(|v| proj * *v)
                    .collect(),
                near: n,
                far: f,
                orthographic: false,
                paraboloid: false,
                texel_scale: 2.0,
            }
        }
        LightType::Directional => {
            let dir = light.direction.normalize();
            let c = scene_bounds.center();
            let r = scene_bounds.size().length() * 0.5 + 1e-3;
            let view = glam::camera::rh::view::look_to_mat4(c - dir * (2.0 * r), dir, up_for(dir));
            let scene_ls = scene_bounds.transformed(view);
            // The camera frustum, its far plane pulled in to the scene, in light space.
            let vp = camera.projection(aspect) * camera.view();
            let inv = vp.inverse();
            let reach = (camera.eye.distance(c) + r).min(camera.far);
            let far_z = {
                let p = camera.projection(aspect) * Vec4::new(0.0, 0.0, -reach, 1.0);
                (p.z / p.w).clamp(0.0, 1.0)
            };
            let corners = [0.0f32, far_z].into_iter().flat_map(|z| {
                [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)].map(|(x, y)| {
                    let w = inv * Vec4::new(x, y, z, 1.0);
                    view.transform_point3(w.truncate() / w.w)
                })
            });
            let cam_ls = Aabb::from_points(corners);
            let min_x = scene_ls.min.x.max(cam_ls.min.x);
            let max_x = scene_ls.max.x.min(cam_ls.max.x);
            let min_y = scene_ls.min.y.max(cam_ls.min.y);
            let max_y = scene_ls.max.y.min(cam_ls.max.y);
            let (min_x, max_x, min_y, max_y) = if min_x < max_x && min_y < max_y {
                (min_x, max_x, min_y, max_y)
            } else {
                (
                    scene_ls.min.x,
                    scene_ls.max.x,
                    scene_ls.min.y,
                    scene_ls.max.y,
                )
            };
            // Square texels: the larger extent on both axes.
            let half = ((max_x - min_x).max(max_y - min_y) * 0.5).max(1e-3);
            let (cx, cy) = ((min_x + max_x) * 0.5, (min_y + max_y) * 0.5);
            // View space looks down −z: depth range from the scene's z extent.
            let (n, f) = (-scene_ls.max.z - 1e-3, -scene_ls.min.z + 1e-3);
            LightSetup {
                faces: vec![
                    orthographic(cx - half, cx + half, cy - half, cy + half, n.max(0.0), f) * view,
                ],
                near: n.max(0.0),
                far: f,
                orthographic: true,
                paraboloid: false,
                texel_scale: 2.0 * half,
            }
        }
    }
}

/// Point lights standing in for an area light: `n` stratified points of its
/// disk (sphere lights, facing `towards`) or rectangle (facing its
/// direction); for directional lights, directions within its angular radius.
pub fn area_samples(light: &Light, n: usize, towards: Vec3) -> Vec<Light> {
    use crate::scene::LightArea;
    use crate::technique::raytraced::{concentric_disk, stratified_square};
    let Some(area) = light.area else {
        return vec![*light];
    };
    stratified_square(n, || (0.5, 0.5))
        .into_iter()
        .map(|(a, b)| {
            let ((u, v), (hu, hv)) = match area {
                LightArea::Sphere { radius } => (concentric_disk(a, b), (radius, radius)),
                LightArea::Rect { width, height } => ((a, b), (width * 0.5, height * 0.5)),
            };
            let mut l = *light;
            l.area = None;
            match light.kind {
                LightType::Directional => {
                    let d = light.direction.normalize();
                    let t = d.any_orthonormal_vector();
                    l.direction = (d + t * (u * hu) + d.cross(t) * (v * hv)).normalize();
                }
                _ => {
                    let axis = match area {
                        LightArea::Sphere { .. } => {
                            (towards - light.position).normalize_or(Vec3::NEG_Y)
                        }
                        LightArea::Rect { .. } => light.direction.normalize_or(Vec3::NEG_Y),
                    };
                    let t = axis.any_orthonormal_vector();
                    l.position += t * (u * hu) + axis.cross(t) * (v * hv);
                }
            }
            l
        })
        .collect()
}

/// What a depth-pass pipeline depends on.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct DepthPassKey {
    format: usize,
    cull: usize,
    bias: i32,
    slope_bits: u32,
    moments: bool,
    paraboloid: bool,
}

struct Maps {
    size: u32,
    layers: u32,
    format: usize,
    moments: bool,
    depth_layer_views: Vec<wgpu::TextureView>,
    depth_array: wgpu::TextureView,
    /// The 8-bit map: per-layer views and the array view.
    byte: Option<(Vec<wgpu::TextureView>, wgpu::TextureView)>,
    /// Moment maps A (result) and B (blur scratch): per-layer views and array views.
    moment: Option<[(Vec<wgpu::TextureView>, wgpu::TextureView); 2]>,
    bytes: u64,
}

pub struct ShadowMapTechnique {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    depth_pipelines: HashMap<DepthPassKey, wgpu::RenderPipeline>,
    /// `stage=floor`: bare depth-only pipelines per depth format.
    floor_pipelines: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    lookup: wgpu::RenderPipeline,
    /// The lookup adding `constant × visibility` (area maps).
    lookup_accumulate: wgpu::RenderPipeline,
    blur: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    compare_sampler: wgpu::Sampler,
    placeholder_bytes: wgpu::TextureView,
    /// Bound in place of the maps while they are rendered.
    placeholder_depth: wgpu::TextureView,
    placeholder_moments: wgpu::TextureView,
    maps: Option<Maps>,
    /// Shadow maps rendered per face last frame (area lights: several).
    samples: usize,
    /// Debug views: a 256² picture of face 0 and the last light matrices.
    debug: Option<wgpu::Texture>,
    debug_pipeline: wgpu::RenderPipeline,
    /// Frame-sized debug views: the map projected onto the scene, texels per pixel.
    debug_frame: Option<[wgpu::Texture; 2]>,
    debug_frame_pipeline: wgpu::RenderPipeline,
    last_faces: Vec<Mat4>,
    last_paraboloid: bool,
    want_debug: bool,
}

/// Uniform slots: per face, the depth pass (and lookup), blur along x, blur along y.
const STRIDE: u64 = 512;
const SLOTS: u64 = 18;
const MOMENT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

fn depth_format(i: usize) -> wgpu::TextureFormat {
    match i {
        0 | 3 => wgpu::TextureFormat::Depth16Unorm,
        1 => wgpu::TextureFormat::Depth24Plus,
        _ => wgpu::TextureFormat::Depth32Float,
    }
}

fn placeholder(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::TextureView {
    crate::renderer::texture_2d(
        device,
        "shadow map placeholder",
        1,
        1,
        1,
        format,
        wgpu::TextureUsages::TEXTURE_BINDING,
    )
    .create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

impl ShadowMapTechnique {
    pub fn new(gpu: &crate::gpu::GpuContext) -> ShadowMapTechnique {
        let device = &gpu.device;
        let tex = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow map"),
            entries: &[
                crate::renderer::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT, true),
                super::gbuffer_entry(1),
                super::gbuffer_entry(2),
                tex(3, wgpu::TextureSampleType::Depth),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                tex(5, wgpu::TextureSampleType::Float { filterable: false }),
                tex(6, wgpu::TextureSampleType::Float { filterable: false }),
            ],
        });
        let module = crate::renderer::shader_module(
            device,
            "shadow map",
            &[include_str!("shadow_map.wgsl")],
        );
        let pipeline_layout = super::pipeline_layout(gpu, "shadow map", &layout);
        let fullscreen = |label: &str,
                          fs: &str,
                          target: wgpu::ColorTargetState,
                          depth: Option<wgpu::DepthStencilState>| {
            super::fullscreen_pipeline(
                device,
                label,
                &pipeline_layout,
                &module,
                fs,
                &[Some(target)],
                depth,
            )
        };
        let mask_depth = Some(super::frame_depth_read(Default::default()));
        let lookup = fullscreen(
            "shadow map lookup",
            "fs_lookup",
            MASK_FORMAT.into(),
            mask_depth.clone(),
        );
        let lookup_accumulate = fullscreen(
            "shadow map lookup (accumulate)",
            "fs_lookup",
            wgpu::ColorTargetState {
                format: MASK_FORMAT,
                blend: Some(wgpu::BlendState {
                    color: wgpu::BlendComponent {
                        src_factor: wgpu::BlendFactor::Constant,
                        dst_factor: wgpu::BlendFactor::One,
                        operation: wgpu::BlendOperation::Add,
                    },
                    alpha: wgpu::BlendComponent::REPLACE,
                }),
                write_mask: wgpu::ColorWrites::RED,
            },
            mask_depth,
        );
        let blur = fullscreen("shadow map blur", "fs_blur", MOMENT_FORMAT.into(), None);
        let debug_frame_pipeline = super::fullscreen_pipeline(
            device,
            "shadow map debug frame",
            &pipeline_layout,
            &module,
            "fs_debug_frame",
            &[
                Some(wgpu::TextureFormat::Rgba8Unorm.into()),
                Some(wgpu::TextureFormat::Rgba8Unorm.into()),
            ],
            None,
        );
        let debug_pipeline = fullscreen(
            "shadow map debug",
            "fs_debug_map",
            wgpu::TextureFormat::Rgba8Unorm.into(),
            None,
        );
        ShadowMapTechnique {
            uniforms: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow map uniforms"),
                size: STRIDE * SLOTS,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            compare_sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow compare"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
            placeholder_bytes: placeholder(device, wgpu::TextureFormat::R8Unorm),
            placeholder_depth: placeholder(device, wgpu::TextureFormat::Depth32Float),
            placeholder_moments: placeholder(device, MOMENT_FORMAT),
            layout,
            pipeline_layout,
            module,
            depth_pipelines: HashMap::new(),
            floor_pipelines: HashMap::new(),
            lookup,
            lookup_accumulate,
            blur,
            maps: None,
            samples: 0,
            debug: None,
            debug_pipeline,
            debug_frame: None,
            debug_frame_pipeline,
            last_faces: vec![],
            last_paraboloid: false,
            want_debug: false,
        }
    }

    fn depth_pipeline(
        &mut self,
        device: &wgpu::Device,
        key: DepthPassKey,
    ) -> &wgpu::RenderPipeline {
        let DepthPassKey {
            format,
            cull,
            bias,
            slope_bits,
            moments,
            paraboloid,
        } = key;
        let slope = f32::from_bits(slope_bits);
        let (module, layout) = (&self.module, &self.pipeline_layout);
        self.depth_pipelines.entry(key).or_insert_with(|| {
            let (entry, color) = if moments {
                (Some("fs_depth_moments"), Some(MOMENT_FORMAT))
            } else if format == 3 {
                (Some("fs_depth_byte"), Some(wgpu::TextureFormat::R8Unorm))
            } else if paraboloid {
                (Some("fs_depth_paraboloid"), None)
            } else {
                (None, None)
            };
            let targets = [color.map(wgpu::ColorTargetState::from)];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("shadow map depth"),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_depth"),
                    compilation_options: Default::default(),
                    buffers: &[Some(VERTEX_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: [Some(wgpu::Face::Back), Some(wgpu::Face::Front), None][cull],
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: depth_format(format),
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: Default::default(),
                    bias: wgpu::DepthBiasState {
                        constant: bias,
                        slope_scale: slope,
                        clamp: 0.0,
                    },
                }),
                multisample: Default::default(),
                fragment: entry.map(|e| wgpu::FragmentState {
                    module,
                    entry_point: Some(e),
                    compilation_options: Default::default(),
                    targets: if targets[0].is_some() { &targets } else { &[] },
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }

    /// The floor of `stage=floor`: positions transformed by the face matrix,
    /// depth test and write, nothing else.
    fn floor_pipeline(
        &mut self,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
    ) -> &wgpu::RenderPipeline {
        let (module, layout) = (&self.module, &self.pipeline_layout);
        self.floor_pipelines.entry(format).or_insert_with(|| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("shadow map floor"),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_floor"),
                    compilation_options: Default::default(),
                    buffers: &[Some(VERTEX_LAYOUT)],
                },
                primitive: Default::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: None,
                multiview_mask: None,
                cache: None,
            })
        })
    }

    fn ensure_maps(
        &mut self,
        gpu: &crate::gpu::GpuContext,
        size: u32,
        layers: u32,
        format: usize,
        moments: bool,
    ) -> Result<()> {
        if self.maps.as_ref().is_some_and(|m| {
            (m.size, m.layers, m.format, m.moments) == (size, layers, format, moments)
        }) {
            return Ok(());
        }
        let texels = size as u64 * size as u64 * layers as u64;
        let depth_bytes = [2u64, 4, 4, 2][format];
        let bytes = texels * (depth_bytes + (format == 3) as u64 + if moments { 32 } else { 0 });
        gpu.check_allocation(
            &format!(
                "shadow-map: {layers} map(s) of {size}x{size} (--set size=N; largest texture {})",
                gpu.max_texture_size()
            ),
            (size, size, layers),
            bytes,
        )?;
        // Free the old maps first; keep the new ones only once created.
        self.maps = None;
        let make = |f: wgpu::TextureFormat| {
            crate::renderer::texture_2d(
                &gpu.device,
                "shadow map",
                size,
                size,
                layers,
                f,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            )
        };
        let views = |t: &wgpu::Texture| -> (Vec<wgpu::TextureView>, wgpu::TextureView) {
            let layer_views = (0..layers)
                .map(|i| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: i,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect();
            let array = t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            (layer_views, array)
        };
        let maps = gpu.checked("allocating the shadow maps", || {
            let (depth_layer_views, depth_array) = views(&make(depth_format(format)));
            let byte = (format == 3).then(|| views(&make(wgpu::TextureFormat::R8Unorm)));
            let moment =
                moments.then(|| [views(&make(MOMENT_FORMAT)), views(&make(MOMENT_FORMAT))]);
            Ok(Maps {
                size,
                layers,
                format,
                moments,
                depth_layer_views,
                depth_array,
                byte,
                moment,
                bytes,
            })
        })?;
        self.maps = Some(maps);
        Ok(())
    }

    /// The technique's bind group with the given depth, 8-bit and moment arrays.
    fn bind_group(
        &self,
        ctx: &MaskContext,
        depth: &wgpu::TextureView,
        bytes: &wgpu::TextureView,
        moments: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let view = |binding, v| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(v),
        };
        ctx.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow map"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: crate::renderer::dynamic_uniform::<ShadowMapUniform>(
                            &self.uniforms,
                        ),
                    },
                    view(1, &ctx.frame.gbuffer_position_view),
                    view(2, &ctx.frame.gbuffer_normal_view),
                    view(3, depth),
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::Sampler(&self.compare_sampler),
                    },
                    view(5, bytes),
                    view(6, moments),
                ],
            })
    }
}

fn clear_op(color: wgpu::Color) -> wgpu::Operations<wgpu::Color> {
    wgpu::Operations {
        load: wgpu::LoadOp::Clear(color),
        store: wgpu::StoreOp::Store,
    }
}

impl ShadowTechnique for ShadowMapTechnique {
    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let p = ctx.params;
        if self.want_debug && self.debug.is_none() {
            self.debug = Some(crate::renderer::texture_2d(
                &ctx.gpu.device,
                "shadow map debug",
                256,
                256,
                1,
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            ));
        }
        let aspect = ctx.frame.width as f32 / ctx.frame.height as f32;
        let size = p.get_usize("size")? as u32;
        let format = p.get_usize("format")?;
        let filter = p.get_usize("filter")?;
        let moments = filter >= FIRST_MOMENT_FILTER;
        let blur = if moments {
            p.get_usize("blur")? as u32
        } else {
            0
        };
        let normal_offset = match ctx.light.kind {
            LightType::Directional => p.get_f32("normal_offset_directional")?,
            _ => p.get_f32("normal_offset_local")?,
        };
        // An area light with `area` on becomes several point samples.
        let lights = if p.get_bool("area")? && ctx.light.area.is_some() {
            area_samples(
                ctx.light,
                p.get_usize("area_maps")?,
                ctx.scene_gpu.bounds.center(),
            )
        } else {
            vec![*ctx.light]
        };
        let area_radius = match ctx.light.area {
            Some(crate::scene::LightArea::Sphere { radius }) if lights.len() == 1 => radius,
            Some(crate::scene::LightArea::Rect { width, height }) if lights.len() == 1 => {
                width.max(height) * 0.5
            }
            _ => 0.0,
        };
        let frustum_params = FrustumParams {
            near: p.get_f32("near")?,
            far: p.get_f32("far")?,
            fov_deg: p.get_f32("fov")?,
            paraboloid: p.get_usize("omni")? == 1,
        };
        let setups: Vec<LightSetup> = lights
            .iter()
            .map(|l| {
                light_setup(
                    l,
                    &ctx.scene_gpu.bounds,
                    ctx.camera,
                    aspect,
                    &frustum_params,
                )
            })
            .collect();
        let layers = setups[0].faces.len() as u32;
        self.ensure_maps(ctx.gpu, size, layers, format, moments)?;
        // Slot (s·6 + f)·3 + k: sample s, face f; k = 0 depth pass and lookup, 1 and 2 blur along x and y.
        let slots = (lights.len() * 18) as u64;
        if self.uniforms.size() < slots * STRIDE {
            self.uniforms = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow map uniforms"),
                size: slots * STRIDE,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
        let mut data = vec![0u8; (slots * STRIDE) as usize];
        for (si, (light, setup)) in lights.iter().zip(&setups).enumerate() {
            let mut faces = [Mat4::IDENTITY; 6];
            faces[..setup.faces.len()].copy_from_slice(&setup.faces);
            let base = ShadowMapUniform {
                faces,
                light: light.position.extend(layers as f32),
                kernel: Vec4::new(
                    filter as f32,
                    p.get_f32("samples")?,
                    p.get_f32("radius")?,
                    normal_offset,
                ),
                map: Vec4::new(
                    size as f32,
                    1.0 / size as f32,
                    setup.texel_scale / size as f32,
                    if setup.paraboloid {
                        2.0
                    } else {
                        setup.orthographic as u32 as f32
                    },
                ),
                soft: Vec4::new(
                    p.get_f32("light_size")?,
                    p.get_f32("varwidth_scale")?,
                    p.get_f32("varwidth_exponent")?,
                    p.get_f32("blocker_search")?,
                ),
                depth: Vec4::new(
                    setup.near,
                    setup.far,
                    (format == 3) as u32 as f32,
                    area_radius,
                ),
                face: UVec4::ZERO,
                moments: Vec4::new(
                    p.get_f32("bleeding_reduction")?,
                    p.get_f32("exponent")?,
                    p.get_f32("exponent_negative")?,
                    p.get_f32("moment_bias")?,
                ),
            };
            for f in 0..6u32 {
                for k in 0..3u32 {
                    let u = ShadowMapUniform {
                        face: UVec4::new(
                            f,
                            k.saturating_sub(1),
                            blur,
                            p.get_bool("receiver_plane")? as u32,
                        ),
                        ..base
                    };
                    let at = (((si as u32 * 6 + f) * 3 + k) as u64 * STRIDE) as usize;
                    data[at..at + std::mem::size_of::<ShadowMapUniform>()]
                        .copy_from_slice(bytemuck::bytes_of(&u));
                }
            }
        }
        ctx.gpu.queue.write_buffer(&self.uniforms, 0, &data);
        let device = &ctx.gpu.device;
        let depth_bias = p.get("depth_bias")?.round().min(i32::MAX as f64) as i32;
        let key = DepthPassKey {
            format,
            cull: p.get_usize("cull")?,
            bias: depth_bias,
            slope_bits: p.get_f32("slope_bias")?.to_bits(),
            moments,
            paraboloid: frustum_params.paraboloid,
        };
        let stage = p.get_usize("stage")?;
        let floor = stage == 2;
        let pipeline = if floor {
            self.floor_pipeline(device, depth_format(format)).clone()
        } else {
            self.depth_pipeline(device, key).clone()
        };
        let maps = self.maps.as_ref().expect("ensured above");
        let slot =
            |s: usize, f: u32, k: u32| ((((s as u32) * 6 + f) * 3 + k) as u64 * STRIDE) as u32;
        // Bind groups: none of the maps while they are rendered; the moment
        // maps as blur sources; everything for the lookup.
        let render_group = self.bind_group(
            ctx,
            &self.placeholder_depth,
            &self.placeholder_bytes,
            &self.placeholder_moments,
        );
        let blur_groups = maps.moment.as_ref().map(|m| {
            [0, 1].map(|src| {
                self.bind_group(
                    ctx,
                    &self.placeholder_depth,
                    &self.placeholder_bytes,
                    &m[src].1,
                )
            })
        });
        let byte_array = maps.byte.as_ref().map_or(&self.placeholder_bytes, |b| &b.1);
        let moment_array = maps
            .moment
            .as_ref()
            .map_or(&self.placeholder_moments, |m| &m[0].1);
        let lookup_group = self.bind_group(ctx, &maps.depth_array, byte_array, moment_array);
        for si in 0..lights.len() {
            for face in 0..layers {
                let f = face as usize;
                let color = match (&maps.moment, &maps.byte, floor) {
                    (_, _, true) | (None, None, _) => None,
                    (Some(m), _, _) => Some(&m[0].0[f]),
                    (None, Some(b), _) => Some(&b.0[f]),
                }
                .map(|view| wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear_op(wgpu::Color::WHITE),
                });
                let colors = [color];
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("shadow map depth"),
                    color_attachments: if colors[0].is_some() { &colors } else { &[] },
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &maps.depth_layer_views[f],
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    ..Default::default()
                });
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &ctx.frame.frame_bind_group, &[]);
                pass.set_bind_group(1, &ctx.scene_gpu.object_bind_group, &[]);
                pass.set_bind_group(2, &render_group, &[slot(si, face, 0)]);
                ctx.scene_gpu.draw_objects(&mut pass, |d| d.casts_shadow);
            }
            if let (Some(m), Some(groups), true) = (&maps.moment, &blur_groups, blur > 0 && !floor)
            {
                // A → B along x, B → A along y.
                for (k, src, dst) in [(1u32, 0usize, 1usize), (2, 1, 0)] {
                    for face in 0..layers {
                        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                            label: Some("shadow map blur"),
                            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                                view: &m[dst].0[face as usize],
                                depth_slice: None,
                                resolve_target: None,
                                ops: clear_op(wgpu::Color::WHITE),
                            })],
                            ..Default::default()
                        });
                        pass.set_pipeline(&self.blur);
                        pass.set_bind_group(0, &ctx.frame.frame_bind_group, &[]);
                        pass.set_bind_group(1, &ctx.scene_gpu.object_bind_group, &[]);
                        pass.set_bind_group(2, &groups[src], &[slot(si, face, k)]);
                        pass.draw(0..3, 0..1);
                    }
                }
            }
            if stage != 0 {
                continue;
            }
            // One sample writes the mask; several add 1/N each onto a cleared mask.
            let (load, accumulate) = match (lights.len(), si) {
                (1, _) => (wgpu::LoadOp::Clear(wgpu::Color::WHITE), false),
                (_, 0) => (wgpu::LoadOp::Clear(wgpu::Color::BLACK), true),
                _ => (wgpu::LoadOp::Load, true),
            };
            let mut pass = super::mask_pass_with(encoder, ctx, "shadow map lookup", load);
            if accumulate {
                pass.set_pipeline(&self.lookup_accumulate);
                let w = 1.0 / lights.len() as f64;
                pass.set_blend_constant(wgpu::Color {
                    r: w,
                    g: w,
                    b: w,
                    a: w,
                });
            } else {
                pass.set_pipeline(&self.lookup);
            }
            pass.set_bind_group(0, &ctx.frame.frame_bind_group, &[]);
            pass.set_bind_group(1, &ctx.scene_gpu.object_bind_group, &[]);
            pass.set_bind_group(2, &lookup_group, &[slot(si, 0, 0)]);
            pass.draw(0..3, 0..1);
        }
        if stage != 0 {
            // The maps alone: no lookup, a lit mask.
            crate::renderer::clear_mask(encoder, ctx.target, 1.0);
        }
        if let Some(t) = &self.debug {
            // Face 0 of the (last) map, for the viewer.
            let view = t.create_view(&Default::default());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map debug"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear_op(wgpu::Color::BLACK),
                })],
                ..Default::default()
            });
            pass.set_pipeline(&self.debug_pipeline);
            pass.set_bind_group(0, &ctx.frame.frame_bind_group, &[]);
            pass.set_bind_group(1, &ctx.scene_gpu.object_bind_group, &[]);
            pass.set_bind_group(2, &lookup_group, &[slot(lights.len() - 1, 0, 0)]);
            pass.draw(0..3, 0..1);
            drop(pass);
            // The frame-sized views, (re)made at the frame's size.
            let (w, h) = (ctx.frame.width, ctx.frame.height);
            if self
                .debug_frame
                .as_ref()
                .is_none_or(|t| (t[0].width(), t[0].height()) != (w, h))
            {
                self.debug_frame = Some([0, 1].map(|_| {
                    crate::renderer::texture_2d(
                        &ctx.gpu.device,
                        "shadow map debug frame",
                        w,
                        h,
                        1,
                        wgpu::TextureFormat::Rgba8Unorm,
                        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    )
                }));
            }
            let views = self
                .debug_frame
                .as_ref()
                .expect("made above")
                .each_ref()
                .map(|t| t.create_view(&Default::default()));
            let attachments = views.each_ref().map(|v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear_op(wgpu::Color::BLACK),
                })
            });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map debug frame"),
                color_attachments: &attachments,
                ..Default::default()
            });
            pass.set_pipeline(&self.debug_frame_pipeline);
            pass.set_bind_group(0, &ctx.frame.frame_bind_group, &[]);
            pass.set_bind_group(1, &ctx.scene_gpu.object_bind_group, &[]);
            pass.set_bind_group(2, &lookup_group, &[slot(lights.len() - 1, 0, 0)]);
            pass.draw(0..3, 0..1);
        }
        self.samples = lights.len();
        self.last_faces = setups.iter().flat_map(|s| s.faces.clone()).collect();
        self.last_paraboloid = frustum_params.paraboloid && ctx.light.kind == LightType::Point;
        Ok(())
    }

    fn enable_debug(&mut self, on: bool) {
        self.debug = None;
        self.debug_frame = None;
        self.want_debug = on;
    }

    fn debug_views(&self, gpu: &crate::gpu::GpuContext) -> Result<super::DebugViews> {
        let mut views = super::DebugViews::default();
        if !self.last_paraboloid {
            for m in &self.last_faces {
                views
                    .lines
                    .extend(super::frustum_lines(*m, [1.0, 0.85, 0.2, 1.0]));
            }
        }
        if let Some(t) = &self.debug {
            views.images.push(super::DebugImage {
                label: "shadow map (face 0, linear depth)".into(),
                width: t.width(),
                height: t.height(),
                rgba: gpu.read_texture(t, 0, 4)?,
            });
        }
        if let Some([projection, texels]) = &self.debug_frame {
            for (t, label) in [
                (
                    projection,
                    "map projected onto the scene (red: outside the map)",
                ),
                (
                    texels,
                    "shadow-map texels per pixel (blue < 1/4: aliasing, green 1, red > 4)",
                ),
            ] {
                views.images.push(super::DebugImage {
                    label: label.into(),
                    width: t.width(),
                    height: t.height(),
                    rgba: gpu.read_texture(t, 0, 4)?,
                });
            }
        }
        Ok(views)
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        self.maps
            .as_ref()
            .map(|m| {
                vec![
                    ("map_size", m.size as f64),
                    ("faces", m.layers as f64),
                    ("maps_per_face", self.samples as f64),
                ]
            })
            .unwrap_or_default()
    }

    fn resource_bytes(&self) -> u64 {
        self.maps.as_ref().map_or(0, |m| m.bytes)
    }
}
