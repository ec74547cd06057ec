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

    /// Bytes the buffer holds.
    pub fn size(&self) -> u64 {
        self.buffer.size()
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
