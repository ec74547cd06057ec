//! `shadow-map`: shadow maps (Williams 1978; [000] §4, [001] §3,
//! [002] §2). Depth from the light — perspective for spot lights, six 90°
//! faces for point lights, orthographic for directional lights fitted to the
//! scene and clipped to what the camera sees — then a screen-space lookup
//! that moves each G-buffer point along its normal (normal offset), projects
//! it with the light's matrices (wgpu: NDC z in [0,1], texture v down, see
//! `light_space::bias_matrix`), compares depths (`z ≤ stored` is lit,
//! outside the map is lit) and filters: nearest, hardware 2×2 PCF, N×N grid,
//! rotated Vogel disk, PCSS, or the documents' variable-width PCF.

pub mod config;
mod gpu;
mod passes;
pub mod projection;
mod virtual_map;

pub use config::{
    Cascades, CullFace, DepthFormat, Filter, Fit, Omni, Roll, Select, ShadowMapConfig, Stage, Warp,
};
pub use projection::FrustumParams;
pub use projection::setup::{CascadeSplit, LightSetup, cube_views, light_setup};

use crate::gpu::{GpuContext, SectionTimer};
use crate::scene::AlphaMode;
use crate::technique::params::BlendedCasters;
use crate::technique::{Family, MaskContext, ParamValues, ShadowTechnique};
use anyhow::Result;
use glam::{Mat4, Vec2};
use gpu::binding as B;
use gpu::edge_mask::BoundsChain;
use gpu::maps::{MapContents, Maps};
use gpu::pipelines::{MapProjection, MapShape, ShadowMapShared};
use gpu::uniform::{FrameTerms, SLOTS, STRIDE, ShadowMapUniform, slot_data, slot_offset};
use projection::depth_bounds::{DepthReduction, SeenBounds};
use std::sync::Arc;

pub static FAMILY: Family = Family {
    id: "shadow-map",
    summary: "shadow maps: depth from the light, compared per pixel, with the PCF family of filters",
    capabilities: crate::technique::Capabilities {
        point_lights: true,
        spot_lights: true,
        directional_lights: true,
        soft_shadows: true,
        self_shadowing: true,
        open_meshes: true,
        curved_receivers: true,
        cutout_casters: true,
    },
    params: config::PARAMS,
    presets: config::presets::PRESETS,
    create: |gpu, params| {
        Ok(Box::new(ShadowMapTechnique::new(
            gpu,
            ShadowMapConfig::parse(params)?,
        )))
    },
};

/// What a shadow-map bind group binds: the uniforms, the depth, 8-bit,
/// moment, edge-bounds and part arrays and a virtual map's buffers;
/// [`MapBindings::empty`] binds placeholders for all but the uniforms.
struct MapBindings<'a> {
    uniforms: &'a wgpu::Buffer,
    depth: &'a wgpu::TextureView,
    bytes: &'a wgpu::TextureView,
    moments: &'a wgpu::TextureView,
    bounds: &'a wgpu::TextureView,
    bound_parts: &'a wgpu::TextureView,
    parts: &'a wgpu::TextureView,
    transmit_depth: &'a wgpu::TextureView,
    transmittance: &'a wgpu::TextureView,
    virtual_buffers: [&'a wgpu::Buffer; 4],
}

impl<'a> MapBindings<'a> {
    fn empty(shared: &'a ShadowMapShared, uniforms: &'a wgpu::Buffer) -> MapBindings<'a> {
        MapBindings {
            uniforms,
            depth: &shared.placeholder_depth,
            bytes: &shared.placeholder_bytes,
            moments: &shared.placeholder_moments,
            bounds: &shared.placeholder_bounds,
            bound_parts: &shared.placeholder_parts,
            parts: &shared.placeholder_parts,
            transmit_depth: &shared.placeholder_depth,
            transmittance: &shared.placeholder_bytes,
            virtual_buffers: shared.placeholder_virtual.each_ref(),
        }
    }
}

/// A light's maps across frames.
enum MapState {
    /// Nothing rendered yet.
    Empty,
    /// Maps that are not paged.
    Dense(Box<DenseMaps>),
    /// `paging=virtual|adaptive`: the pool, page table and cache.
    Virtual(Box<virtual_map::VirtualState>),
}

