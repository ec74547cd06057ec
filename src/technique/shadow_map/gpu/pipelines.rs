//! The shadow-map family's GPU programs, shared by every light's instance
//! on a device: one shader module, its layouts, samplers and placeholders
//! ([`ShadowMapShared`]), and the lookup's pipelines, specialised by
//! filter, taps, depth format, receiver-plane bias and map shape and taken
//! from the device's bounded cache. The depth pass's are in
//! [`crate::technique::shadow_map::gpu::depth_pass`].

use super::binding as B;
use super::{LOOKUP_FORMAT, MOMENT_FORMAT, PART_FORMAT, placeholder};
use crate::frame::MASK_FORMAT;
use crate::gpu::GpuContext;
use crate::technique::params::Choice;
use crate::technique::shadow_map::config::Filter;
use crate::technique::shadow_map::projection::setup::LightSetup;
pub use crate::technique::shadow_map::projection::setup::MapProjection;

/// The shape of a light's maps, a constant of every pipeline that reads
/// them: SIMD rasterisers such as llvmpipe run both sides of a branch on a
/// uniform value under a lane mask, so a lookup that branched on the shape
/// paid for the cascade path, the cube-face choice and the warp on every
/// one-map pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MapShape {
    pub projection: MapProjection,
    /// Faces are cascades, chosen per pixel by view depth.
    pub cascaded: bool,
    /// Faces are warped (PSM, LiSPSM, TSM): depth stored linear along the light.
    pub warped: bool,
}

impl MapShape {
    /// The shape of the maps `setup` describes.
    pub fn of(setup: &LightSetup) -> MapShape {
        MapShape {
            projection: setup.projection,
            cascaded: setup.cascades.is_some(),
            warped: setup.warp_depth.is_some(),
        }
    }

    /// The values of the shape's pipeline-overridable constants.
    pub(in crate::technique::shadow_map) fn constants(self) -> [(&'static str, f64); 3] {
        [
            ("PROJECTION", self.projection.index() as f64),
            ("CASCADED", self.cascaded as u32 as f64),
            ("WARPED", self.warped as u32 as f64),
        ]
    }
}

/// What a lookup pipeline depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LookupKey {
    pub filter: Filter,
    /// Taps per side; 0 for filters without taps.
    pub taps: u32,
    pub byte_map: bool,
    pub receiver_plane: bool,
    /// Adds `constant × visibility` onto the mask (area-light maps).
    pub accumulate: bool,
    /// The kernel only where the edge mask's bounds chain finds a shadow edge.
    pub edge_mask: bool,
    /// Texels read through a virtual map's page table.
    pub virtual_map: bool,
    /// Every page a virtual map's pixels marked this frame is resident: the
    /// lookup filters each pixel's own level without checking.
    pub marked_resident: bool,
    /// A virtual map's kernel can read more than 2×2 pages (its marked
    /// reach spans a page): taps beyond them read the page table.
    pub wide_kernel: bool,
    /// The maps store convex part IDs (`part_ids`).
    pub parts: bool,
    /// Translucent casters' transmittance maps (`blended_casters=transmit`).
    pub transmit: bool,
    pub shape: MapShape,
}

impl LookupKey {
    /// The values of the lookup's pipeline-overridable constants.
    fn constants(&self) -> Vec<(&'static str, f64)> {
        let mut constants = vec![
            ("FILTER_KIND", self.filter.index() as f64),
            ("TAPS", self.taps as f64),
            ("BYTE_MAP", self.byte_map as u32 as f64),
            ("RECEIVER_PLANE", self.receiver_plane as u32 as f64),
            ("EDGE_MASK", self.edge_mask as u32 as f64),
            ("VIRTUAL", self.virtual_map as u32 as f64),
            ("MARKED_RESIDENT", self.marked_resident as u32 as f64),
            ("WIDE_KERNEL", self.wide_kernel as u32 as f64),
            ("PART_IDS", self.parts as u32 as f64),
            ("TRANSMIT", self.transmit as u32 as f64),
        ];
        constants.extend(self.shape.constants());
        constants
    }
}

