//! The irregular z-buffer's buffers: their sizes, checked against the
//! device's storage-buffer limit and the memory budget, and their making.

use super::casters::CasterCluster;
use super::gpu::{
    AUX_HEADER_WORDS, IrregularUniform, JOB_CAPACITY, MAX_FACES, binning_words, cells_fitting,
    storage_buffer,
};
use super::{BlendedCrossing, GridCells, IrregularConfig, IrregularZBuffer, casters};
use crate::scene::scene_fingerprint;
use crate::technique::MaskContext;
use anyhow::{Result, bail};

/// The buffers of one frame size, scene, light shape, grid, sample count and
/// whether the marks hold optical depths.
pub(super) struct Buffers {
    pub(super) key: (u32, u32, u64, usize, GridCells, u32, bool),
    pub(super) uniform: wgpu::Buffer,
    /// Counts, offsets and prefix-sum partials (`cells` of irregular.wgsl).
    pub(super) binning: wgpu::Buffer,
    pub(super) grid: GridCells,
    pub(super) samples: wgpu::Buffer,
    pub(super) marks: wgpu::Buffer,
    pub(super) triangles: wgpu::Buffer,
    /// The opaque casters' triangles, which lead `triangles`.
    pub(super) opaque_triangles: u32,
    /// The caster list's clusters, culled each frame (`cull`).
    pub(super) clusters: Vec<CasterCluster>,
    /// The frame's kept ranges of the list (`kept_ranges` of
    /// irregular.wgsl): a pair of words per cluster at most.
    pub(super) kept_ranges: wgpu::Buffer,
    /// Jobs the job list holds.
    pub(super) job_capacity: u32,
    pub(super) aux: wgpu::Buffer,
    /// The per-face bounds and grids, copied from `aux` (`face_boxes`).
    pub(super) face_boxes: wgpu::Buffer,
    /// The job passes' indirect arguments, copied from `aux`: the opaque
    /// casters', then the see-through ones'.
    pub(super) job_args: wgpu::Buffer,
    pub(super) bind_group: wgpu::BindGroup,
}

/// The job list's capacity: four jobs per caster triangle and face, or twice
/// the jobs a frame asked for where they overflowed, within [`JOB_CAPACITY`].
fn job_capacity(triangles: u64, faces: u64, asked: u64) -> u64 {
    (4 * triangles * faces)
        .max(2 * asked)
        .clamp(JOB_CAPACITY.0, JOB_CAPACITY.1)
}

/// Bytes of the kept ranges of a list of `clusters` clusters: two words
/// each, at least one range's.
fn kept_range_bytes(clusters: usize) -> u64 {
    clusters.max(1) as u64 * 8
}

/// Bytes of the samples: for one sample per pixel, 16 a pixel sorted by
/// cell (the origin kept) and 16 a pixel staged before the sort; for
/// sub-pixel samples 4 a sample (the id alone), in whole 16-byte words
/// (`samples` is an array of `vec4u`).
fn sample_bytes(pixels: u64, pixel_samples: u32) -> u64 {
    match pixel_samples {
        0 | 1 => pixels * 32,
        n => (pixels * n as u64 * 4).next_multiple_of(16),
    }
}

/// The marks' bytes: a word per pixel, then under `transmit` a word of
/// optical depth per sample.
fn mark_bytes(pixels: u64, config: &IrregularConfig) -> u64 {
    let depths = match config.blended {
        BlendedCrossing::Transmit => pixels * config.pixel_samples.max(1) as u64,
        _ => 0,
    };
    (pixels + depths) * 4
}

