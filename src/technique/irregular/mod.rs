//! `irregular`: the irregular z-buffer, or alias-free shadow maps (Johnson,
//! Mark & Burns 2005; Aila & Laine 2004), on the GPU after Sintorn,
//! Eisemann & Assarsson (2008). A shadow map samples occluders on a regular
//! light-space grid that the camera's pixels never coincide with; here the
//! grid only bins the camera's own samples (the G-buffer's surfaces, with
//! the reference's ray-origin offset), and every caster triangle tests the
//! samples binned in the cells its light-space image covers, exactly, with
//! the shadow ray's own intersection test (an opaque solid's faces turned
//! away from the light are skipped: its faces toward the light block the
//! same rays). The mask has no resolution error: it is the reference's,
//! computed by rasterization-style work.
//!
//! Per frame: the samples' bounds on each face (one orthographic view for a
//! directional light, one perspective view along a spot light's axis, six
//! cube faces for point lights and spots wider than 75°) and each face's
//! grid, fitted to the samples it holds (a point light's crowd onto one or
//! two faces), the samples binned by count, prefix sum and scatter (sorted by cell, so a
//! row of cells' samples is one contiguous run and the lists cannot
//! overflow), a triangle pass in which each triangle tests the samples of
//! its cells, the opaque casters first and the see-through ones after,
//! each with a pipeline of its own (triangles whose cells hold more than
//! `large_samples` are
//! listed as jobs of 1024 samples, each shared by a workgroup of an
//! indirect dispatch, so that no invocation loops long however dense the
//! samples; jobs past the list's capacity are counted, tested by their
//! triangle's thread, and the list grows for the next frame), and the mask.

mod buffers;
mod casters;
mod cull;
mod gpu;
mod timing;

use super::params::{Choice, choice_enum};
use super::{Family, MaskContext, ParamSpec, ParamValues, Preset, ShadowTechnique};
use crate::gpu::GpuContext;
use crate::scene::{Light, LightType};
use anyhow::Result;
use buffers::Buffers;
use glam::{Mat4, UVec4, Vec3, Vec4};
use gpu::{
    AUX_BOUNDS, AUX_DISPATCH, AUX_HEADER_WORDS, AUX_HISTOGRAM, AUX_JOBS, AUX_LAYOUT, AUX_LONGEST,
    AUX_OVERFLOW, AUX_PAIRS, AUX_SAMPLES, AUX_SEE_THROUGH_DISPATCH, AUX_SEE_THROUGH_JOBS,
    AUX_TESTS, BOUNDS_RUN, HISTOGRAM_BINS, IrregularShared, IrregularUniform, MAX_FACES,
    SCAN_BLOCK, SamplePass, TestPass, TestStage, grid_of_workgroups, workgroups_for,
};
use std::sync::Arc;
use timing::{Pass, PassTimer};

const GRID: ParamSpec = ParamSpec::int(
    "grid",
    0,
    0,
    4096,
    "cells per side of each light-space face the samples are binned into (directional lights and spot lights up to 75°: one face; point lights and wider spots: six cube faces), at least 64; 0: each face's grid fitted to the samples it holds, a cell per sample (a point light's samples crowd onto one or two faces, which then get the cells), within the largest storage buffer — more cells shorten the lists, fewer shorten the per-cell passes",
);
/// Cells per sample a face fitted to its samples is given.
const CELLS_PER_SAMPLE: f64 = 1.0;
/// The uniform's cone cosine for a light without a cone: below every
/// cosine, so every direction is inside.
const NO_CONE: f32 = -2.0;
/// The least grid side (an explicit `grid` below it is raised to it).
const GRID_MIN: u32 = 64;
const LARGE_SAMPLES: ParamSpec = ParamSpec::int(
    "large_samples",
    256,
    1,
    16384,
    "a triangle whose cells hold more samples than this is split into jobs of 1024 samples, each tested by a workgroup of 64 threads, not by the triangle's one thread (one invocation looping over many samples runs long: llvmpipe ends a shader's loops after 65535 iterations, GPUs have watchdogs)",
);

