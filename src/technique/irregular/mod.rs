//! `irregular`: the irregular z-buffer, or alias-free shadow maps (Johnson,
//! Mark & Burns 2005; Aila & Laine 2004), on the GPU after Sintorn,
//! Eisemann & Assarsson (2008). A shadow map samples occluders on a regular
//! light-space grid that the camera's pixels never coincide with; here the
//! grid only bins the camera's own samples (the G-buffer's surfaces, with
//! the reference's ray-origin offset), and every caster triangle tests the
//! samples binned in the cells its light-space image covers, exactly, with
//! the shadow ray's own intersection test. The mask has no resolution
//! error: it is the reference's, computed by rasterization-style work.
//!
//! Per frame: the samples' bounds on each face (one orthographic view for a
//! directional light, six cube faces for point and spot lights), the
//! samples pushed onto per-cell linked lists (one node per pixel, so the
//! lists cannot overflow), a triangle pass in which each triangle visits its
//! cells (triangles covering more than `large_cells` cells are listed in
//! chunks of 1024 cells, each shared by a workgroup of an indirect
//! dispatch; chunks past the list's capacity are counted and tested by their
//! triangle's thread), and the mask.

mod casters;
mod gpu;

use super::{Family, MaskContext, ParamSpec, ParamValues, Preset, ShadowTechnique};
use crate::gpu::GpuContext;
use crate::scene::{LightType, scene_fingerprint};
use anyhow::{Result, bail};
use glam::{Mat4, UVec4, Vec3, Vec4};
use gpu::{
    AUX_DISPATCH, AUX_HEADER_WORDS, AUX_HISTOGRAM, AUX_LARGE, AUX_OVERFLOW, AUX_PAIRS, AUX_SAMPLES,
    AUX_TESTS, HISTOGRAM_BINS, IrregularShared, IrregularUniform, LARGE_CAPACITY, MAX_FACES,
    storage_buffer, workgroups_for,
};
use std::sync::Arc;

const GRID: ParamSpec = ParamSpec::int(
    "grid",
    1024,
    64,
    4096,
    "cells per side of each light-space face the samples are binned into (directional lights: one face; point and spot lights: six cube faces); about one cell per pixel keeps the lists short",
);
const LARGE_CELLS: ParamSpec = ParamSpec::int(
    "large_cells",
    256,
    1,
    4096,
    "a triangle whose image covers more cells than this is split into chunks of 1024 cells, each tested by a workgroup of 64 threads, not by the triangle's one thread (one invocation looping over many cells runs long: llvmpipe ends a shader's loops after 65535 iterations, GPUs have watchdogs)",
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
    params: &[GRID, LARGE_CELLS, super::raytraced::OFFSET_ULPS],
    presets: &[Preset {
        name: "default",
        summary: "1024² cells per face, one sample per pixel, cut-outs alpha-tested at full resolution",
        values: &[],
    }],
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
    large_cells: u32,
    offset_ulps: f32,
}

impl IrregularConfig {
    fn parse(p: &ParamValues) -> Result<IrregularConfig> {
        Ok(IrregularConfig {
            grid: p.int(&GRID)?,
            large_cells: p.int(&LARGE_CELLS)?,
            offset_ulps: p.float(&super::raytraced::OFFSET_ULPS)?,
        })
    }
}

/// What the last frame counted (read back a frame late).
#[derive(Clone, Copy, Debug, Default)]
struct ListStats {
    samples: u32,
    pairs: u32,
    tests: u32,
    large: u32,
    overflow: u32,
    /// Cells holding n samples (n from 1; the last bin: that many or more).
    histogram: [u32; HISTOGRAM_BINS],
}

impl ListStats {
    fn from_words(w: &[u32]) -> ListStats {
        let mut histogram = [0; HISTOGRAM_BINS];
        histogram.copy_from_slice(&w[AUX_HISTOGRAM..AUX_HISTOGRAM + HISTOGRAM_BINS]);
        ListStats {
            samples: w[AUX_SAMPLES],
            pairs: w[AUX_PAIRS],
            tests: w[AUX_TESTS],
            large: w[AUX_LARGE],
            overflow: w[AUX_OVERFLOW],
            histogram,
        }
    }

    /// The list length below which a fraction `q` of the non-empty cells lie.
    fn length_quantile(&self, q: f64) -> u32 {
        let total: u64 = self.histogram.iter().map(|&c| c as u64).sum();
        let mut seen = 0u64;
        for (n, &c) in self.histogram.iter().enumerate() {
            seen += c as u64;
            if c > 0 && seen as f64 >= q * total as f64 {
                return n as u32;
            }
        }
        0
    }
}