impl IrregularZBuffer {
    /// The buffers for this frame, made again where the frame size, the
    /// scene, the light's face count or the grid changed, or where the last
    /// frame's jobs overflowed the list; sizes past the device's
    /// storage-buffer limit or the memory budget are an error.
    pub(super) fn ensure_buffers(&mut self, ctx: &MaskContext, faces: usize) -> Result<&Buffers> {
        let (w, h) = (ctx.frame.width(), ctx.frame.height());
        let pixels = w as u64 * h as u64;
        let limit = ctx.gpu.device.limits().max_storage_buffer_binding_size;
        let samples = pixels * self.config.pixel_samples as u64;
        let grid = self.config.grid_cells(samples, faces, cells_fitting(limit));
        let key = (
            w,
            h,
            scene_fingerprint(ctx.scene),
            faces,
            grid,
            self.config.pixel_samples,
            self.config.blended == BlendedCrossing::Transmit,
        );
        let asked = self.stats.jobs as u64;
        if self
            .buffers
            .as_ref()
            .is_some_and(|b| b.key == key && asked <= b.job_capacity as u64)
        {
            return Ok(self.buffers.as_ref().expect("checked"));
        }
        let asked = if self.buffers.as_ref().is_some_and(|b| b.key == key) {
            asked
        } else {
            0
        };
        self.buffers = None;
        let gpu = ctx.gpu;
        let casters = casters::caster_triangles(ctx.scene);
        let triangles = &casters.triangles;
        let capacity = job_capacity(triangles.len() as u64, faces as u64, asked);
        let sizes = [
            (
                "cell counts and offsets (grid)",
                binning_words(grid.cells) * 4,
            ),
            ("samples", sample_bytes(pixels, self.config.pixel_samples)),
            ("caster triangles", triangles.len() as u64 * 64),
            ("caster ranges", kept_range_bytes(casters.clusters.len())),
            ("job list", (AUX_HEADER_WORDS + 4 * capacity) * 4),
            ("marks", mark_bytes(pixels, &self.config)),
        ];
        for (what, bytes) in sizes {
            if bytes > limit {
                bail!(
                    "irregular: the {what} take {:.1} MiB, more than the device's largest storage buffer ({:.1} MiB); choose a smaller grid, frame or pixel_samples",
                    bytes as f64 / (1u64 << 20) as f64,
                    limit as f64 / (1u64 << 20) as f64
                );
            }
        }
        let total = sizes.iter().map(|s| s.1).sum::<u64>();
        gpu.check_allocation("irregular (grid, samples, casters)", (1, 1, 1), total)?;
        let uniform = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("irregular uniform"),
            size: std::mem::size_of::<IrregularUniform>() as u64,
            usage: crate::gpu::uniform_usage(gpu),
            mapped_at_creation: false,
        });
        let binning = storage_buffer(gpu, "irregular cell counts and offsets", sizes[0].1);
        let samples = storage_buffer(gpu, "irregular samples", sizes[1].1);
        let marks = storage_buffer(gpu, "irregular marks", sizes[5].1);
        let triangle_buffer = storage_buffer(gpu, "irregular casters", sizes[2].1);
        gpu.queue
            .write_buffer(&triangle_buffer, 0, bytemuck::cast_slice(triangles));
        let kept_ranges = storage_buffer(gpu, "irregular kept casters", sizes[3].1);
        let aux = storage_buffer(gpu, "irregular header and job list", sizes[4].1);
        let face_boxes = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("irregular face bounds"),
            size: (2 * MAX_FACES * 16) as u64,
            usage: crate::gpu::uniform_usage(gpu),
            mapped_at_creation: false,
        });
        let buffers = [
            &uniform,
            &binning,
            &samples,
            &marks,
            &triangle_buffer,
            &aux,
            &face_boxes,
            &kept_ranges,
        ];
        let entries: Vec<_> = (0u32..)
            .zip(buffers)
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("irregular"),
            layout: &self.shared.layout,
            entries: &entries,
        });
        Ok(self.buffers.insert(Buffers {
            key,
            uniform,
            binning,
            grid,
            samples,
            marks,
            triangles: triangle_buffer,
            opaque_triangles: casters.opaque,
            clusters: casters.clusters,
            kept_ranges,
            job_capacity: capacity as u32,
            aux,
            face_boxes,
            job_args: storage_buffer(gpu, "irregular job dispatch", 24),
            bind_group,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The job list holds four jobs per triangle and face; after a frame
    /// whose jobs overflowed it, twice what that frame asked for; always
    /// within its bounds.
    #[test]
    fn the_job_list_grows_after_an_overflow() {
        assert_eq!(job_capacity(10, 1, 0), JOB_CAPACITY.0);
        assert_eq!(job_capacity(100_000, 6, 0), 2_400_000);
        assert_eq!(job_capacity(100_000, 6, 1_500_000), 3_000_000);
        assert_eq!(job_capacity(100_000, 6, 1 << 30), JOB_CAPACITY.1);
    }
}