choice_enum! {
    /// How the shadow rays meet translucent (glTF `BLEND`) casters.
    pub enum BlendedCrossing {
        /// Solid where the opacity reaches ½ (the other families' default).
        Cutout = "cutout",
        /// Letting 1 − opacity through, multiplied over the surfaces a ray
        /// crosses: the reference's transmittance.
        Transmit = "transmit",
        /// Solid everywhere.
        Opaque = "opaque",
        /// Not in the way at all.
        Ignore = "ignore",
    }
}

const BLENDED_CASTERS: ParamSpec = ParamSpec::choice_of::<BlendedCrossing>(
    "blended_casters",
    BlendedCrossing::Cutout as usize,
    "translucent (glTF BLEND) casters: cutout — solid where opacity ≥ ½; transmit — each sample keeps the product of 1 − opacity over the translucent surfaces its ray crosses (summed as optical depth, 4 more bytes per sample), exactly what the reference traces; opaque — solid everywhere; ignore — cast no shadow",
);

pub static FAMILY: Family = Family {
    id: "irregular",
    summary: "irregular z-buffer (alias-free shadow maps): caster triangles tested exactly against the camera's own samples, binned in light space",
    capabilities: super::Capabilities {
        point_lights: true,
        spot_lights: true,
        directional_lights: true,
        soft_shadows: false,
        self_shadowing: true,
        open_meshes: true,
        curved_receivers: true,
        cutout_casters: true,
    },
    params: &[
        GRID,
        LARGE_SAMPLES,
        super::raytraced::PIXEL_SAMPLES,
        super::raytraced::OFFSET_ULPS,
        super::raytraced::OFFSET_FOOTPRINT,
        BLENDED_CASTERS,
    ],
    presets: &[
        Preset {
            name: "default",
            summary: "a grid of at least one cell per sample, one sample per pixel, cut-outs alpha-tested at full resolution",
            values: &[],
        },
        Preset {
            name: "subpixel",
            summary: "16 samples per pixel on its surface plane (frustum-traced raster shadows, Wyman, Hoetzlein & Lefohn 2015): the fraction of the pixel's footprint that sees the light; measure it against `raytraced:subpixel`",
            values: &[(super::raytraced::PIXEL_SAMPLES.name, "16")],
        },
    ],
    create: |gpu, params| {
        Ok(Box::new(IrregularZBuffer::new(
            gpu,
            IrregularConfig::parse(params)?,
        )))
    },
};

/// The family's parameters, parsed.
#[derive(Clone, Copy, Debug)]
struct IrregularConfig {
    grid: u32,
    large_samples: u32,
    pixel_samples: u32,
    offset_ulps: f32,
    offset_footprint: f32,
    blended: BlendedCrossing,
}

impl IrregularConfig {
    /// The grid for at most `samples` samples over `faces` faces: `grid`
    /// on every face, or with `grid` 0 the faces' sides left to the GPU
    /// (`cs_face_layout` of samples.wgsl: ⌈√(n_f · c)⌉ for the n_f samples
    /// a face holds, c = [`CELLS_PER_SAMPLE`]), with room for them: the
    /// sides' squares sum to at most Σ(√(n_f c) + 1)² ≤ c·n + 2√(F·c·n) + F
    /// over F faces and n samples (Cauchy–Schwarz), within `max_cells`
    /// (the largest storage buffer's worth; past it the crowded faces get
    /// fewer cells).
    fn grid_cells(&self, samples: u64, faces: usize, max_cells: u64) -> GridCells {
        let faces = faces.max(1) as u64;
        if self.grid != 0 {
            let side = self.grid.clamp(GRID_MIN, GRID.max as u32);
            let cells = faces * side as u64 * side as u64;
            return GridCells { side, cells };
        }
        let wanted = CELLS_PER_SAMPLE * samples as f64;
        let bound = wanted + 2.0 * (faces as f64 * wanted).sqrt() + faces as f64;
        GridCells {
            side: 0,
            cells: (bound.ceil() as u64).clamp(faces, max_cells.max(faces)),
        }
    }