/// The buffers of one frame size, scene and light shape.
struct Buffers {
    key: (u32, u32, u64, usize, u32),
    uniform: wgpu::Buffer,
    heads: wgpu::Buffer,
    samples: wgpu::Buffer,
    marks: wgpu::Buffer,
    triangles: wgpu::Buffer,
    triangle_count: u32,
    /// Chunks the large list holds.
    large_capacity: u32,
    aux: wgpu::Buffer,
    /// The large pass's indirect arguments, copied from `aux`.
    large_args: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

pub struct IrregularZBuffer {
    shared: Arc<IrregularShared>,
    config: IrregularConfig,
    buffers: Option<Buffers>,
    readback: crate::gpu::AsyncReadback,
    pending: bool,
    stats: ListStats,
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
        }
    }

    /// The buffers for this frame, made again where the frame size, the
    /// scene, the light's face count or the grid changed; sizes past the
    /// device's storage-buffer limit or the memory budget are an error.
    fn ensure_buffers(&mut self, ctx: &MaskContext, faces: usize) -> Result<&Buffers> {
        let (w, h) = (ctx.frame.width(), ctx.frame.height());
        let key = (w, h, scene_fingerprint(ctx.scene), faces, self.config.grid);
        if self.buffers.as_ref().is_some_and(|b| b.key == key) {
            return Ok(self.buffers.as_ref().expect("checked"));
        }
        self.buffers = None;
        let gpu = ctx.gpu;
        let triangles = casters::caster_triangles(ctx.scene);
        let cells = faces as u64 * self.config.grid as u64 * self.config.grid as u64;
        let pixels = w as u64 * h as u64;
        let large_capacity =
            (4 * triangles.len() as u64 * faces as u64).clamp(LARGE_CAPACITY.0, LARGE_CAPACITY.1);
        let sizes = [
            ("cell lists (grid)", cells * 4),
            ("samples and their lists", pixels * 16),
            ("caster triangles", triangles.len() as u64 * 64),
            (
                "large-triangle list",
                (AUX_HEADER_WORDS + 2 * large_capacity) * 4,
            ),
        ];
        let limit = gpu.device.limits().max_storage_buffer_binding_size;
        for (what, bytes) in sizes {
            if bytes > limit {
                bail!(
                    "irregular: the {what} take {:.1} MiB, more than the device's largest storage buffer ({:.1} MiB); choose a smaller grid or frame",
                    bytes as f64 / (1u64 << 20) as f64,
                    limit as f64 / (1u64 << 20) as f64
                );
            }
        }
        let total = sizes.iter().map(|s| s.1).sum::<u64>() + pixels * 4;
        gpu.check_allocation("irregular (grid, lists, casters)", (1, 1, 1), total)?;
        let uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("irregular uniform"),
            size: std::mem::size_of::<IrregularUniform>() as u64,
            usage: crate::gpu::uniform_usage(gpu),
            mapped_at_creation: false,
        });
        let heads = storage_buffer(gpu, "irregular cell lists", sizes[0].1);
        let samples = storage_buffer(gpu, "irregular samples", pixels * 16);
        let marks = storage_buffer(gpu, "irregular marks", pixels * 4);
        let triangle_buffer = storage_buffer(gpu, "irregular casters", sizes[2].1);
        gpu.queue
            .write_buffer(&triangle_buffer, 0, bytemuck::cast_slice(&triangles));
        let aux = storage_buffer(gpu, "irregular header and large list", sizes[3].1);
        fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("irregular"),
            layout: &self.shared.layout,
            entries: &[
                entry(0, &uniform),
                entry(1, &heads),
                entry(2, &samples),
                entry(3, &marks),
                entry(4, &triangle_buffer),
                entry(5, &aux),
            ],
        });
        Ok(self.buffers.insert(Buffers {
            key,
            uniform,
            heads,
            samples,
            marks,
            triangles: triangle_buffer,
            triangle_count: triangles.len() as u32,
            large_capacity: large_capacity as u32,
            aux,
            large_args: storage_buffer(gpu, "irregular large dispatch", 12),
            bind_group,
        }))
    }
}

/// The light views of a light's faces: for a directional light one view
/// looking along it (its image is orthographic, so where it stands does not
/// matter); for point and spot lights the six cube faces +x, −x, +y, −y,
/// +z, −z from its position, each looking down its axis.
fn face_views(kind: LightType, position: Vec3, direction: Vec3) -> Vec<Mat4> {
    if kind == LightType::Directional {
        let dir = direction.normalize();
        let up = super::light_space::up_for(dir);
        return vec![glam::camera::rh::view::look_to_mat4(Vec3::ZERO, dir, up)];
    }
    [
        (Vec3::X, Vec3::Y),
        (Vec3::NEG_X, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y),
    ]
    .map(|(axis, up)| glam::camera::rh::view::look_to_mat4(position, axis, up))
    .to_vec()
}

