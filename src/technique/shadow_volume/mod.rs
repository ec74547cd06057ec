//! `shadow-volume`: stencil shadow volumes (Crow 1977; Heidmann 1991;
//! Everitt & Kilgard 2002; [000] §3, [001] §4). Each caster's
//! silhouette edges, found with the light in object space (`P·L > 0` is a
//! lit face), are extruded away from the light — to infinity as w = 0
//! vertices, or by a finite length — and capped with the lit faces (light
//! cap) and their extrusion (dark cap). The volumes are counted in the
//! frame's stencil buffer against the prepass depth: z-pass (front faces +1,
//! back faces −1 where the depth test passes; wrong when the camera is in a
//! shadow), z-fail (Carmack's reverse: back +1, front −1 where it fails;
//! needs caps and a far plane at infinity or depth clamp) or `auto` (z-fail
//! only for casters whose volume can contain part of the near-plane
//! rectangle, or that the camera can see through: cut-outs and translucent
//! casters). Meshes that are not closed can extrude every triangle's own
//! volume instead (`silhouette=triangles`). Where the count is not 0 the mask
//! is 1 − darkening.
//!
//! Geometry: [`adjacency`] welds and builds the edge table once per scene;
//! [`silhouette`] decides per caster and extrudes on the CPU; the compute
//! shader in `extrude.wgsl` writes the same index lists on the GPU, drawn
//! with draw-indexed-indirect (`extrusion` uploads and runs either);
//! `scissor` bounds a ranged light's stencil work on screen.

pub mod adjacency;
pub mod config;
mod debug;
mod extrusion;
mod pipelines;
mod scissor;
pub mod silhouette;

use scissor::range_scissor;

use super::{DebugLine, Family, MaskContext, ParamValues, ShadowTechnique};
use crate::frame::Compose;
use crate::gpu::GpuContext;
use crate::scene::{AlphaMode, LightType};
use adjacency::Adjacency;
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use config::{Extrusion, FarPlane, Method, SilhouetteMode, StencilMode, VolumeConfig};
use extrusion::Geometry;
use glam::Vec4;
use pipelines::{VolumeKey, VolumeShared};
use silhouette::{CasterPlan, VolumeKind};
use std::sync::Arc;

pub static FAMILY: Family = Family {
    id: "shadow-volume",
    summary: "stencil shadow volumes: silhouettes extruded away from the light, counted in the stencil buffer (exact hard shadows; cut-out and translucent casters shadow as solids: a volume is extruded from whole triangles and has no holes)",
    capabilities: super::Capabilities {
        point_lights: true,
        spot_lights: true,
        directional_lights: true,
        soft_shadows: false,
        self_shadowing: true,
        open_meshes: true,
        curved_receivers: true,
        cutout_casters: false,
    },
    params: config::PARAMS,
    presets: config::PRESETS,
    create: |gpu, params| {
        Ok(Box::new(ShadowVolumeRenderer::new(
            gpu,
            VolumeConfig::parse(params)?,
        )))
    },
};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct VolumeUniform {
    light: Vec4,
    extrusion: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ExtrudeParams {
    edge_count: u32,
    face_count: u32,
    dark_cap: u32,
    _pad: u32,
}

/// `draw_indexed_indirect` arguments.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Default)]
struct IndirectArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

/// The indirect arguments of the z-pass and z-fail lists and the
/// silhouette counter (`Args` in extrude.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Default)]
struct Args {
    lists: [IndirectArgs; 2],
    silhouette_edges: u32,
}

/// Offset of the z-fail list's arguments.
const ZFAIL_ARGS: u64 = std::mem::size_of::<IndirectArgs>() as u64;

const ARGS_SIZE: u64 = std::mem::size_of::<Args>() as u64;
/// Readback layout: the arguments, then the pipeline-statistics result.
const STATS_OFFSET: u64 = 48;

/// Statistics of the last frame.
#[derive(Clone, Copy, Debug, Default)]
struct Stats {
    silhouette_edges: u32,
    volume_triangles: u32,
    /// Fragment-shader invocations of the volume draws. A GPU driver may
    /// skip their empty, write-nothing fragment stage (NVIDIA's does, and
    /// reads 0 whatever the volumes cover): a GPU's 0 is left out, not
    /// reported; a CPU rasteriser (lavapipe) runs every one.
    fragments: Option<u64>,
    skipped: usize,
    zpass: usize,
    zfail: usize,
    per_triangle: usize,
    /// The volumes were drawn with unclipped depth (`far_plane=depth-clamp`
    /// on an adapter that has it), not with the infinite far plane.
    depth_clamped: bool,
}

pub struct ShadowVolumeRenderer {
    shared: Arc<VolumeShared>,
    config: VolumeConfig,
    uniform: wgpu::Buffer,
    extrude_params: wgpu::Buffer,
    indices: wgpu::Buffer,
    args: wgpu::Buffer,
    /// The indirect arguments and statistics of a frame, read back without
    /// waiting ([`ShadowTechnique::after_frame`]).
    readback: crate::gpu::AsyncReadback,
    statistics: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    depth_clamp: bool,
    warned_no_depth_clamp: bool,
    warned_see_through: bool,
    adjacency: Option<(u64, Vec<Option<Adjacency>>)>,
    geometry: Option<Geometry>,
    stats: Stats,
    /// Statistics were recorded this frame and await [`ShadowTechnique::after_frame`].
    pending: bool,
    want_debug: bool,
    debug: Option<wgpu::Texture>,
    silhouette_lines: Vec<DebugLine>,
}

fn buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(4),
        usage,
        mapped_at_creation: false,
    })
}