    fn parse(p: &ParamValues) -> Result<IrregularConfig> {
        Ok(IrregularConfig {
            grid: p.int(&GRID)?,
            large_samples: p.int(&LARGE_SAMPLES)?,
            pixel_samples: p.int(&super::raytraced::PIXEL_SAMPLES)?,
            offset_ulps: p.float(&super::raytraced::OFFSET_ULPS)?,
            offset_footprint: p.float(&super::raytraced::OFFSET_FOOTPRINT)?,
            blended: p.choice(&BLENDED_CASTERS)?,
        })
    }
}

/// The grid a frame's buffers are made for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct GridCells {
    /// Cells per side of every face (`grid`), or 0: each face's side fitted
    /// to its samples on the GPU.
    side: u32,
    /// The cells the binning buffer holds.
    cells: u64,
}

/// What the last frame counted (read back a frame late).
#[derive(Clone, Copy, Debug, Default)]
struct ListStats {
    samples: u32,
    pairs: u32,
    tests: u32,
    jobs: u32,
    /// Samples of the jobs that did not fit the list.
    overflow: u32,
    /// Cells by the samples they hold: bin n < 16 holds n, then one bin per
    /// octave (`histogram_bin` of samples.wgsl), the last one open.
    histogram: [u32; HISTOGRAM_BINS],
    longest: u32,
    /// Cells the faces' grids took.
    cells: u32,
}

impl ListStats {
    fn from_words(w: &[u32]) -> ListStats {
        let mut histogram = [0; HISTOGRAM_BINS];
        histogram.copy_from_slice(&w[AUX_HISTOGRAM..AUX_HISTOGRAM + HISTOGRAM_BINS]);
        ListStats {
            samples: w[AUX_SAMPLES],
            pairs: w[AUX_PAIRS],
            tests: w[AUX_TESTS],
            jobs: w[AUX_JOBS] + w[AUX_SEE_THROUGH_JOBS],
            overflow: w[AUX_OVERFLOW],
            histogram,
            longest: w[AUX_LONGEST],
            cells: w[AUX_LAYOUT + 2],
        }
    }

    /// The least list length of a histogram bin.
    fn bin_floor(bin: usize) -> u32 {
        if bin < 16 {
            bin as u32
        } else {
            1 << (bin - 12)
        }
    }

    /// The list length below which a fraction `q` of the non-empty cells
    /// lie, to the octave past 16 (the least length of its bin).
    fn length_quantile(&self, q: f64) -> u32 {
        let total: u64 = self.histogram.iter().map(|&c| c as u64).sum();
        let mut seen = 0u64;
        for (n, &c) in self.histogram.iter().enumerate() {
            seen += c as u64;
            if c > 0 && seen as f64 >= q * total as f64 {
                return Self::bin_floor(n);
            }
        }
        0
    }
}

pub struct IrregularZBuffer {
    shared: Arc<IrregularShared>,
    config: IrregularConfig,
    buffers: Option<Buffers>,
    readback: crate::gpu::AsyncReadback,
    pending: bool,
    stats: ListStats,
    /// The caster triangles the last frame dispatched (`cull`).
    kept_triangles: u32,
    /// GPU time of each pass.
    timer: PassTimer,
}

impl IrregularZBuffer {
    fn new(gpu: &GpuContext, config: IrregularConfig) -> IrregularZBuffer {
        IrregularZBuffer {
            shared: gpu.cache.shared(|| IrregularShared::new(gpu)),
            config,
            buffers: None,
            readback: crate::gpu::AsyncReadback::new(
                &gpu.device,
                "irregular statistics",
                AUX_HEADER_WORDS * 4,
            ),
            pending: false,
            stats: ListStats::default(),
            kept_triangles: 0,
            timer: PassTimer::new(gpu),
        }
    }
}

/// The widest outer cone (half-angle, degrees) of a spot light whose
/// samples are binned on one face looking along its axis; a wider spot
/// takes the six cube faces (an image's coordinates, tan θ, grow without
/// bound towards 90°).
const ONE_FACE_SPOT_CONE_DEG: f32 = 75.0;

