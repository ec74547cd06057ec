//! The irregular z-buffer's GPU side: its uniform, bind-group layout and
//! pipelines (shared per device), and the buffers one instance owns.

use crate::frame::MASK_FORMAT;
use crate::gpu::GpuContext;
use crate::technique::params::Choice;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, UVec4, Vec4};
use std::sync::OnceLock;

/// Cube faces of a local light's grid; a directional light has one face.
pub const MAX_FACES: usize = 6;
/// Words of the `aux` buffer's header (`AUX_JOB_LIST` of irregular.wgsl):
/// counters, the list-length histogram, the per-face bounds, the longest list.
pub const AUX_HEADER_WORDS: u64 = 112;
/// The header's counters and histogram (`AUX_*` of irregular.wgsl).
pub const AUX_SAMPLES: usize = 0;
pub const AUX_PAIRS: usize = 1;
pub const AUX_TESTS: usize = 2;
pub const AUX_JOBS: usize = 3;
/// The job pass's indirect dispatch arguments.
pub const AUX_DISPATCH: usize = 4;
pub const AUX_OVERFLOW: usize = 7;
pub const AUX_HISTOGRAM: usize = 8;
/// Per face, 4 words of its samples' bounds, copied to the `face_boxes`
/// uniform after the bounds pass.
pub const AUX_BOUNDS: usize = 40;
pub const HISTOGRAM_BINS: usize = 32;
pub const AUX_LONGEST: usize = 64;
/// The see-through casters' jobs and their indirect dispatch arguments.
pub const AUX_SEE_THROUGH_JOBS: usize = 65;
pub const AUX_SEE_THROUGH_DISPATCH: usize = 66;
/// Per face, 4 words of its grid (side, first cell, cells used, 0), copied
/// to the `face_boxes` uniform after the bounds.
pub const AUX_LAYOUT: usize = 88;
/// Samples of one job of a large triangle (`JOB_SAMPLES`), checked against
/// the WGSL.
#[cfg(test)]
pub const JOB_SAMPLES: u32 = 1024;
/// Pixels along a row that one invocation of the bounds pass visits
/// (`BOUNDS_RUN`).
pub const BOUNDS_RUN: u32 = 8;
/// Counts summed by one workgroup of the prefix sum (`SCAN_BLOCK`).
pub const SCAN_BLOCK: u64 = 1024;
/// Threads per workgroup of every compute pass.
pub const WORKGROUP: u32 = 64;
/// The job list's capacity: four jobs per caster triangle and face, or
/// twice what the last frame asked for where that overflowed, within these
/// bounds (4 words each: 1 to 64 MiB).
pub const JOB_CAPACITY: (u64, u64) = (1 << 16, 1 << 22);

/// Words of the binning buffer for `cells` cells: the counts, the
/// offsets with their total, and the prefix sum's block partials.
pub fn binning_words(cells: u64) -> u64 {
    2 * cells + 1 + cells.div_ceil(SCAN_BLOCK)
}

/// The most cells whose [`binning_words`] fit in `bytes` (rounding the
/// partials up: a cell or so under the exact bound).
pub fn cells_fitting(bytes: u64) -> u64 {
    (bytes / 4).saturating_sub(2) * SCAN_BLOCK / (2 * SCAN_BLOCK + 1)
}

/// The family's WGSL: its `blended_casters` choice's constants
/// (`BLENDED_*`) and the reference's least footprint cosine, the interface
/// and triangle passes, then the samples and their binning.
fn module_source() -> String {
    let min_cosine = crate::technique::raytraced::MIN_FOOTPRINT_COSINE;
    [
        super::BlendedCrossing::wgsl_constants("BLENDED").as_str(),
        &format!("const MIN_FOOTPRINT_COSINE: f32 = {min_cosine:?};"),
        &format!("const BOUNDS_RUN: u32 = {BOUNDS_RUN}u;"),
        include_str!("irregular.wgsl"),
        include_str!("samples.wgsl"),
    ]
    .join("\n")
}