/// A light's maps that are not paged, with the edge mask's bounds chain
/// when `edge_mask=true`.
struct DenseMaps {
    maps: Maps,
    chain: Option<BoundsChain>,
}

pub struct ShadowMapTechnique {
    shared: Arc<ShadowMapShared>,
    config: ShadowMapConfig,
    uniforms: wgpu::Buffer,
    /// The maps kept across frames: dense or virtual, never both.
    state: MapState,
    /// Shadow maps rendered per face last frame (area lights: several).
    samples: usize,
    /// Debug views: a 256² picture of face 0 and the last light matrices.
    debug: Option<wgpu::Texture>,
    /// Frame-sized debug views: the map projected onto the scene, texels per pixel.
    debug_frame: Option<[wgpu::Texture; 3]>,
    last_faces: Vec<Mat4>,
    /// Per light sample: the half-extents of last frame's stabilised
    /// single map's window (kept while they fit; `stable_window::Hold`).
    stable_halves: Vec<Vec2>,
    /// A directional light's single map's turn last frame (`roll`).
    turn: Option<usize>,
    last_paraboloid: bool,
    want_debug: bool,
    /// Triangles drawn into the maps last frame (after culling per face).
    map_triangles: u64,
    /// SDSM's reduction (`fit=depth|samples`), made on first use.
    depth_reduction: Option<DepthReduction>,
    /// What the cascades were fitted to last frame with SDSM.
    last_seen: Option<SeenBounds>,
    /// Counter `lookup_ms`: GPU time of the screen-space lookup of each
    /// map sample, with the edge mask's bounds chain (part of the
    /// lookup's cost), not the depth passes — the time the edge mask and the
    /// virtual page table are meant to save.
    lookup_timer: SectionTimer,
    /// Counter `edge_chain_ms`: the part of `lookup_ms` that builds the
    /// edge mask's bounding chain (it reads every texel of the maps).
    chain_timer: SectionTimer,
}