/// The light views of a light's faces: for a directional light one view
/// looking along it (its image is orthographic, so where it stands does not
/// matter); for a spot light no wider than [`ONE_FACE_SPOT_CONE_DEG`] one
/// perspective view along its axis, which every sample its cone reaches
/// lies in front of (a sixth of a point light's cells and projections);
/// for other point and spot lights the six cube faces +x, −x, +y, −y, +z,
/// −z from its position, each looking down its axis.
fn face_views(light: &Light) -> Vec<Mat4> {
    use glam::camera::rh::view::look_to_mat4;
    let dir = light.direction.normalize();
    match light.kind {
        LightType::Directional => {
            return vec![look_to_mat4(
                Vec3::ZERO,
                dir,
                super::light_space::up_for(dir),
            )];
        }
        LightType::Spot if light.outer_cone_deg <= ONE_FACE_SPOT_CONE_DEG => {
            return vec![look_to_mat4(
                light.position,
                dir,
                super::light_space::up_for(dir),
            )];
        }
        _ => {}
    }
    [
        (Vec3::X, Vec3::Y),
        (Vec3::NEG_X, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y),
    ]
    .map(|(axis, up)| look_to_mat4(light.position, axis, up))
    .to_vec()
}

impl ShadowTechnique for IrregularZBuffer {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.config = IrregularConfig::parse(params)?;
        Ok(())
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let light = ctx.light;
        let views = face_views(light);
        let faces = views.len();
        let config = self.config;
        let shared = self.shared.clone();
        let stamps = self.timer.begin_frame(ctx.gpu);
        let sub_pixel = config.pixel_samples > 1;
        let [count, scatter] = [SamplePass::Count, SamplePass::Scatter]
            .map(|pass| shared.sample_pass(ctx.gpu, pass, sub_pixel));
        let bounds = shared.bounds_pass(ctx.gpu, sub_pixel);
        let see_through = match config.blended {
            BlendedCrossing::Transmit => TestPass::Transmit,
            _ => TestPass::SeeThrough,
        };
        let b = self.ensure_buffers(ctx, faces)?;
        let kept = kept_casters(ctx, b);
        let uniform = frame_uniform(ctx, &config, b, &views, &kept);
        ctx.gpu
            .queue
            .write_buffer(&b.uniform, 0, bytemuck::bytes_of(&uniform));
        encoder.clear_buffer(&b.binning, 0, Some(b.grid.cells * 4));
        encoder.clear_buffer(&b.marks, 0, None);
        encoder.clear_buffer(&b.aux, 0, Some(AUX_HEADER_WORDS * 4));
        let fullscreen = |encoder: &mut wgpu::CommandEncoder, label, pipeline| {
            let mut pass = super::mask_pass(encoder, ctx, label);
            ctx.bind_frame_groups(&mut pass);
            pass.set_bind_group(crate::frame::OWN_GROUP, &b.bind_group, &[]);
            pass.set_pipeline(pipeline);
            pass.draw(0..3, 0..1);
        };
        let compute = |encoder: &mut wgpu::CommandEncoder, label, pipeline, groups: Dispatch| {
            let mut pass = ctx.gpu.compute_pass(
                encoder,
                &wgpu::ComputePassDescriptor {
                    label: Some(label),
                    timestamp_writes: None,
                },
            );
            bind_compute_groups(ctx, &mut pass, &b.bind_group);
            pass.set_pipeline(pipeline);
            match groups {
                Dispatch::Direct(x, y) => pass.dispatch_workgroups(x, y, 1),
                Dispatch::Indirect(offset) => {
                    pass.dispatch_workgroups_indirect(&b.job_args, offset)
                }
            }
        };
        let runs = ctx.frame.width().div_ceil(BOUNDS_RUN) as u64 * ctx.frame.height() as u64;
        let (x, y) = workgroups_for(runs);
        stamps.time(encoder, Pass::Bounds, |e| {
            compute(e, "irregular bounds", bounds, Dispatch::Direct(x, y));
            let one = Dispatch::Direct(1, 1);
            compute(e, "irregular face layout", &shared.face_layout, one);
            let face_bytes = MAX_FACES as u64 * 16;
            let (boxes, grids) = (AUX_BOUNDS as u64 * 4, AUX_LAYOUT as u64 * 4);
            e.copy_buffer_to_buffer(&b.aux, boxes, &b.face_boxes, 0, face_bytes);
            e.copy_buffer_to_buffer(&b.aux, grids, &b.face_boxes, face_bytes, face_bytes);
        });
        stamps.time(encoder, Pass::Counts, |e| {
            fullscreen(e, "irregular counts", count)
        });
        let (x, y) = grid_of_workgroups(b.grid.cells.div_ceil(SCAN_BLOCK));
        let blocks = Dispatch::Direct(x, y);
        stamps.time(encoder, Pass::PrefixSum, |e| {
            compute(e, "irregular prefix sum", &shared.scan_blocks, blocks);
            let one = Dispatch::Direct(1, 1);
            compute(e, "irregular partials", &shared.scan_partials, one);
            compute(e, "irregular offsets", &shared.scan_add, blocks);
        });
        stamps.time(encoder, Pass::Scatter, |e| {
            fullscreen(e, "irregular scatter", scatter)
        });
        // The opaque casters' passes, then the see-through ones' (their
        // jobs take what room the opaque ones left in the list): each
        // run's triangle and job pipelines, its triangles and the words of
        // its jobs' dispatch.
        let run = |test, count, word| {
            let pipeline = |stage| shared.test_pass(ctx.gpu, stage, test, sub_pixel);
            let pipelines = [TestStage::Triangles, TestStage::Jobs].map(pipeline);
            (pipelines, count, word)
        };
        let runs = [
            run(TestPass::Opaque, kept.opaque, AUX_DISPATCH),
            run(see_through, kept.see_through, AUX_SEE_THROUGH_DISPATCH),
        ];
        stamps.time(encoder, Pass::Triangles, |e| {
            for ([triangles, _], count, _) in runs.iter().filter(|r| r.1 > 0) {
                let (x, y) = workgroups_for(*count as u64);
                compute(e, "irregular triangles", triangles, Dispatch::Direct(x, y));
            }
            let dispatch = &shared.job_dispatch;
            compute(
                e,
                "irregular job dispatch",
                dispatch,
                Dispatch::Direct(1, 1),
            );
            for (k, (_, _, word)) in runs.iter().enumerate() {
                e.copy_buffer_to_buffer(&b.aux, *word as u64 * 4, &b.job_args, 12 * k as u64, 12);
            }
        });
        stamps.time(encoder, Pass::Jobs, |e| {
            for (k, ([_, jobs], ..)) in runs.iter().enumerate().filter(|r| r.1.1 > 0) {
                compute(e, "irregular jobs", jobs, Dispatch::Indirect(12 * k as u64));
            }
        });
        stamps.time(encoder, Pass::MaskWrite, |e| {
            fullscreen(e, "irregular mask", &shared.mask)
        });
        self.kept_triangles = kept.opaque + kept.see_through;
        self.timer.resolve(encoder);
        if let Some(target) = self.readback.target() {
            let aux = &self.buffers.as_ref().expect("made above").aux;
            encoder.copy_buffer_to_buffer(aux, 0, target, 0, AUX_HEADER_WORDS * 4);
            self.pending = true;
        }
        Ok(())
    }

    fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        if std::mem::take(&mut self.pending) {
            self.readback.request();
        }
        if let Some(data) = self.readback.try_read(gpu)? {
            self.stats = ListStats::from_words(bytemuck::cast_slice(&data));
        }
        self.timer.after_frame(gpu)?;
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        let s = &self.stats;
        let mut counters = vec![
            ("samples_binned", s.samples as f64),
            ("list_length_p50", s.length_quantile(0.5) as f64),
            ("list_length_p99", s.length_quantile(0.99) as f64),
            ("triangle_cell_pairs", s.pairs as f64),
            ("sample_tests", s.tests as f64),
            ("caster_triangles_kept", self.kept_triangles as f64),
            ("list_length_max", s.longest as f64),
            ("large_triangle_jobs", s.jobs as f64),
            ("job_overflow_samples", s.overflow as f64),
            ("grid_cells", s.cells as f64),
        ];
        counters.extend(self.timer.counters());
        counters
    }

    fn resource_bytes(&self) -> u64 {
        self.buffers.as_ref().map_or(0, |b| {
            [
                &b.uniform,
                &b.binning,
                &b.samples,
                &b.marks,
                &b.triangles,
                &b.kept_ranges,
                &b.aux,
            ]
            .iter()
            .map(|x| x.size())
            .sum()
        })
    }
}