/// The variants of the test passes (pipeline constants `SEE_THROUGH` and
/// `TRANSMIT` of irregular.wgsl), each over its own run of the caster
/// list. llvmpipe slows a loop by the code it holds even where no lane
/// runs it, so the opaque casters' tests carry no see-through code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TestPass {
    /// The opaque casters, which block every ray they meet.
    Opaque,
    /// The cut-out and translucent casters, their opacity maps read.
    SeeThrough,
    /// The same, translucent crossings summed as optical depth
    /// (`blended_casters=transmit`).
    Transmit,
}

/// The full-screen passes over the pixels' samples after their bounds,
/// built per sample count (`SUB_PIXEL` of samples.wgsl: the centre alone
/// carries no sub-pixel code).
#[derive(Clone, Copy, Debug)]
pub enum SamplePass {
    Count,
    Scatter,
}

impl SamplePass {
    fn entry(self) -> &'static str {
        match self {
            SamplePass::Count => "fs_count",
            SamplePass::Scatter => "fs_scatter",
        }
    }
}

/// The passes that test samples against triangles: a thread per triangle,
/// and a workgroup per job of a large one.
#[derive(Clone, Copy, Debug)]
pub enum TestStage {
    Triangles,
    Jobs,
}

impl TestStage {
    fn entry(self) -> &'static str {
        match self {
            TestStage::Triangles => "cs_triangles",
            TestStage::Jobs => "cs_jobs",
        }
    }
}

/// A pipeline constant's value for a flag.
fn flag(on: bool) -> f64 {
    if on { 1.0 } else { 0.0 }
}

/// `Irregular` of irregular.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct IrregularUniform {
    pub views: [Mat4; MAX_FACES],
    pub light: Vec4,
    pub grid: UVec4,
    pub work: UVec4,
    pub offset: Vec4,
    pub pixel: UVec4,
    pub cone: Vec4,
    pub kept: UVec4,
}

/// The family's layout, module and pipelines, shared per device; the
/// variants of the sample and test passes are built when first asked for
/// and kept here (not only in the device's cache, whose least recently
/// used pipelines give way when a report cycles through every technique).
pub struct IrregularShared {
    pub layout: wgpu::BindGroupLayout,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    pub mask: wgpu::RenderPipeline,
    pub scan_blocks: wgpu::ComputePipeline,
    pub scan_partials: wgpu::ComputePipeline,
    pub scan_add: wgpu::ComputePipeline,
    pub job_dispatch: wgpu::ComputePipeline,
    pub face_layout: wgpu::ComputePipeline,
    /// Indexed by [sub-pixel].
    bounds_passes: [OnceLock<wgpu::ComputePipeline>; 2],
    /// Indexed by [sub-pixel][`SamplePass`].
    sample_passes: [[OnceLock<wgpu::RenderPipeline>; 2]; 2],
    /// Indexed by [sub-pixel][`TestStage`][`TestPass`].
    test_passes: [[[OnceLock<wgpu::ComputePipeline>; 3]; 2]; 2],
}