impl ShadowMapTechnique {
    pub fn new(gpu: &GpuContext, config: ShadowMapConfig) -> ShadowMapTechnique {
        ShadowMapTechnique {
            shared: gpu.cache.shared(|| ShadowMapShared::new(gpu)),
            config,
            uniforms: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow map uniforms"),
                size: STRIDE * SLOTS,
                usage: crate::gpu::uniform_usage(gpu),
                mapped_at_creation: false,
            }),
            state: MapState::Empty,
            samples: 0,
            debug: None,
            debug_frame: None,
            last_faces: vec![],
            stable_halves: vec![],
            turn: None,
            last_paraboloid: false,
            want_debug: false,
            map_triangles: 0,
            depth_reduction: None,
            last_seen: None,
            lookup_timer: SectionTimer::new("shadow map lookup timestamps"),
            chain_timer: SectionTimer::new("edge mask chain timestamps"),
        }
    }

    /// Keeps the maps when their size, layers and contents match;
    /// otherwise frees them and allocates new ones.
    fn ensure_maps(
        &mut self,
        gpu: &GpuContext,
        size: u32,
        layers: u32,
        contents: MapContents,
    ) -> Result<()> {
        if self
            .maps()
            .is_some_and(|m| m.matches(size, layers, contents))
        {
            return Ok(());
        }
        // Free the old maps first (the chain stays: it checks its own
        // size); keep the new ones only once created.
        let chain = match std::mem::replace(&mut self.state, MapState::Empty) {
            MapState::Dense(dense) => dense.chain,
            _ => None,
        };
        let maps = Maps::allocate(gpu, size, layers, contents)?;
        self.state = MapState::Dense(Box::new(DenseMaps { maps, chain }));
        Ok(())
    }

    /// The dense maps, when the last frame rendered them.
    fn maps(&self) -> Option<&Maps> {
        match &self.state {
            MapState::Dense(dense) => Some(&dense.maps),
            _ => None,
        }
    }

    /// The dense maps' edge-mask bounds chain, when there is one.
    fn chain(&self) -> Option<&BoundsChain> {
        match &self.state {
            MapState::Dense(dense) => dense.chain.as_ref(),
            _ => None,
        }
    }

    /// The virtual map's state, when the last frame was paged.
    fn virtual_state(&self) -> Option<&virtual_map::VirtualState> {
        match &self.state {
            MapState::Virtual(v) => Some(v),
            _ => None,
        }
    }

    /// The technique's bind group of `b`.
    /// Starts the lookup's and the edge chain's GPU timers for `samples`
    /// maps (cleared where the frame has no lookup or no chain).
    fn begin_lookup_timers(
        &mut self,
        gpu: &GpuContext,
        samples: u32,
    ) -> (Option<crate::gpu::Stamps>, Option<crate::gpu::Stamps>) {
        let stamps = match self.config.stage {
            Stage::Full => self.lookup_timer.begin(gpu, samples),
            // No lookup: no time, not an earlier stage's.
            _ => {
                self.lookup_timer.clear();
                None
            }
        };
        let chain_stamps = match self.chain() {
            Some(_) => self.chain_timer.begin(gpu, samples),
            None => {
                self.chain_timer.clear();
                None
            }
        };
        (stamps, chain_stamps)
    }

    /// The lookup's bind group: every map of this frame, placeholders for
    /// those not in use.
    fn lookup_group(&self, ctx: &MaskContext, maps: &Maps) -> wgpu::BindGroup {
        let shared = &self.shared;
        self.bind_group(
            ctx,
            MapBindings {
                depth: &maps.depth_array,
                bytes: maps
                    .byte
                    .as_ref()
                    .map_or(&shared.placeholder_bytes, |b| &b.1),
                moments: maps
                    .moment
                    .as_ref()
                    .map_or(&shared.placeholder_moments, |m| &m[0].1),
                bounds: self.chain().map_or(&shared.placeholder_bounds, |c| &c.view),
                bound_parts: self
                    .chain()
                    .map_or(&shared.placeholder_parts, |c| &c.part_view),
                parts: maps
                    .part
                    .as_ref()
                    .map_or(&shared.placeholder_parts, |p| &p.1),
                transmit_depth: maps
                    .transmit
                    .as_ref()
                    .map_or(&shared.placeholder_depth, |t| &t.depth.1),
                transmittance: maps
                    .transmit
                    .as_ref()
                    .map_or(&shared.placeholder_bytes, |t| &t.transmittance.1),
                ..MapBindings::empty(shared, &self.uniforms)
            },
        )
    }

    fn bind_group(&self, ctx: &MaskContext, b: MapBindings) -> wgpu::BindGroup {
        let view = |binding, v| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(v),
        };
        fn buffer(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }
        ctx.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadow map"),
                layout: &self.shared.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: B::UNIFORM,
                        resource: crate::gpu::dynamic_uniform::<ShadowMapUniform>(b.uniforms),
                    },
                    view(B::DEPTH_MAP, b.depth),
                    wgpu::BindGroupEntry {
                        binding: B::COMPARE_SAMPLER,
                        resource: wgpu::BindingResource::Sampler(&self.shared.compare_sampler),
                    },
                    view(B::BYTE_MAP, b.bytes),
                    view(B::MOMENT_MAP, b.moments),
                    view(B::EDGE_BOUNDS, b.bounds),
                    buffer(B::VIRTUAL[0], b.virtual_buffers[0]),
                    buffer(B::VIRTUAL[1], b.virtual_buffers[1]),
                    buffer(B::VIRTUAL[2], b.virtual_buffers[2]),
                    buffer(B::VIRTUAL[3], b.virtual_buffers[3]),
                    view(B::PART_MAP, b.parts),
                    wgpu::BindGroupEntry {
                        binding: B::PART_SAMPLER,
                        resource: wgpu::BindingResource::Sampler(&self.shared.part_sampler),
                    },
                    view(B::EDGE_PARTS, b.bound_parts),
                    view(B::TRANSMIT_DEPTH, b.transmit_depth),
                    view(B::TRANSMITTANCE, b.transmittance),
                ],
            })
    }
}

/// What the maps of a frame under `c` hold besides depth.
fn map_contents(c: &ShadowMapConfig, ctx: &MaskContext, parts: bool) -> MapContents {
    MapContents {
        format: c.format,
        moments: c.filter.is_moment(),
        parts,
        transmit: transmits(c, ctx),
    }
}

