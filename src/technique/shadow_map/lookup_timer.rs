//! The `lookup_ms` counter: GPU time of the screen-space lookup of each map
//! sample, with the edge mask's min/max chain (part of the lookup's cost),
//! not the depth passes — the time the edge mask and the virtual page table
//! are meant to save, measured apart from the maps' rendering. Timestamps
//! inside the encoder, read back a frame late without a stall.

use crate::gpu::{GpuContext, Stamps, TimestampPairs};
use anyhow::Result;

#[derive(Default)]
pub struct LookupTimer {
    pairs: Option<TimestampPairs>,
    /// The newest frame's lookup time whose timestamps arrived, ms.
    pub last_ms: f64,
}

impl LookupTimer {
    /// Starts a frame of `samples` lookups; `None` without timestamps.
    pub fn begin(&mut self, gpu: &GpuContext, samples: u32) -> Option<Stamps> {
        if !gpu.timestamps {
            return None;
        }
        if self.pairs.as_ref().is_none_or(|p| p.pairs() != samples) {
            self.pairs = Some(TimestampPairs::new(
                &gpu.device,
                "shadow map lookup timestamps",
                samples,
            ));
        }
        self.pairs.as_mut().map(TimestampPairs::begin_frame)
    }

    /// After the frame's lookups are recorded.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(p) = &mut self.pairs {
            p.resolve(encoder);
        }
    }

    /// After the frame's submission: asks for its timestamps and takes the
    /// newest that have arrived.
    pub fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        if let Some(p) = &mut self.pairs {
            p.request_readback();
            if let Some(t) = p.latest(gpu)? {
                self.last_ms = t.iter().sum();
            }
        }
        Ok(())
    }
}