impl ShadowTechnique for IrregularZBuffer {
    fn configure(&mut self, params: &ParamValues) -> Result<()> {
        self.config = IrregularConfig::parse(params)?;
        Ok(())
    }

    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        let light = ctx.light;
        let views = face_views(light.kind, light.position, light.direction);
        let faces = views.len();
        let config = self.config;
        let shared = self.shared.clone();
        let b = self.ensure_buffers(ctx, faces)?;
        let mut uniform = IrregularUniform {
            views: [Mat4::IDENTITY; MAX_FACES],
            light: match light.kind {
                LightType::Directional => light.direction.normalize().extend(0.0),
                _ => light.position.extend(1.0),
            },
            grid: UVec4::new(
                faces as u32,
                config.grid,
                ctx.frame.width(),
                ctx.frame.height(),
            ),
            work: UVec4::new(b.triangle_count, config.large_cells, b.large_capacity, 0),
            offset: Vec4::new(config.offset_ulps, 0.0, 0.0, 0.0),
        };
        uniform.views[..faces].copy_from_slice(&views);
        ctx.gpu
            .queue
            .write_buffer(&b.uniform, 0, bytemuck::bytes_of(&uniform));
        encoder.clear_buffer(&b.heads, 0, None);
        encoder.clear_buffer(&b.marks, 0, None);
        encoder.clear_buffer(&b.aux, 0, Some(AUX_HEADER_WORDS * 4));
        for (label, pipeline) in [
            ("irregular bounds", &shared.bounds),
            ("irregular binning", &shared.bin),
        ] {
            let mut pass = super::mask_pass(encoder, ctx, label);
            ctx.bind_frame_groups(&mut pass);
            pass.set_bind_group(crate::frame::OWN_GROUP, &b.bind_group, &[]);
            pass.set_pipeline(pipeline);
            pass.draw(0..3, 0..1);
        }
        let cells = faces as u64 * config.grid as u64 * config.grid as u64;
        let dispatches = [
            (
                "irregular list lengths",
                &shared.histogram,
                Some(workgroups_for(cells)),
            ),
            (
                "irregular triangles",
                &shared.triangles,
                Some(workgroups_for(b.triangle_count as u64)),
            ),
            (
                "irregular large dispatch",
                &shared.large_dispatch,
                Some((1, 1)),
            ),
            ("irregular large triangles", &shared.large, None),
        ];
        for (label, pipeline, groups) in dispatches {
            if groups.is_none() {
                encoder.copy_buffer_to_buffer(
                    &b.aux,
                    AUX_DISPATCH as u64 * 4,
                    &b.large_args,
                    0,
                    12,
                );
            }
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
                Some((x, y)) => pass.dispatch_workgroups(x, y, 1),
                None => pass.dispatch_workgroups_indirect(&b.large_args, 0),
            }
        }
        {
            let mut pass = super::mask_pass(encoder, ctx, "irregular mask");
            ctx.bind_frame_groups(&mut pass);
            pass.set_bind_group(crate::frame::OWN_GROUP, &b.bind_group, &[]);
            pass.set_pipeline(&shared.mask);
            pass.draw(0..3, 0..1);
        }
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
        Ok(())
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        let s = &self.stats;
        vec![
            ("samples_binned", s.samples as f64),
            ("list_length_p50", s.length_quantile(0.5) as f64),
            ("list_length_p99", s.length_quantile(0.99) as f64),
            ("triangle_cell_pairs", s.pairs as f64),
            ("sample_tests", s.tests as f64),
            ("large_triangle_chunks", s.large as f64),
            ("chunk_overflows", s.overflow as f64),
        ]
    }

    fn resource_bytes(&self) -> u64 {
        self.buffers.as_ref().map_or(0, |b| {
            [
                &b.uniform,
                &b.heads,
                &b.samples,
                &b.marks,
                &b.triangles,
                &b.aux,
            ]
            .iter()
            .map(|x| x.size())
            .sum()
        })
    }
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
        let views = face_views(LightType::Point, p, Vec3::ZERO);
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
        let sun = face_views(
            LightType::Directional,
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
        );
        assert_eq!(sun.len(), 1);
        assert!(sun[0].transform_vector3(Vec3::NEG_Y).z < -0.999);
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
    }
}
