//! Frame timing: CPU wall times per stage and GPU timestamps read back
//! without stalling (two readback buffers, mapped asynchronously).

use crate::gpu::GpuContext;
use anyhow::Result;
use serde::Serialize;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

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
/// technique work, is not counted as GPU time).
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    slots: [ReadbackSlot; 2],
    /// The slot this frame's timestamps are copied into (none while both
    /// are still being mapped).
    current: Option<usize>,
    frame: u64,
    latest: Option<(u64, GpuPassTimes)>,
}

const SLOT_FREE: u8 = 0;
const SLOT_PENDING: u8 = 1;
const SLOT_MAPPED: u8 = 2;
const SLOT_FAILED: u8 = 3;

struct ReadbackSlot {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// The frame whose timestamps the buffer holds.
    frame: u64,
}

impl GpuTimer {
    pub fn new(device: &wgpu::Device) -> GpuTimer {
        let slot = || ReadbackSlot {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: 48,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(SLOT_FREE)),
            frame: 0,
        };
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

    /// Starts a frame: picks a free readback slot; returns the query set.
    pub fn begin_frame(&mut self) -> wgpu::QuerySet {
        self.frame += 1;
        self.current = self
            .slots
            .iter()
            .position(|s| s.state.load(Ordering::Acquire) == SLOT_FREE);
        self.queries.clone()
    }

    /// Resolves the six timestamps into this frame's readback slot.
    pub fn resolve(&mut self, enc: &mut wgpu::CommandEncoder) {
        if let Some(i) = self.current {
            enc.resolve_query_set(&self.queries, 0..6, &self.resolve, 0);
            enc.copy_buffer_to_buffer(&self.resolve, 0, &self.slots[i].buffer, 0, 48);
        }
    }

    /// After submission: asks for this frame's slot to be mapped.
    pub fn request_readback(&mut self) {
        let Some(i) = self.current.take() else {
            return;
        };
        let slot = &mut self.slots[i];
        slot.frame = self.frame;
        slot.state.store(SLOT_PENDING, Ordering::Release);
        let state = slot.state.clone();
        slot.buffer
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                state.store(
                    if r.is_ok() { SLOT_MAPPED } else { SLOT_FAILED },
                    Ordering::Release,
                );
            });
    }

    /// The newest frame's GPU times whose readback has completed, without
    /// waiting for the GPU.
    pub fn latest(&mut self, gpu: &GpuContext) -> Result<Option<GpuPassTimes>> {
        gpu.device.poll(wgpu::PollType::Poll)?;
        let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
        for slot in &self.slots {
            match slot.state.load(Ordering::Acquire) {
                SLOT_MAPPED => {
                    let t: Vec<u64> = bytemuck::cast_slice::<u8, u64>(
                        &slot.buffer.slice(..).get_mapped_range()?,
                    )
                    .to_vec();
                    slot.buffer.unmap();
                    slot.state.store(SLOT_FREE, Ordering::Release);
                    let d = |a: usize, b: usize| t[b].saturating_sub(t[a]) as f64 * period;
                    let times = GpuPassTimes {
                        prepass_ms: d(0, 1),
                        masks_ms: d(2, 3),
                        lighting_ms: d(4, 5),
                        total_ms: d(0, 1) + d(2, 3) + d(4, 5),
                    };
                    if self.latest.is_none_or(|(f, _)| f < slot.frame) {
                        self.latest = Some((slot.frame, times));
                    }
                }
                SLOT_FAILED => {
                    slot.state.store(SLOT_FREE, Ordering::Release);
                }
                _ => {}
            }
        }
        Ok(self.latest.map(|(_, t)| t))
    }
}
