//! Hardware-independent cost: pipeline-statistics queries around every
//! render and compute pass of a frame, summed per stage (prepass, masks,
//! lighting). Invocation counts say how much work a technique asks for
//! whatever rasterizer runs it; a CPU rasterizer's times rank techniques as
//! a CPU does, and a GPU's otherwise.
//!
//! Passes are opened through [`GpuContext::render_pass`] and
//! [`GpuContext::compute_pass`]: while a frame is counted
//! ([`GpuContext::count_work`]), each gets its own query, ended when the
//! pass is dropped.

use super::GpuContext;
use anyhow::{Result, bail};
use serde::Serialize;
use std::sync::Mutex;

/// The stage a pass's work counts to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkStage {
    Prepass,
    Masks,
    Lighting,
}

/// Invocation counts of one stage of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageWork {
    pub vertex_invocations: u64,
    pub fragment_invocations: u64,
    pub compute_invocations: u64,
    /// Primitives leaving the clipper (what reaches the rasterizer).
    pub clipper_primitives: u64,
}

/// Invocation counts of one frame, per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameWork {
    pub prepass: StageWork,
    pub masks: StageWork,
    pub lighting: StageWork,
}

impl FrameWork {
    /// Fragment invocations of the whole frame.
    pub fn fragment_invocations(&self) -> u64 {
        self.prepass.fragment_invocations
            + self.masks.fragment_invocations
            + self.lighting.fragment_invocations
    }
}

/// The statistics each query records, in the order wgpu writes them
/// (ascending bit order of [`wgpu::PipelineStatisticsTypes`]).
const STATISTICS: wgpu::PipelineStatisticsTypes =
    wgpu::PipelineStatisticsTypes::VERTEX_SHADER_INVOCATIONS
        .union(wgpu::PipelineStatisticsTypes::CLIPPER_PRIMITIVES_OUT)
        .union(wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS)
        .union(wgpu::PipelineStatisticsTypes::COMPUTE_SHADER_INVOCATIONS);
const VALUES: usize = 4;

/// Most passes one counted frame may open (cube maps of area samples open
/// hundreds); past it the frame's count is an error, never a partial sum.
pub const MAX_COUNTED_PASSES: u32 = 4096;

struct Counting {
    /// The thread whose frame is counted: passes other threads open at the
    /// same time (tests share a device) are not.
    thread: std::thread::ThreadId,
    set: wgpu::QuerySet,
    /// The stage of each query taken so far.
    stages: Vec<WorkStage>,
    current: WorkStage,
    overflowed: bool,
}

/// The counter of one device: idle, or counting one thread's frame (one
/// at a time: `exclusive` is held while counting).
#[derive(Default)]
pub struct WorkCounter {
    state: Mutex<Option<Counting>>,
    exclusive: Mutex<()>,
}

impl WorkCounter {
    /// Runs `f` on the frame being counted by this thread, if any.
    fn on_mine<T>(&self, f: impl FnOnce(&mut Counting) -> T) -> Option<T> {
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        state
            .as_mut()
            .filter(|c| c.thread == std::thread::current().id())
            .map(f)
    }

    /// The next query of the frame being counted, for the current stage.
    fn take(&self) -> Option<(wgpu::QuerySet, u32)> {
        self.on_mine(Counting::next).flatten()
    }
}

impl Counting {
    fn next(&mut self) -> Option<(wgpu::QuerySet, u32)> {
        let c = self;
        if c.stages.len() as u32 >= MAX_COUNTED_PASSES {
            c.overflowed = true;
            return None;
        }
        c.stages.push(c.current);
        Some((c.set.clone(), c.stages.len() as u32 - 1))
    }
}

/// A pass that can hold a pipeline-statistics query.
pub trait StatisticsPass {
    fn begin_statistics(&mut self, set: &wgpu::QuerySet, index: u32);
    fn end_statistics(&mut self);
}

impl StatisticsPass for wgpu::RenderPass<'_> {
    fn begin_statistics(&mut self, set: &wgpu::QuerySet, index: u32) {
        self.begin_pipeline_statistics_query(set, index);
    }
    fn end_statistics(&mut self) {
        self.end_pipeline_statistics_query();
    }
}

impl StatisticsPass for wgpu::ComputePass<'_> {
    fn begin_statistics(&mut self, set: &wgpu::QuerySet, index: u32) {
        self.begin_pipeline_statistics_query(set, index);
    }
    fn end_statistics(&mut self) {
        self.end_pipeline_statistics_query();
    }
}

