//! The GPU time of each of the irregular z-buffer's passes (counters
//! `<pass>_ms`), where the adapter has timestamp queries: where a frame's
//! mask time goes.

use crate::gpu::{GpuContext, SectionTimer, Stamps};
use anyhow::Result;

/// The frame's passes, timed apart.
#[derive(Clone, Copy)]
pub enum Pass {
    /// The samples' bounds on each face.
    Bounds,
    /// Each cell's samples counted.
    Counts,
    /// The counts' prefix sum (three compute passes).
    PrefixSum,
    /// The samples written to their cells' runs.
    Scatter,
    /// A thread per caster triangle, and the job dispatch.
    Triangles,
    /// A workgroup per job of a large triangle.
    Jobs,
    /// The mask from the marks.
    MaskWrite,
}

impl Pass {
    const ALL: [Pass; 7] = [
        Pass::Bounds,
        Pass::Counts,
        Pass::PrefixSum,
        Pass::Scatter,
        Pass::Triangles,
        Pass::Jobs,
        Pass::MaskWrite,
    ];

    fn counter(self) -> &'static str {
        match self {
            Pass::Bounds => "bounds_ms",
            Pass::Counts => "counts_ms",
            Pass::PrefixSum => "prefix_sum_ms",
            Pass::Scatter => "scatter_ms",
            Pass::Triangles => "triangles_ms",
            Pass::Jobs => "jobs_ms",
            Pass::MaskWrite => "mask_write_ms",
        }
    }
}

/// A pair of timestamps per [`Pass`], read back a frame or two late.
pub struct PassTimer {
    timer: SectionTimer,
    /// Whether the adapter has timestamp queries (else no counters).
    timed: bool,
}

/// One frame's timestamps (none without timestamp queries).
pub struct FrameStamps(Option<Stamps>);

impl FrameStamps {
    /// Records `work` into `encoder` between the timestamps of `pass`.
    pub fn time<R>(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pass: Pass,
        work: impl FnOnce(&mut wgpu::CommandEncoder) -> R,
    ) -> R {
        if let Some(s) = &self.0 {
            s.stamp(encoder, pass as u32, false);
        }
        let result = work(encoder);
        if let Some(s) = &self.0 {
            s.stamp(encoder, pass as u32, true);
        }
        result
    }
}

impl PassTimer {
    pub fn new(gpu: &GpuContext) -> PassTimer {
        PassTimer {
            timer: SectionTimer::new("irregular pass timestamps"),
            timed: gpu.timestamps,
        }
    }

    pub fn begin_frame(&mut self, gpu: &GpuContext) -> FrameStamps {
        FrameStamps(self.timer.begin(gpu, Pass::ALL.len() as u32))
    }

    /// After the frame's passes, into the encoder that holds the last.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        self.timer.resolve(encoder);
    }

    /// After the frame's submission: asks for its times and takes the
    /// newest that have arrived.
    pub fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        self.timer.after_frame(gpu)
    }

    /// `<pass>_ms` of each pass (0 until a frame's times arrive), none
    /// without timestamp queries.
    pub fn counters(&self) -> Vec<(&'static str, f64)> {
        if !self.timed {
            return vec![];
        }
        let ms = self.timer.last_pairs_ms();
        Pass::ALL
            .iter()
            .map(|&p| (p.counter(), ms.get(p as usize).copied().unwrap_or(0.0)))
            .collect()
    }
}