impl ShadowVolumeRenderer {
    pub fn new(gpu: &GpuContext, config: VolumeConfig) -> ShadowVolumeRenderer {
        let device = &gpu.device;
        let usage_args = wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let statistics = gpu.pipeline_statistics.then(|| {
            (
                device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("shadow volume fragments"),
                    ty: wgpu::QueryType::PipelineStatistics(
                        wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS,
                    ),
                    count: 1,
                }),
                buffer(
                    device,
                    "shadow volume statistics",
                    8,
                    wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                ),
            )
        });
        ShadowVolumeRenderer {
            shared: gpu.cache.shared(|| VolumeShared::new(gpu)),
            config,
            uniform: buffer(
                device,
                "shadow volume uniform",
                std::mem::size_of::<VolumeUniform>() as u64,
                crate::gpu::uniform_usage(gpu),
            ),
            extrude_params: buffer(
                device,
                "shadow volume extrusion params",
                std::mem::size_of::<ExtrudeParams>() as u64,
                crate::gpu::uniform_usage(gpu),
            ),
            indices: buffer(device, "shadow volume indices", 16, index_usage()),
            args: buffer(device, "shadow volume indirect args", ARGS_SIZE, usage_args),
            readback: crate::gpu::AsyncReadback::new(
                device,
                "shadow volume readback",
                STATS_OFFSET + 8,
            ),
            statistics,
            depth_clamp: gpu.depth_clamp,
            warned_no_depth_clamp: false,
            warned_see_through: false,
            adjacency: None,
            geometry: None,
            stats: Stats::default(),
            pending: false,
            want_debug: false,
            debug: None,
            silhouette_lines: vec![],
        }
    }

    /// Decides, per caster, whether and how its volume is drawn.
    fn plan(&mut self, ctx: &MaskContext, config: &VolumeConfig) -> Result<Vec<CasterPlan>> {
        let (method, silhouette, cull) = (config.method, config.silhouette, config.cull_casters);
        let geometry = self.geometry.as_mut().expect("ensured");
        let view_proj = ctx.frame.uniform().view_proj;
        let frustum = silhouette::frustum_planes(view_proj);
        let light = ctx.light.homogeneous();
        let inv = ctx.frame.uniform().inv_view_proj;
        let near = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| {
            let c = inv * Vec4::new(x, y, crate::scene::NEAR_PLANE_DEPTH, 1.0);
            c.truncate() / c.w
        });
        let region = silhouette::near_clip_region(near, light);
        let mut report = vec![];
        let plans = geometry
            .mesh
            .casters
            .iter()
            .map(|c| {
                let object_light = c.model.inverse() * light;
                let touches =
                    !cull || silhouette::volume_may_touch(&frustum, &c.world_bounds, light);
                let kind = match silhouette {
                    _ if !touches => VolumeKind::Skip,
                    SilhouetteMode::Auto if !c.closed => {
                        report.push(c.object);
                        VolumeKind::Triangles
                    }
                    SilhouetteMode::Auto | SilhouetteMode::Edges => VolumeKind::Silhouette,
                    SilhouetteMode::Triangles => VolumeKind::Triangles,
                };
                // Z-pass counts the side faces a view ray crosses, so it
                // needs the ray to enter a volume through a side or stop at
                // the opaque light cap; through a cut-out's holes or a
                // translucent pane (which the G-buffer sees past) it enters
                // through the light cap and counts nothing. Such casters
                // take z-fail, which counts behind the pixel.
                let object = &ctx.scene.objects[c.object];
                let see_through = ctx.scene.materials[object.material].is_see_through();
                let zfail = match method {
                    Method::ZPass => false,
                    Method::ZFail => true,
                    Method::Auto => {
                        see_through
                            || region
                                .as_ref()
                                .is_none_or(|r| silhouette::meets(r, &c.world_bounds))
                    }
                };
                CasterPlan {
                    kind,
                    zfail,
                    light: object_light,
                    capped: config.caps,
                }
            })
            .collect();
        if !geometry.reported_open && !report.is_empty() {
            let names: Vec<&str> = report
                .iter()
                .map(|&o| ctx.scene.objects[o].name.as_str())
                .collect();
            log::info!(
                "shadow-volume: {} not closed (open or inconsistently wound edges): per-triangle volumes for {}",
                if names.len() == 1 {
                    "1 caster is"
                } else {
                    "some casters are"
                },
                names.join(", ")
            );
            geometry.reported_open = true;
        }
        Ok(plans)
    }
}