/// A pass whose work is counted while it is open (the query ends when it
/// is dropped).
pub struct Counted<P: StatisticsPass> {
    pass: P,
    counting: bool,
}

pub type CountedRenderPass<'e> = Counted<wgpu::RenderPass<'e>>;
pub type CountedComputePass<'e> = Counted<wgpu::ComputePass<'e>>;

impl<P: StatisticsPass> Counted<P> {
    /// Opens this thread's next query on `pass` when its frame is counted.
    fn new(mut pass: P, counter: &WorkCounter) -> Counted<P> {
        let query = counter.take();
        if let Some((set, i)) = &query {
            pass.begin_statistics(set, *i);
        }
        Counted {
            pass,
            counting: query.is_some(),
        }
    }
}

impl<P: StatisticsPass> std::ops::Deref for Counted<P> {
    type Target = P;
    fn deref(&self) -> &P {
        &self.pass
    }
}

impl<P: StatisticsPass> std::ops::DerefMut for Counted<P> {
    fn deref_mut(&mut self) -> &mut P {
        &mut self.pass
    }
}

impl<P: StatisticsPass> Drop for Counted<P> {
    fn drop(&mut self) {
        if self.counting {
            self.pass.end_statistics();
        }
    }
}

impl GpuContext {
    /// Opens a render pass, counted while a frame is counted.
    pub fn render_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        desc: &wgpu::RenderPassDescriptor,
    ) -> CountedRenderPass<'e> {
        Counted::new(encoder.begin_render_pass(desc), &self.work)
    }

    /// Opens a compute pass, counted while a frame is counted.
    pub fn compute_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        desc: &wgpu::ComputePassDescriptor,
    ) -> CountedComputePass<'e> {
        Counted::new(encoder.begin_compute_pass(desc), &self.work)
    }

    /// Whether this thread's frame is being counted.
    pub fn counting_work(&self) -> bool {
        self.work.on_mine(|_| ()).is_some()
    }

    /// The stage this thread's passes opened from now on count to.
    pub fn set_work_stage(&self, stage: WorkStage) {
        self.work.on_mine(|c| c.current = stage);
    }

    /// Counts the work of the passes `frame` records and submits, per
    /// stage; an error where the adapter has no pipeline-statistics queries
    /// or the frame opens more than [`MAX_COUNTED_PASSES`] passes.
    pub fn count_work(&self, frame: impl FnOnce() -> Result<()>) -> Result<FrameWork> {
        if !self.pipeline_statistics {
            bail!(
                "{}: no pipeline-statistics queries (PIPELINE_STATISTICS_QUERY); work cannot be counted",
                self.info.name
            );
        }
        let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("work"),
            ty: wgpu::QueryType::PipelineStatistics(STATISTICS),
            count: MAX_COUNTED_PASSES,
        });
        let _one_at_a_time = self
            .work
            .exclusive
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        *self.work.state.lock().unwrap_or_else(|e| e.into_inner()) = Some(Counting {
            thread: std::thread::current().id(),
            set,
            stages: vec![],
            current: WorkStage::Prepass,
            overflowed: false,
        });
        let recorded = frame();
        let counting = self
            .work
            .state
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .expect("counting until here");
        recorded?;
        if counting.overflowed {
            bail!(
                "the frame opened more than {MAX_COUNTED_PASSES} passes; its work was not counted"
            );
        }
        let queries = counting.stages.len() as u32;
        let mut work = FrameWork::default();
        if queries == 0 {
            return Ok(work);
        }
        let bytes = queries as u64 * (VALUES * 8) as u64;
        let resolve = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("work resolve"),
            size: bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("work read"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.resolve_query_set(&counting.set, 0..queries, &resolve, 0);
        enc.copy_buffer_to_buffer(&resolve, 0, &read, 0, bytes);
        self.queue.submit([enc.finish()]);
        let values: Vec<u64> = bytemuck::pod_collect_to_vec(&self.read_buffer(&read)?);
        for (stage, v) in counting.stages.iter().zip(values.chunks_exact(VALUES)) {
            let s = match stage {
                WorkStage::Prepass => &mut work.prepass,
                WorkStage::Masks => &mut work.masks,
                WorkStage::Lighting => &mut work.lighting,
            };
            s.vertex_invocations += v[0];
            s.clipper_primitives += v[1];
            s.fragment_invocations += v[2];
            s.compute_invocations += v[3];
        }
        Ok(work)
    }
}
