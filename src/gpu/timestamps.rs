//! GPU time of bracketed stretches of command recording: pairs of
//! timestamps written inside encoders, resolved each frame into one of two
//! [`AsyncReadback`] slots, so that no frame waits for them; the newest
//! frame's times whose readback has completed are read without a stall.

use super::{AsyncReadback, GpuContext};
use anyhow::Result;

pub struct TimestampPairs {
    pairs: u32,
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    /// Readback slots and the frame whose timestamps each holds.
    slots: [(AsyncReadback, u64); 2],
    /// The slot this frame's timestamps are copied into (none while both
    /// are still being read).
    current: Option<usize>,
    frame: u64,
    latest: Option<(u64, Vec<f64>)>,
}

impl TimestampPairs {
    /// Room for `pairs` (start, end) timestamps a frame. Needs
    /// `TIMESTAMP_QUERY_INSIDE_ENCODERS` (`GpuContext::timestamps`).
    pub fn new(device: &wgpu::Device, label: &str, pairs: u32) -> TimestampPairs {
        let bytes = pairs as u64 * 16;
        let slot = || (AsyncReadback::new(device, label, bytes), 0);
        TimestampPairs {
            pairs,
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count: pairs * 2,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            slots: [slot(), slot()],
            current: None,
            frame: 0,
            latest: None,
        }
    }

    pub fn pairs(&self) -> u32 {
        self.pairs
    }

    /// Starts a frame; returns where to write its timestamps.
    pub fn begin_frame(&mut self) -> Stamps {
        self.frame += 1;
        self.current = None;
        Stamps(self.queries.clone())
    }

    /// Resolves this frame's timestamps into a free readback slot (none
    /// free: this frame's are skipped).
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let bytes = self.pairs as u64 * 16;
        for (i, (slot, frame)) in self.slots.iter_mut().enumerate() {
            if let Some(buffer) = slot.target() {
                encoder.resolve_query_set(&self.queries, 0..self.pairs * 2, &self.resolve, 0);
                encoder.copy_buffer_to_buffer(&self.resolve, 0, buffer, 0, bytes);
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

    /// Milliseconds of each pair of the newest frame whose readback has
    /// completed, without waiting for the GPU.
    pub fn latest(&mut self, gpu: &GpuContext) -> Result<Option<&[f64]>> {
        let period = gpu.queue.get_timestamp_period() as f64 * 1e-6;
        for (slot, frame) in &self.slots {
            let Some(data) = slot.try_read(gpu)? else {
                continue;
            };
            let t: &[u64] = bytemuck::cast_slice(&data);
            let times = t
                .chunks_exact(2)
                .map(|p| p[1].saturating_sub(p[0]) as f64 * period)
                .collect();
            if self.latest.as_ref().is_none_or(|(f, _)| f < frame) {
                self.latest = Some((*frame, times));
            }
        }
        Ok(self.latest.as_ref().map(|(_, t)| t.as_slice()))
    }
}

/// Writes one frame's timestamps of a [`TimestampPairs`].
pub struct Stamps(wgpu::QuerySet);

impl Stamps {
    /// Writes the start (`end` false) or end of pair `pair` into `encoder`.
    pub fn stamp(&self, encoder: &mut wgpu::CommandEncoder, pair: u32, end: bool) {
        encoder.write_timestamp(&self.0, pair * 2 + end as u32);
    }
}

/// The GPU time of one stretch of each frame's work, per pair and summed
/// over its pairs (one per light, say): a [`TimestampPairs`] made on first
/// use and remade when the pair count changes; read a frame late, without
/// a stall.
pub struct SectionTimer {
    label: &'static str,
    pairs: Option<TimestampPairs>,
    /// Each pair's time of the newest frame whose timestamps arrived, ms.
    last_pairs_ms: Vec<f64>,
}

impl SectionTimer {
    pub fn new(label: &'static str) -> SectionTimer {
        SectionTimer {
            label,
            pairs: None,
            last_pairs_ms: vec![],
        }
    }

    /// The newest frame's time whose timestamps arrived, over all its
    /// pairs, ms.
    pub fn last_ms(&self) -> f64 {
        self.last_pairs_ms.iter().sum()
    }

    /// Each pair's time of the newest frame whose timestamps arrived, ms
    /// (empty before any arrived).
    pub fn last_pairs_ms(&self) -> &[f64] {
        &self.last_pairs_ms
    }

    /// Starts a frame of `pairs` stretches; `None` without timestamps.
    pub fn begin(&mut self, gpu: &GpuContext, pairs: u32) -> Option<Stamps> {
        if !gpu.timestamps {
            return None;
        }
        if self.pairs.as_ref().is_none_or(|p| p.pairs() != pairs) {
            self.pairs = Some(TimestampPairs::new(&gpu.device, self.label, pairs));
        }
        self.pairs.as_mut().map(TimestampPairs::begin_frame)
    }

    /// Records `work` into `encoder` as the frame's one stretch, between a
    /// pair of timestamps (none without timestamp support), and resolves
    /// them into `encoder`.
    pub fn time<R>(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        work: impl FnOnce(&mut wgpu::CommandEncoder) -> R,
    ) -> R {
        let stamps = self.begin(gpu, 1);
        if let Some(s) = &stamps {
            s.stamp(encoder, 0, false);
        }
        let result = work(encoder);
        if let Some(s) = &stamps {
            s.stamp(encoder, 0, true);
            self.resolve(encoder);
        }
        result
    }

    /// Forgets the time: this frame has no such stretch.
    pub fn clear(&mut self) {
        self.pairs = None;
        self.last_pairs_ms.clear();
    }

    /// After the frame's stretches are recorded, into the encoder that
    /// holds the last of them.
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
                self.last_pairs_ms = t.to_vec();
            }
        }
        Ok(())
    }
}