fn entry(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: b.as_entire_binding(),
    }
}

fn index_usage() -> wgpu::BufferUsages {
    wgpu::BufferUsages::INDEX
        | wgpu::BufferUsages::STORAGE
        | wgpu::BufferUsages::COPY_DST
        | wgpu::BufferUsages::COPY_SRC
}

impl Stats {
    /// The counts of a frame's plans: skipped, z-pass, z-fail and
    /// per-triangle volumes.
    fn of(plans: &[CasterPlan]) -> Stats {
        Stats {
            skipped: plans.iter().filter(|p| p.kind == VolumeKind::Skip).count(),
            zpass: plans
                .iter()
                .filter(|p| p.kind != VolumeKind::Skip && !p.zfail)
                .count(),
            zfail: plans
                .iter()
                .filter(|p| p.kind != VolumeKind::Skip && p.zfail)
                .count(),
            per_triangle: plans
                .iter()
                .filter(|p| p.kind == VolumeKind::Triangles)
                .count(),
            ..Default::default()
        }
    }
}

impl ShadowTechnique for ShadowVolumeRenderer {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.config = VolumeConfig::parse(params)?;
        Ok(())
    }

    fn compose(&self) -> Compose {
        self.config.compose
    }

    fn infinite_far_plane(&self) -> bool {
        let c = &self.config;
        c.length <= 0.0
            && match c.far_plane {
                FarPlane::Infinite => true,
                FarPlane::DepthClamp => !self.depth_clamp,
                FarPlane::Clip => false,
            }
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let config = self.config;
        let gpu = ctx.gpu;
        self.ensure_geometry(gpu, ctx.scene);
        let plans = self.plan(ctx, &config)?;
        let length = config.length;
        let dark_cap = !(ctx.light.kind == LightType::Directional && length <= 0.0);
        let see_through =
            |d: &crate::frame::DrawCall| d.casts_shadow && d.alpha_mode != AlphaMode::Opaque;
        if ctx.scene_gpu.draws.iter().any(see_through)
            && !std::mem::replace(&mut self.warned_see_through, true)
        {
            log::warn!(
                "shadow-volume: {}'s cut-out and translucent casters shadow as solids (a shadow volume has no holes)",
                ctx.scene.name
            );
        }
        let clamp_asked = length <= 0.0 && config.far_plane == FarPlane::DepthClamp;
        if clamp_asked
            && !self.depth_clamp
            && !std::mem::replace(&mut self.warned_no_depth_clamp, true)
        {
            log::warn!(
                "shadow-volume: the adapter has no depth clamp (DEPTH_CLIP_CONTROL); using the far plane at infinity"
            );
        }
        let unclipped = clamp_asked && self.depth_clamp;
        self.extrude(
            gpu,
            encoder,
            &plans,
            dark_cap,
            config.extrusion == Extrusion::Gpu,
        )?;
        self.stats = Stats {
            depth_clamped: unclipped,
            ..Stats::of(&plans)
        };
        let geometry = self.geometry.as_ref().expect("ensured");
        let vm = &geometry.mesh;
        if self.want_debug {
            self.silhouette_lines = debug::silhouette_lines(vm, &plans);
        }

        // Count in the stencil, then write the mask where the count is not 0.
        let world_light = match ctx.light.kind {
            LightType::Directional => ctx.light.direction.normalize().extend(0.0),
            _ => ctx.light.position.extend(1.0),
        };
        let uniform = VolumeUniform {
            light: world_light,
            extrusion: Vec4::new(length, config.visibility, 0.0, 0.0),
        };
        gpu.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow volume"),
            layout: &self.shared.layout,
            entries: &[entry(0, &self.uniform), entry(1, &geometry.positions)],
        });
        let two_pass = config.stencil == StencilMode::TwoPass;
        let mut draws = vec![];
        for zfail in [false, true] {
            for pass in if two_pass { &[1u8, 2][..] } else { &[0u8][..] } {
                let key = VolumeKey {
                    zfail,
                    pass: *pass,
                    unclipped,
                };
                draws.push((self.shared.volume_pipeline(gpu, key), zfail));
            }
        }
        let (width, height) = (ctx.frame.width(), ctx.frame.height());
        let scissor = if config.scissor {
            range_scissor(ctx.light, ctx.frame.uniform().view_proj, width, height)
        } else {
            Some([0, 0, width, height])
        };
        // A frame whose passes are counted whole (`bench`'s work) has the
        // pass's query already open: the volumes' own count waits.
        let own_statistics = self.statistics.as_ref().filter(|_| !gpu.counting_work());
        {
            let mut pass = super::mask_pass(encoder, ctx, "shadow volumes");
            if let Some([x, y, w, h]) = scissor {
                pass.set_scissor_rect(x, y, w, h);
                ctx.bind_frame_groups(&mut pass);
                pass.set_bind_group(crate::frame::OWN_GROUP, &group, &[]);
                pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
                if let Some((set, _)) = own_statistics {
                    pass.begin_pipeline_statistics_query(set, 0);
                }
                for (pipeline, zfail) in &draws {
                    pass.set_pipeline(pipeline);
                    let offset = if *zfail { ZFAIL_ARGS } else { 0 };
                    pass.draw_indexed_indirect(&self.args, offset);
                }
                if own_statistics.is_some() {
                    pass.end_pipeline_statistics_query();
                }
                pass.set_pipeline(&self.shared.shadow_pipeline);
                pass.set_stencil_reference(0);
                pass.draw(0..3, 0..1);
            }
        }
        if let Some(target) = self.readback.target() {
            if let Some((set, resolve)) = own_statistics {
                encoder.resolve_query_set(set, 0..1, resolve, 0);
                encoder.copy_buffer_to_buffer(resolve, 0, target, STATS_OFFSET, 8);
            }
            encoder.copy_buffer_to_buffer(&self.args, 0, target, 0, ARGS_SIZE);
            self.pending = true;
        }

        if self.want_debug {
            self.render_debug(ctx, encoder, &group, unclipped);
        }
        Ok(())
    }

    fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        if std::mem::take(&mut self.pending) {
            self.readback.request();
        }
        let Some(data) = self.readback.try_read(gpu)? else {
            return Ok(());
        };
        let args: Args = bytemuck::pod_read_unaligned(&data[..ARGS_SIZE as usize]);
        self.stats.silhouette_edges = args.silhouette_edges;
        self.stats.volume_triangles = (args.lists[0].index_count + args.lists[1].index_count) / 3;
        self.stats.fragments = self
            .statistics
            .as_ref()
            .map(|_| {
                bytemuck::pod_read_unaligned::<u64>(
                    &data[STATS_OFFSET as usize..STATS_OFFSET as usize + 8],
                )
            })
            .filter(|&f| f > 0 || gpu.is_cpu_adapter());
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        let s = &self.stats;
        let mut c = vec![
            ("silhouette_edges", s.silhouette_edges as f64),
            ("volume_triangles", s.volume_triangles as f64),
            ("casters_zpass", s.zpass as f64),
            ("casters_zfail", s.zfail as f64),
            ("casters_per_triangle", s.per_triangle as f64),
            ("casters_culled", s.skipped as f64),
            ("depth_clamped", s.depth_clamped as u32 as f64),
        ];
        if let Some(f) = s.fragments {
            c.push(("volume_fragments", f as f64));
        }
        c
    }

    fn resource_bytes(&self) -> u64 {
        self.indices.size()
            + self.geometry.as_ref().map_or(0, |g| {
                g.positions.size() + g.faces.size() + g.edges.size() + g.casters.size()
            })
    }

    fn enable_debug(&mut self, on: bool) {
        self.want_debug = on;
        self.debug = None;
        self.silhouette_lines.clear();
    }

    fn debug_views(&self, gpu: &GpuContext) -> Result<super::DebugViews> {
        let mut views = super::DebugViews {
            lines: self.silhouette_lines.clone(),
            images: vec![],
        };
        if let Some(t) = &self.debug {
            views.images.push(super::DebugImage {
                label: "shadow volumes (translucent red) over the scene".into(),
                width: t.width(),
                height: t.height(),
                rgba: gpu.read_texture(t, 0, 4)?,
            });
        }
        Ok(views)
    }
}

