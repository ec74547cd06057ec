//! Frame timing: CPU wall times per stage and GPU timestamps read back
//! without stalling (`gpu::TimestampPairs`).

use crate::gpu::{GpuContext, Stamps, TimestampPairs};
use anyhow::Result;
use serde::Serialize;

/// CPU wall times of one frame's stages, milliseconds. With
/// [`super::RenderSettings::stage_waits`] each stage waits for the GPU so
/// that the times are the stage's own; otherwise the lighting time holds
/// the GPU work still running at the end of the frame.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameTimings {
    pub prepass_ms: f64,
    pub masks_ms: f64,
    pub lighting_ms: f64,
    pub total_ms: f64,
    /// GPU time per pass from timestamp queries, when measured: this frame's
    /// with stage waits, else the newest frame's whose timestamps arrived.
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

/// Three pairs of timestamps per frame: around the prepass, mask and
/// lighting work (bracketing each, so time between submissions, such as
/// CPU-side technique work, is not counted as GPU time), read back
/// without a stall.
pub struct GpuTimer(TimestampPairs);

/// The pairs of [`GpuTimer`].
pub const PREPASS: u32 = 0;
pub const MASKS: u32 = 1;
pub const LIGHTING: u32 = 2;

impl GpuTimer {
    pub fn new(device: &wgpu::Device) -> GpuTimer {
        GpuTimer(TimestampPairs::new(device, "pass timestamps", 3))
    }

    /// Starts a frame; returns the timestamps to write into.
    pub fn begin_frame(&mut self) -> Stamps {
        self.0.begin_frame()
    }

    /// Resolves the frame's timestamps for reading back.
    pub fn resolve(&mut self, enc: &mut wgpu::CommandEncoder) {
        self.0.resolve(enc);
    }

    /// After submission: asks for this frame's timestamps to be read.
    pub fn request_readback(&mut self) {
        self.0.request_readback();
    }

    /// The newest frame's GPU times whose readback has completed, without
    /// waiting for the GPU.
    pub fn latest(&mut self, gpu: &GpuContext) -> Result<Option<GpuPassTimes>> {
        Ok(self.0.latest(gpu)?.map(|t| GpuPassTimes {
            prepass_ms: t[PREPASS as usize],
            masks_ms: t[MASKS as usize],
            lighting_ms: t[LIGHTING as usize],
            total_ms: t.iter().sum(),
        }))
    }
}