impl IrregularShared {
    pub fn new(gpu: &GpuContext) -> IrregularShared {
        let device = &gpu.device;
        let stages = wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let storage = |binding, read_only| crate::gpu::storage_entry(binding, stages, read_only);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("irregular"),
            entries: &[
                crate::gpu::uniform_entry(gpu, 0, stages, false),
                storage(1, false),
                storage(2, false),
                storage(3, false),
                storage(4, true),
                storage(5, false),
                crate::gpu::uniform_entry(gpu, 6, stages, false),
                storage(7, true),
            ],
        });
        let module = crate::frame::technique_shader(gpu, "irregular", &[&module_source()]);
        let pipeline_layout = super::super::pipeline_layout(gpu, "irregular", &layout);
        IrregularShared {
            mask: fullscreen(
                gpu,
                &pipeline_layout,
                &module,
                "fs_mask",
                wgpu::ColorWrites::RED,
                &[],
            ),
            scan_blocks: compute(gpu, &pipeline_layout, &module, "cs_scan_blocks", &[]),
            scan_partials: compute(gpu, &pipeline_layout, &module, "cs_scan_partials", &[]),
            scan_add: compute(gpu, &pipeline_layout, &module, "cs_scan_add", &[]),
            job_dispatch: compute(gpu, &pipeline_layout, &module, "cs_job_dispatch", &[]),
            face_layout: compute(gpu, &pipeline_layout, &module, "cs_face_layout", &[]),
            layout,
            module,
            pipeline_layout,
            bounds_passes: Default::default(),
            sample_passes: Default::default(),
            test_passes: Default::default(),
        }
    }

    /// `pass` for pixels of one sample or, with `sub_pixel`, several.
    pub fn sample_pass(
        &self,
        gpu: &GpuContext,
        pass: SamplePass,
        sub_pixel: bool,
    ) -> &wgpu::RenderPipeline {
        self.sample_passes[sub_pixel as usize][pass as usize].get_or_init(|| {
            let constants = [("SUB_PIXEL", flag(sub_pixel))];
            fullscreen(
                gpu,
                &self.pipeline_layout,
                &self.module,
                pass.entry(),
                wgpu::ColorWrites::empty(),
                &constants,
            )
        })
    }

    /// The bounds pass (a thread per run of [`BOUNDS_RUN`] pixels) for
    /// pixels of one sample or, with `sub_pixel`, several.
    pub fn bounds_pass(&self, gpu: &GpuContext, sub_pixel: bool) -> &wgpu::ComputePipeline {
        self.bounds_passes[sub_pixel as usize].get_or_init(|| {
            let constants = [("SUB_PIXEL", flag(sub_pixel))];
            compute(
                gpu,
                &self.pipeline_layout,
                &self.module,
                "cs_bounds",
                &constants,
            )
        })
    }

    /// `stage` over the casters of `test`, for pixels of one sample or,
    /// with `sub_pixel`, several.
    pub fn test_pass(
        &self,
        gpu: &GpuContext,
        stage: TestStage,
        test: TestPass,
        sub_pixel: bool,
    ) -> &wgpu::ComputePipeline {
        self.test_passes[sub_pixel as usize][stage as usize][test as usize].get_or_init(|| {
            let constants = [
                ("SUB_PIXEL", flag(sub_pixel)),
                ("SEE_THROUGH", flag(test != TestPass::Opaque)),
                ("TRANSMIT", flag(test == TestPass::Transmit)),
            ];
            compute(
                gpu,
                &self.pipeline_layout,
                &self.module,
                stage.entry(),
                &constants,
            )
        })
    }
}

/// The full-screen pass `fs` of the family's module, writing `write_mask`
/// of the mask (the sample passes write none of it), from the device's
/// cache.
fn fullscreen(
    gpu: &GpuContext,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    fs: &str,
    write_mask: wgpu::ColorWrites,
    constants: &[(&str, f64)],
) -> wgpu::RenderPipeline {
    super::super::fullscreen_pipeline(
        gpu,
        &format!("irregular {fs}"),
        layout,
        super::super::FragmentEntry {
            module,
            entry: fs,
            constants,
        },
        &[Some(wgpu::ColorTargetState {
            format: MASK_FORMAT,
            blend: None,
            write_mask,
        })],
        Some(super::super::frame_depth_read(gpu, Default::default())),
    )
}

/// The compute pass `entry` of the family's module.
fn compute(
    gpu: &GpuContext,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    gpu.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(layout),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        })
}