#[cfg(test)]
mod tests {
    use super::{Args, ExtrudeParams, IndirectArgs, VolumeUniform};
    use crate::gpu::wgsl_layout::assert_struct_matches;
    use std::mem::{offset_of, size_of};

    /// `Volume` of volume.wgsl is laid out as `VolumeUniform`.
    #[test]
    fn the_volume_uniform_matches_its_wgsl_struct() {
        let source = crate::frame::technique_source(&[include_str!("volume.wgsl")]);
        assert_struct_matches(
            &source,
            "Volume",
            crate::field_offsets!(VolumeUniform; light, extrusion),
            size_of::<VolumeUniform>(),
        );
    }

    /// The extrusion's `Params` and `Args` (two flattened indirect draws and
    /// the silhouette counter) of extrude.wgsl are laid out as
    /// `ExtrudeParams` and `Args`.
    #[test]
    fn the_extrusion_structs_match_extrude_wgsl() {
        let source = include_str!("extrude.wgsl");
        assert_struct_matches(
            source,
            "Params",
            crate::field_offsets!(ExtrudeParams; edge_count, face_count, dark_cap, _pad),
            size_of::<ExtrudeParams>(),
        );
        let list = |i: usize| i * size_of::<IndirectArgs>();
        let arg = |i: usize, field: usize| offset_of!(Args, lists) + list(i) + field;
        let fields = |i| {
            [
                arg(i, offset_of!(IndirectArgs, index_count)),
                arg(i, offset_of!(IndirectArgs, instance_count)),
                arg(i, offset_of!(IndirectArgs, first_index)),
                arg(i, offset_of!(IndirectArgs, base_vertex)),
                arg(i, offset_of!(IndirectArgs, first_instance)),
            ]
        };
        let names = ["count", "instances", "first", "base", "first_instance"];
        let names: Vec<String> = ["zpass", "zfail"]
            .iter()
            .flat_map(|l| names.iter().map(move |n| format!("{l}_{n}")))
            .collect();
        let mut rust: Vec<(&str, usize)> = names
            .iter()
            .map(String::as_str)
            .zip(fields(0).into_iter().chain(fields(1)))
            .collect();
        rust.push(("silhouette_edges", offset_of!(Args, silhouette_edges)));
        assert_struct_matches(source, "Args", &rust, size_of::<Args>());
        crate::gpu::wgsl_layout::assert_consts_match(
            source,
            &[("NO_FACE", super::adjacency::NO_FACE)],
        );
        super::extrusion::assert_buffers_match_wgsl(source);
    }
}