/// Whether the maps of a frame under `c` keep transmittance maps: with
/// `blended_casters=transmit`, where some caster is translucent and the
/// maps are looked up.
fn transmits(c: &ShadowMapConfig, ctx: &MaskContext) -> bool {
    let translucent = ctx
        .scene_gpu
        .draws
        .iter()
        .any(|d| d.casts_shadow && d.alpha_mode == AlphaMode::Blend);
    c.caster_alpha.blended == BlendedCasters::Transmit && c.stage != Stage::Floor && translucent
}

fn clear_op(color: wgpu::Color) -> wgpu::Operations<wgpu::Color> {
    wgpu::Operations {
        load: wgpu::LoadOp::Clear(color),
        store: wgpu::StoreOp::Store,
    }
}

impl ShadowTechnique for ShadowMapTechnique {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.config = ShadowMapConfig::parse(params)?;
        Ok(())
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        if self.config.paging.is_paged() {
            return self.render_virtual(ctx, encoder);
        }
        let gpu = ctx.gpu;
        let c = self.config.for_light(ctx.light, gpu.max_texture_size());
        let aspect = ctx.frame.width() as f32 / ctx.frame.height() as f32;
        let (size, format) = (c.size, c.format);
        let blur = c.moment_blur();
        let normal_offset = c.normal_offset(ctx.light.kind);
        let (lights, area_radius) = projection::light_samples(&c, ctx);
        let setups = self.light_setups(ctx, encoder, &lights, aspect)?;
        let layers = setups[0].faces.len() as u32;
        // Every sample of an area light has the first one's shape.
        let shape = MapShape::of(&setups[0]);
        let cull = c.cull.for_shape(shape);
        let contents = map_contents(&c, ctx, c.uses_part_ids(cull));
        let (parts, transmit) = (contents.parts, contents.transmit);
        self.ensure_maps(ctx.gpu, size, layers, contents)?;
        let edge_mask = c.edge_masked() && c.stage == Stage::Full;
        if let MapState::Dense(dense) = &mut self.state {
            if edge_mask {
                BoundsChain::ensure(&mut dense.chain, ctx.gpu, size, layers)?;
            } else {
                dense.chain = None;
            }
        }
        let frame = FrameTerms {
            size,
            format,
            area_radius,
            normal_offset,
            cull,
            blur,
            fit_view: ctx.fit_camera.view(),
        };
        let data = slot_data(&c, &lights, &setups, &frame);
        crate::gpu::grow_buffer(
            &ctx.gpu.device,
            &mut self.uniforms,
            data.len() as u64,
            "shadow map uniforms",
        );
        ctx.gpu.queue.write_buffer(&self.uniforms, 0, &data);
        let floor = c.stage == Stage::Floor;
        let (depth_key, lookup_key) =
            passes::dense_keys(&c, cull, shape, parts, edge_mask, transmit);
        let (stamps, chain_stamps) = self.begin_lookup_timers(gpu, lights.len() as u32);
        let maps = self.maps().expect("ensured above");
        // Bind groups: none of the maps while they are rendered; the moment
        // maps as blur sources; everything for the lookup.
        let shared = &self.shared;
        let render_group = self.bind_group(ctx, MapBindings::empty(shared, &self.uniforms));
        let blur_groups = maps.moment.as_ref().map(|m| {
            [0, 1].map(|src| {
                self.bind_group(
                    ctx,
                    MapBindings {
                        moments: &m[src].1,
                        ..MapBindings::empty(shared, &self.uniforms)
                    },
                )
            })
        });
        let lookup_group = self.lookup_group(ctx, maps);
        let passes = passes::SamplePasses {
            maps,
            render_group,
            blur_groups,
            lookup_group: &lookup_group,
            lookup_key,
            depth_key,
            layers,
            blur,
            floor,
            samples: lights.len(),
            aspect,
        };
        let mut map_triangles = 0;
        for (si, (setup, light)) in setups.iter().zip(&lights).enumerate() {
            map_triangles += self.record_maps(ctx, encoder, &passes, si, setup, light);
            if c.stage == Stage::Full {
                self.record_lookup(
                    ctx,
                    encoder,
                    &passes,
                    si,
                    stamps.as_ref(),
                    chain_stamps.as_ref(),
                );
            }
        }
        if stamps.is_some() {
            self.lookup_timer.resolve(encoder);
        }
        if chain_stamps.is_some() {
            self.chain_timer.resolve(encoder);
        }
        if c.stage != Stage::Full {
            // The maps alone: no lookup, a lit mask.
            crate::frame::clear_mask(ctx.gpu, encoder, ctx.target, 1.0);
        }
        self.render_debug(
            ctx,
            encoder,
            &lookup_group,
            lookup_key,
            slot_offset(lights.len() - 1, 0, 0) as u32,
        );
        self.samples = lights.len();
        self.map_triangles = map_triangles;
        self.last_faces = setups.iter().flat_map(|s| s.faces.clone()).collect();
        self.last_paraboloid = shape.projection == MapProjection::Paraboloid;
        Ok(())
    }

    fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        if let Some(r) = &mut self.depth_reduction {
            r.after_frame(gpu)?;
        }
        if let MapState::Virtual(v) = &mut self.state {
            v.after_frame(gpu)?;
        }
        self.chain_timer.after_frame(gpu)?;
        self.lookup_timer.after_frame(gpu)
    }

    fn enable_debug(&mut self, on: bool) {
        self.debug = None;
        self.debug_frame = None;
        self.want_debug = on;
    }

    fn debug_views(&self, gpu: &GpuContext) -> Result<crate::technique::DebugViews> {
        self.read_debug_views(gpu)
    }

    fn map_lookup(&self, gpu: &GpuContext) -> Result<Option<crate::technique::MapLookup>> {
        self.read_map_lookup(gpu)
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        if let Some(v) = self.virtual_state() {
            let p = v.counters;
            return vec![
                ("pages_needed", p.needed as f64),
                ("pages_rendered", p.rendered as f64),
                ("pages_cached", p.cached as f64),
                ("pages_degraded", p.degraded as f64),
                ("pages_dropped", p.dropped as f64),
                ("pages_resident", p.resident as f64),
                ("pool_pages", p.capacity as f64),
                (
                    "pool_occupancy",
                    p.resident as f64 / p.capacity.max(1) as f64,
                ),
                ("virtual_levels", p.levels as f64),
                ("refine_passes", p.refine_passes as f64),
                ("page_feedback_ms", p.feedback_ms),
                ("page_marking_ms", v.marking_ms()),
                ("lookup_ms", self.lookup_timer.last_ms()),
                ("map_triangles", self.map_triangles as f64),
            ];
        }
        self.maps()
            .map(|m| {
                vec![
                    ("map_size", m.size as f64),
                    ("faces", m.layers as f64),
                    ("maps_per_face", self.samples as f64),
                    ("map_triangles", self.map_triangles as f64),
                    ("lookup_ms", self.lookup_timer.last_ms()),
                ]
                .into_iter()
                .chain(
                    self.chain()
                        .map(|_| ("edge_chain_ms", self.chain_timer.last_ms())),
                )
                .chain(self.turn.map(|t| {
                    (
                        "map_turn_deg",
                        projection::roll::turn_angle(t).to_degrees() as f64,
                    )
                }))
                .chain(self.last_seen.as_ref().map_or(vec![], |s| {
                    vec![
                        ("sdsm_near", s.near as f64),
                        ("sdsm_far", s.far as f64),
                        (
                            "sdsm_reduction_ms",
                            self.depth_reduction
                                .as_ref()
                                .map_or(0.0, |r| r.timer.last_ms()),
                        ),
                        (
                            "sdsm_wait_ms",
                            self.depth_reduction.as_ref().map_or(0.0, |r| r.wait_ms),
                        ),
                    ]
                }))
                .collect()
            })
            .unwrap_or_default()
    }

    fn resource_bytes(&self) -> u64 {
        match &self.state {
            MapState::Empty => 0,
            MapState::Dense(dense) => {
                dense.maps.bytes + dense.chain.as_ref().map_or(0, |c| c.bytes)
            }
            MapState::Virtual(v) => v.resource_bytes(),
        }
    }
}