pub struct ShadowMapShared {
    pub layout: wgpu::BindGroupLayout,
    pub(in crate::technique::shadow_map) pipeline_layout: wgpu::PipelineLayout,
    pub(in crate::technique::shadow_map) module: wgpu::ShaderModule,
    pub compare_sampler: wgpu::Sampler,
    pub placeholder_bytes: wgpu::TextureView,
    /// Bound in place of the maps while they are rendered.
    pub placeholder_depth: wgpu::TextureView,
    pub placeholder_moments: wgpu::TextureView,
    pub placeholder_bounds: wgpu::TextureView,
    pub placeholder_parts: wgpu::TextureView,
    /// Nearest-texel sampler of the part maps (`textureGather`).
    pub part_sampler: wgpu::Sampler,
    /// Bound in place of a virtual map's buffers (bindings 8 to 11).
    pub placeholder_virtual: [wgpu::Buffer; 4],
}

impl ShadowMapShared {
    pub fn new(gpu: &GpuContext) -> ShadowMapShared {
        let device = &gpu.device;
        let tex = |binding, sample_type| {
            crate::gpu::sampled_texture_entry(
                binding,
                wgpu::ShaderStages::FRAGMENT,
                sample_type,
                wgpu::TextureViewDimension::D2Array,
            )
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow map"),
            entries: &[
                crate::gpu::uniform_entry(
                    gpu,
                    B::UNIFORM,
                    wgpu::ShaderStages::VERTEX_FRAGMENT,
                    true,
                ),
                tex(B::DEPTH_MAP, wgpu::TextureSampleType::Depth),
                wgpu::BindGroupLayoutEntry {
                    binding: B::COMPARE_SAMPLER,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                tex(
                    B::BYTE_MAP,
                    wgpu::TextureSampleType::Float { filterable: false },
                ),
                tex(
                    B::MOMENT_MAP,
                    wgpu::TextureSampleType::Float { filterable: false },
                ),
                tex(
                    B::EDGE_BOUNDS,
                    wgpu::TextureSampleType::Float { filterable: false },
                ),
                crate::gpu::storage_entry(B::VIRTUAL[0], wgpu::ShaderStages::FRAGMENT, false),
                crate::gpu::storage_entry(B::VIRTUAL[1], wgpu::ShaderStages::FRAGMENT, true),
                crate::gpu::storage_entry(B::VIRTUAL[2], wgpu::ShaderStages::FRAGMENT, true),
                crate::gpu::storage_entry(B::VIRTUAL[3], wgpu::ShaderStages::FRAGMENT, false),
                tex(B::PART_MAP, wgpu::TextureSampleType::Uint),
                wgpu::BindGroupLayoutEntry {
                    binding: B::PART_SAMPLER,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                    count: None,
                },
                tex(B::EDGE_PARTS, wgpu::TextureSampleType::Uint),
                tex(B::TRANSMIT_DEPTH, wgpu::TextureSampleType::Depth),
                tex(
                    B::TRANSMITTANCE,
                    wgpu::TextureSampleType::Float { filterable: false },
                ),
            ],
        });
        let module = crate::frame::technique_shader(gpu, "shadow map", &[&module_source()]);
        ShadowMapShared {
            pipeline_layout: crate::technique::pipeline_layout(gpu, "shadow map", &layout),
            layout,
            module,
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
            placeholder_bounds: placeholder(device, wgpu::TextureFormat::Rgba32Float),
            placeholder_parts: placeholder(device, PART_FORMAT),
            part_sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow map parts"),
                ..Default::default()
            }),
            placeholder_virtual: std::array::from_fn(|_| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("virtual map placeholder"),
                    size: 256,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                })
            }),
        }
    }

    /// A full-screen pass of the module with the filter constants of `key`.
    pub(super) fn fullscreen(
        &self,
        gpu: &GpuContext,
        label: &'static str,
        fs: &'static str,
        key: LookupKey,
        targets: &[Option<wgpu::ColorTargetState>],
        depth_stencil: Option<wgpu::DepthStencilState>,
    ) -> wgpu::RenderPipeline {
        gpu.cache
            .render_pipeline(label, &(key, targets, &depth_stencil), || {
                let constants = key.constants();
                let options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                gpu.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(label),
                        layout: Some(&self.pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some("vs_fullscreen"),
                            compilation_options: options.clone(),
                            buffers: &[],
                        },
                        primitive: Default::default(),
                        depth_stencil: depth_stencil.clone(),
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &self.module,
                            entry_point: Some(fs),
                            compilation_options: options,
                            targets,
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
            })
    }

    /// The lookup writing (or accumulating into) the mask.
    pub fn lookup(&self, gpu: &GpuContext, key: LookupKey) -> wgpu::RenderPipeline {
        let target = if key.accumulate {
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
            }
        } else {
            MASK_FORMAT.into()
        };
        self.fullscreen(
            gpu,
            "shadow map lookup",
            "fs_lookup",
            key,
            &[Some(target)],
            Some(crate::technique::frame_depth_read(gpu, Default::default())),
        )
    }

    /// A paged map's marking pass: each pixel's level and the pages its
    /// kernel needs — all of them (virtual) or a refinement at shadow edges
    /// (adaptive); storage writes, the mask is not written.
    pub fn virtual_mark(
        &self,
        gpu: &GpuContext,
        key: LookupKey,
        adaptive: bool,
    ) -> wgpu::RenderPipeline {
        let (label, entry) = if adaptive {
            ("adaptive shadow map marking", "fs_adaptive_mark")
        } else {
            ("virtual shadow map marking", "fs_virtual_mark")
        };
        self.fullscreen(
            gpu,
            label,
            entry,
            key,
            &[Some(wgpu::ColorTargetState {
                format: MASK_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            })],
            Some(crate::technique::frame_depth_read(gpu, Default::default())),
        )
    }

    /// Clears one page of a virtual map's pool to the far plane.
    pub fn clear_page(&self, gpu: &GpuContext, key: LookupKey) -> wgpu::RenderPipeline {
        self.fullscreen(
            gpu,
            "virtual shadow map page clear",
            "fs_clear_page",
            key,
            &[],
            Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
        )
    }

    /// The separable box blur of moment maps.
    pub fn blur(&self, gpu: &GpuContext, key: LookupKey) -> wgpu::RenderPipeline {
        self.fullscreen(
            gpu,
            "shadow map blur",
            "fs_blur",
            key,
            &[Some(MOMENT_FORMAT.into())],
            None,
        )
    }

    /// Debug view: face 0 of the map as grey.
    pub fn debug_map(&self, gpu: &GpuContext, key: LookupKey) -> wgpu::RenderPipeline {
        self.fullscreen(
            gpu,
            "shadow map debug",
            "fs_debug_map",
            key,
            &[Some(wgpu::TextureFormat::Rgba8Unorm.into())],
            None,
        )
    }

    /// Debug views at the frame's size: the projected map, texels per pixel.
    pub fn debug_frame(&self, gpu: &GpuContext, key: LookupKey) -> wgpu::RenderPipeline {
        self.fullscreen(
            gpu,
            "shadow map debug frame",
            "fs_debug_frame",
            key,
            &[
                Some(wgpu::TextureFormat::Rgba8Unorm.into()),
                Some(wgpu::TextureFormat::Rgba8Unorm.into()),
                Some(LOOKUP_FORMAT.into()),
            ],
            None,
        )
    }
}

/// The family's WGSL after the frame's shared declarations: its choices'
/// constants, then the uniform and bindings, the depth passes, the filters,
/// the lookup, the virtual map's passes and the debug views.
pub(in crate::technique::shadow_map) fn module_source() -> String {
    let constants = Filter::wgsl_constants("FILTER")
        + &MapProjection::wgsl_constants("PROJECTION")
        + &super::edge_mask::wgsl_constants();
    [
        &constants,
        include_str!("shadow_map.wgsl"),
        include_str!("depth_pass.wgsl"),
        include_str!("transmittance.wgsl"),
        include_str!("filters.wgsl"),
        include_str!("lookup.wgsl"),
        include_str!("virtual_map.wgsl"),
        include_str!("debug.wgsl"),
    ]
    .join("\n")
}