/// The (x, y) workgroups that cover `n` invocations of [`WORKGROUP`]
/// threads within the per-dimension limit (the shaders index y·x·64 + x).
pub fn workgroups_for(n: u64) -> (u32, u32) {
    grid_of_workgroups(n.div_ceil(WORKGROUP as u64))
}

/// `groups` workgroups as (x, y) within the per-dimension limit, at least
/// one (the shaders index y·x + x, and skip what lies past their work).
pub fn grid_of_workgroups(groups: u64) -> (u32, u32) {
    let groups = groups.max(1);
    let x = groups.min(65535);
    (x as u32, groups.div_ceil(x) as u32)
}

/// A storage buffer of `size` bytes (at least 16).
pub fn storage_buffer(gpu: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16).next_multiple_of(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::INDIRECT,
        mapped_at_creation: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::wgsl_layout::{assert_consts_match, assert_struct_matches};

    fn source() -> String {
        crate::frame::technique_source(&[&module_source()])
    }

    /// `Irregular` and `CasterTriangle` of irregular.wgsl are laid out as
    /// the Rust structs, and the header's words are the ones read back.
    #[test]
    fn the_gpu_interface_matches_its_wgsl() {
        let source = source();
        assert_struct_matches(
            &source,
            "Irregular",
            crate::field_offsets!(IrregularUniform; views, light, grid, work, offset, pixel, cone, kept),
            std::mem::size_of::<IrregularUniform>(),
        );
        assert_struct_matches(
            &source,
            "CasterTriangle",
            crate::field_offsets!(super::super::casters::CasterTriangle; a, b, c, v),
            std::mem::size_of::<super::super::casters::CasterTriangle>(),
        );
        assert_consts_match(
            &source,
            &[
                ("AUX_SAMPLES", AUX_SAMPLES as u32),
                ("AUX_PAIRS", AUX_PAIRS as u32),
                ("AUX_TESTS", AUX_TESTS as u32),
                ("AUX_JOBS", AUX_JOBS as u32),
                ("AUX_DISPATCH", AUX_DISPATCH as u32),
                ("AUX_OVERFLOW", AUX_OVERFLOW as u32),
                ("AUX_HISTOGRAM", AUX_HISTOGRAM as u32),
                ("AUX_BOUNDS", AUX_BOUNDS as u32),
                ("HISTOGRAM_BINS", HISTOGRAM_BINS as u32),
                ("AUX_LONGEST", AUX_LONGEST as u32),
                ("AUX_SEE_THROUGH_JOBS", AUX_SEE_THROUGH_JOBS as u32),
                ("AUX_SEE_THROUGH_DISPATCH", AUX_SEE_THROUGH_DISPATCH as u32),
                ("AUX_LAYOUT", AUX_LAYOUT as u32),
                ("AUX_JOB_LIST", AUX_HEADER_WORDS as u32),
                ("WORKGROUP", WORKGROUP),
                ("JOB_SAMPLES", JOB_SAMPLES),
                ("SCAN_BLOCK", SCAN_BLOCK as u32),
            ],
        );
    }

    /// The cells that fit a buffer are the most whose binning words do.
    #[test]
    fn cells_fitting_inverts_binning_words() {
        for bytes in [1u64 << 20, 128 << 20, (128 << 20) + 12_345, 1 << 31] {
            let n = cells_fitting(bytes);
            assert!(binning_words(n) * 4 <= bytes, "{bytes}: {n}");
            assert!(binning_words(n + 2) * 4 > bytes, "{bytes}: {n}");
        }
    }

    #[test]
    fn workgroups_cover_every_invocation_within_the_limit() {
        assert_eq!(workgroups_for(0), (1, 1));
        assert_eq!(workgroups_for(64), (1, 1));
        assert_eq!(workgroups_for(65), (2, 1));
        let (x, y) = workgroups_for(6 * 1024 * 1024);
        assert!(x <= 65535 && x as u64 * y as u64 * 64 >= 6 * 1024 * 1024);
    }
}
