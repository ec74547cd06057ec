//! Frame timing: CPU wall times per stage and GPU timestamps read back
//! without stalling (two readback slots, mapped asynchronously).

use crate::gpu::{AsyncReadback, GpuContext};
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

/// Six timestamps per frame: start and end of the prepass, mask and lighting
/// work (bracketing each, so time between submissions, such as CPU-side
/// technique work, is not counted as GPU time), read back through two
/// [`AsyncReadback`] slots so that no frame waits for them.
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    /// Readback slots and the frame whose timestamps each holds.
    slots: [(AsyncReadback, u64); 2],
    /// The slot this frame's timestamps are copied into (none while both
    /// are still being read).
    current: Option<usize>,
    frame: u64,
    latest: Option<(u64, GpuPassTimes)>,
}

impl GpuTimer {
    pub fn new(device: &wgpu::Device) -> GpuTimer {
        let slot = || (AsyncReadback::new(device, "timestamp readback", 48), 0);
        GpuTimer {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 6,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 48,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            slots: [slot(), slot()],
            current: None,
            frame: 0,
            latest: None,
        }
    }

    /// Starts a frame; returns the query set to write timestamps into.
    pub fn begin_frame(&mut self) -> wgpu::QuerySet {
        self.frame += 1;
        self.current = None;
        self.queries.clone()
    }

    /// Resolves the six timestamps into a free readback slot.
    pub fn resolve(&mut self, enc: &mut wgpu::CommandEncoder) {
        for (i, (slot, frame)) in self.slots.iter_mut().enumerate() {
            if let Some(buffer) = slot.target() {
                enc.resolve_query_set(&self.queries, 0..6, &self.resolve, 0);
                enc.copy_buffer_to_buffer(&self.resolve, 0, buffer, 0, 48);
                *frame = self.frame;
                self.current = Some(i);
                return;
            }
        }
    }

    /// After submission: asks for this frame's slot to be mapped.
    pub fn request_readback(&mut self) {
        if let Some(i) = self.current.take() {
            self.slots[i].0.request();
        }
    }

    /// The newest frame's GPU times whose readback has completed, without
    /// waiting for the GPU.
    pub fn latest(&mut self, gpu: &GpuContext) -> Result<Option<GpuPassTimes>> {
        let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
        for (slot, frame) in &self.slots {
            let Some(data) = slot.try_read(gpu)? else {
                continue;
            };
            let t: &[u64] = bytemuck::cast_slice(&data);
            let d = |a: usize, b: usize| t[b].saturating_sub(t[a]) as f64 * period;
            let times = GpuPassTimes {
                prepass_ms: d(0, 1),
                masks_ms: d(2, 3),
                lighting_ms: d(4, 5),
                total_ms: d(0, 1) + d(2, 3) + d(4, 5),
            };
            if self.latest.is_none_or(|(f, _)| f < *frame) {
                self.latest = Some((*frame, times));
            }
        }
        Ok(self.latest.map(|(_, t)| t))
    }
}