/// The casters that can shadow what the frame's camera sees ([`cull`]),
/// their ranges written to `b.kept_ranges`.
fn kept_casters(ctx: &MaskContext, b: &Buffers) -> cull::KeptCasters {
    let hull = cull::shadowing_hull(
        ctx.camera,
        ctx.frame.width() as f32 / ctx.frame.height() as f32,
        ctx.frame.height(),
        &ctx.scene_gpu.bounds,
        ctx.light,
    );
    let kept = cull::kept_casters(&b.clusters, b.opaque_triangles, |c| !hull.excludes(c));
    if !kept.ranges.is_empty() {
        ctx.gpu
            .queue
            .write_buffer(&b.kept_ranges, 0, bytemuck::cast_slice(&kept.ranges));
    }
    kept
}

/// The frame's uniform: the light's faces, the grid, the work and the
/// settings.
fn frame_uniform(
    ctx: &MaskContext,
    config: &IrregularConfig,
    b: &Buffers,
    views: &[Mat4],
    kept: &cull::KeptCasters,
) -> IrregularUniform {
    let light = ctx.light;
    let faces = views.len();
    let mut uniform = IrregularUniform {
        views: [Mat4::IDENTITY; MAX_FACES],
        light: match light.kind {
            LightType::Directional => light.direction.normalize().extend(0.0),
            _ => light.position.extend(1.0),
        },
        grid: UVec4::new(
            faces as u32,
            b.grid.side,
            ctx.frame.width(),
            ctx.frame.height(),
        ),
        work: UVec4::new(0, config.large_samples, b.job_capacity, b.grid.cells as u32),
        offset: Vec4::new(
            config.offset_ulps,
            light.range,
            config.offset_footprint,
            CELLS_PER_SAMPLE as f32,
        ),
        pixel: UVec4::new(config.pixel_samples, config.blended.index() as u32, 0, 0),
        kept: UVec4::new(
            kept.opaque_ranges,
            kept.ranges.len() as u32,
            kept.opaque,
            kept.see_through,
        ),
        cone: match light.kind {
            LightType::Spot => light.cone_axis().extend(light.cone_cos()),
            _ => Vec4::new(0.0, 0.0, 0.0, NO_CONE),
        },
    };
    uniform.views[..faces].copy_from_slice(views);
    uniform
}

