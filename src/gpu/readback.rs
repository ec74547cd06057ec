//! Reading GPU buffers back without waiting: a `MAP_READ` buffer that is
//! copied into by a frame's commands, mapped asynchronously after the
//! submission, and read once the map has completed (checked with a
//! non-blocking poll), so a frame never stalls for its statistics.

use super::GpuContext;
use anyhow::Result;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

const FREE: u8 = 0;
const COPIED: u8 = 1;
const MAPPING: u8 = 2;
const MAPPED: u8 = 3;
const FAILED: u8 = 4;

pub struct AsyncReadback {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
}

impl AsyncReadback {
    pub fn new(device: &wgpu::Device, label: &str, size: u64) -> AsyncReadback {
        AsyncReadback {
            buffer: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(FREE)),
        }
    }

    /// The buffer to copy into, when it is not waiting for an earlier read
    /// (then this frame's copy is skipped). Marks it as copied into.
    pub fn target(&self) -> Option<&wgpu::Buffer> {
        self.state
            .compare_exchange(FREE, COPIED, Ordering::AcqRel, Ordering::Acquire)
            .ok()
            .map(|_| &self.buffer)
    }

    /// After the copy's submission: asks for the buffer to be mapped.
    pub fn request(&self) {
        if self
            .state
            .compare_exchange(COPIED, MAPPING, Ordering::AcqRel, Ordering::Acquire)
            .is_err()
        {
            return;
        }
        let state = self.state.clone();
        self.buffer
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
    }

    /// The contents once the map has completed; `None` while it has not
    /// (polls the device without waiting).
    pub fn try_read(&self, gpu: &GpuContext) -> Result<Option<Vec<u8>>> {
        if self.state.load(Ordering::Acquire) == MAPPING {
            gpu.device.poll(wgpu::PollType::Poll)?;
        }
        match self.state.load(Ordering::Acquire) {
            MAPPED => {
                let data = self.buffer.slice(..).get_mapped_range()?.to_vec();
                self.buffer.unmap();
                self.state.store(FREE, Ordering::Release);
                Ok(Some(data))
            }
            FAILED => {
                self.state.store(FREE, Ordering::Release);
                Ok(None)
            }
            _ => Ok(None),
        }
    }
}

/// A result the GPU computes for the CPU's set-up of the same frame (SDSM's
/// depth bounds, a virtual map's page marks): this frame's, waited for (one
/// stall; measurements), or the latest that has arrived, copied back a
/// frame late without a stall (the viewer).
pub struct FrameFeedback {
    staging: wgpu::Buffer,
    late: AsyncReadback,
    pending: bool,
    latest: Option<Vec<u8>>,
}

impl FrameFeedback {
    pub fn new(device: &wgpu::Device, label: &str, size: u64) -> FrameFeedback {
        FrameFeedback {
            staging: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            late: AsyncReadback::new(device, label, size),
            pending: false,
            latest: None,
        }
    }

    /// Bytes it can hold.
    pub fn size(&self) -> u64 {
        self.staging.size()
    }

    /// The encoder to record the GPU work into when waiting for it (`wait`:
    /// its own, submitted by [`Self::collect`]); `None`: the frame's.
    pub fn own_encoder(gpu: &GpuContext, wait: bool) -> Option<wgpu::CommandEncoder> {
        wait.then(|| gpu.device.create_command_encoder(&Default::default()))
    }

    /// Copies the first `len` bytes of `source` back: with `own` (from
    /// [`Self::own_encoder`]) submits it and waits, and returns these bytes;
    /// else copies within the frame's `encoder` (read after
    /// [`Self::after_frame`]) and returns the latest bytes that have arrived.
    pub fn collect(
        &mut self,
        gpu: &GpuContext,
        own: Option<wgpu::CommandEncoder>,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::Buffer,
        len: u64,
    ) -> Result<Option<Vec<u8>>> {
        if let Some(mut own) = own {
            own.copy_buffer_to_buffer(source, 0, &self.staging, 0, len);
            gpu.queue.submit([own.finish()]);
            let bytes = gpu.read_buffer(&self.staging)?;
            self.latest = Some(bytes[..len as usize].to_vec());
        } else {
            if let Some(bytes) = self.late.try_read(gpu)? {
                self.latest = Some(bytes[..len as usize].to_vec());
            }
            if let Some(target) = self.late.target() {
                encoder.copy_buffer_to_buffer(source, 0, target, 0, len);
                self.pending = true;
            }
        }
        Ok(self.latest.clone())
    }

    /// After the frame's submission: asks for the frame-late copy.
    pub fn after_frame(&mut self) {
        if std::mem::take(&mut self.pending) {
            self.late.request();
        }
    }
}