/// How a compute pass is dispatched: (x, y) workgroups, or the indirect
/// arguments at this byte offset of the job passes' buffer.
#[derive(Clone, Copy)]
enum Dispatch {
    Direct(u32, u32),
    Indirect(u64),
}

/// Binds the frame's groups (frame, objects, G-buffer) and the family's own
/// to a compute pass.
fn bind_compute_groups(ctx: &MaskContext, pass: &mut wgpu::ComputePass, own: &wgpu::BindGroup) {
    pass.set_bind_group(crate::frame::FRAME_GROUP, ctx.frame.frame_bind_group(), &[]);
    pass.set_bind_group(
        crate::frame::OBJECTS_GROUP,
        &ctx.scene_gpu.object_bind_group,
        &[],
    );
    pass.set_bind_group(crate::frame::OWN_GROUP, own, &[]);
    pass.set_bind_group(
        crate::frame::GBUFFER_GROUP,
        ctx.frame.gbuffer_bind_group(),
        &[],
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each cube face looks down its axis: a point along +x from the light
    /// lies in front of face 0 (−z), centred in its image.
    #[test]
    fn cube_faces_look_down_their_axes() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        let views = face_views(&Light::point(p, 1.0));
        let axes = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ];
        for (view, axis) in views.iter().zip(axes) {
            let v = view.transform_point3(p + axis * 2.0);
            assert!(
                (v - Vec3::new(0.0, 0.0, -2.0)).length() < 1e-5,
                "{axis}: {v}"
            );
        }
        let sun = face_views(&Light::directional(Vec3::new(0.0, -1.0, 0.0), 1.0));
        assert_eq!(sun.len(), 1);
        assert!(sun[0].transform_vector3(Vec3::NEG_Y).z < -0.999);
        // A spot no wider than 75° looks along its axis from its position;
        // a wider one takes the cube.
        let mut spot = Light::spot(p, p + Vec3::new(1.0, -1.0, 0.0), 1.0, 50.0, 60.0);
        let views = face_views(&spot);
        assert_eq!(views.len(), 1);
        let ahead = views[0].transform_point3(p + Vec3::new(1.0, -1.0, 0.0).normalize() * 3.0);
        assert!(
            (ahead - Vec3::new(0.0, 0.0, -3.0)).length() < 1e-5,
            "{ahead}"
        );
        spot.outer_cone_deg = 80.0;
        assert_eq!(face_views(&spot).len(), 6);
    }

    /// The automatic grid gives at least one cell per sample over the
    /// faces, in powers of two, within the largest storage buffer; an
    /// explicit side is kept (raised to 64), and one too large is an error
    /// where the buffers are made.
    #[test]
    fn the_automatic_grid_follows_the_samples() {
        let auto = IrregularConfig {
            grid: 0,
            large_samples: 256,
            pixel_samples: 1,
            offset_ulps: 64.0,
            offset_footprint: 0.004,
            blended: BlendedCrossing::Cutout,
        };
        let any = u64::MAX;
        let fitted = |cells| GridCells { side: 0, cells };
        // 921 600 samples: 921 600 + 2·960 + 1 cells on one face, and
        // 2·√(6 · 921 600) + 6 more over six.
        assert_eq!(auto.grid_cells(1280 * 720, 1, any), fitted(923_521));
        assert_eq!(auto.grid_cells(1280 * 720, 6, any), fitted(926_310));
        assert_eq!(auto.grid_cells(0, 6, any), fitted(6));
        // 32 samples a pixel of 1280 × 720 would ask for 29.5 M cells, past
        // a 128 MiB buffer's 16.7 M cells of counts and offsets.
        let max_cells = gpu::cells_fitting(128 << 20);
        assert_eq!(
            auto.grid_cells(32 * 1280 * 720, 1, max_cells),
            fitted(max_cells)
        );
        let fixed = IrregularConfig { grid: 32, ..auto };
        let side = |side, cells| GridCells { side, cells };
        assert_eq!(fixed.grid_cells(1280 * 720, 1, any), side(64, 64 * 64));
        let fixed = IrregularConfig { grid: 4096, ..auto };
        assert_eq!(
            fixed.grid_cells(1280 * 720, 6, max_cells),
            side(4096, 6 << 24)
        );
    }

    /// The list-length quantiles come from the histogram of non-empty cells.
    #[test]
    fn list_length_quantiles_from_the_histogram() {
        let mut words = vec![0u32; AUX_HEADER_WORDS as usize];
        words[AUX_HISTOGRAM + 1] = 90;
        words[AUX_HISTOGRAM + 2] = 9;
        words[AUX_HISTOGRAM + 7] = 1;
        let s = ListStats::from_words(&words);
        assert_eq!(s.length_quantile(0.5), 1);
        assert_eq!(s.length_quantile(0.95), 2);
        assert_eq!(s.length_quantile(1.0), 7);
        // Past 16, one bin per octave: [16, 32) is bin 16, [1024, 2048) bin 22.
        words[AUX_HISTOGRAM + 22] = 100;
        let s = ListStats::from_words(&words);
        assert_eq!(s.length_quantile(1.0), 1024);
    }
}
