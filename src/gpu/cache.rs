//! Per-device caches: render and compute pipelines, bounded and keyed by
//! what changes them, and one shared set of resources (shader modules,
//! layouts, samplers) per technique family. Every light's technique
//! instance draws from them, so switching back to a technique or adding a
//! light compiles nothing, and a parameter sweep (one pipeline per depth
//! bias) evicts the least recently used pipeline instead of growing.

use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, MutexGuard};

/// Most pipelines one device keeps; past it the least recently used goes.
/// A frame needs far fewer (lighting variants per material kind, and each
/// light's technique passes), but `bench` and `report` interleave every
/// technique of a view frame by frame, and a bound below what they need
/// together evicts and compiles pipelines in every timed frame (on
/// llvmpipe, a compile takes longer than the frame).
pub const PIPELINE_CACHE_BOUND: usize = 512;

/// A compiled pipeline of either kind.
#[derive(Clone)]
enum Pipeline {
    Render(wgpu::RenderPipeline),
    Compute(wgpu::ComputePipeline),
}

#[derive(Default)]
struct CacheState {
    pipelines: HashMap<u64, (Pipeline, u64)>,
    shared: HashMap<TypeId, Arc<dyn Any + Send + Sync>>,
    /// Use counter for least-recently-used eviction.
    clock: u64,
    /// Pipelines created since the device was made.
    created: u64,
}

/// The caches of one device (held by [`super::GpuContext`]).
#[derive(Default)]
pub struct DeviceCache {
    state: Mutex<CacheState>,
}

fn hash_of(key: &impl Hash) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    key.hash(&mut h);
    h.finish()
}

impl DeviceCache {
    fn lock(&self) -> MutexGuard<'_, CacheState> {
        // A panic while holding the lock leaves maps that are still valid.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn pipeline(&self, owner: &str, key: &impl Hash, make: impl FnOnce() -> Pipeline) -> Pipeline {
        let k = hash_of(&(owner, key));
        {
            let mut s = self.lock();
            s.clock += 1;
            let now = s.clock;
            if let Some((p, used)) = s.pipelines.get_mut(&k) {
                *used = now;
                return p.clone();
            }
        }
        // Compile outside the lock: pipeline creation can take a while.
        let p = make();
        let mut s = self.lock();
        s.created += 1;
        while s.pipelines.len() >= PIPELINE_CACHE_BOUND {
            let oldest = s
                .pipelines
                .iter()
                .min_by_key(|(_, (_, used))| *used)
                .map(|(k, _)| *k)
                .expect("a full cache has an entry");
            s.pipelines.remove(&oldest);
        }
        let now = s.clock;
        s.pipelines.insert(k, (p.clone(), now));
        p
    }

    /// The render pipeline of `owner` (a pass's name) for `key`, made by
    /// `make` when the cache does not hold it. `key` must hold everything
    /// `make` reads that can differ between calls.
    pub fn render_pipeline(
        &self,
        owner: &str,
        key: &impl Hash,
        make: impl FnOnce() -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        match self.pipeline(owner, key, || Pipeline::Render(make())) {
            Pipeline::Render(p) => p,
            Pipeline::Compute(_) => unreachable!("owner '{owner}' keyed a compute pipeline"),
        }
    }

    /// [`Self::render_pipeline`] for compute pipelines.
    pub fn compute_pipeline(
        &self,
        owner: &str,
        key: &impl Hash,
        make: impl FnOnce() -> wgpu::ComputePipeline,
    ) -> wgpu::ComputePipeline {
        match self.pipeline(owner, key, || Pipeline::Compute(make())) {
            Pipeline::Compute(p) => p,
            Pipeline::Render(_) => unreachable!("owner '{owner}' keyed a render pipeline"),
        }
    }

    /// The one `T` of this device (a family's modules, layouts, samplers),
    /// made by `make` on first use.
    pub fn shared<T: Any + Send + Sync>(&self, make: impl FnOnce() -> T) -> Arc<T> {
        let id = TypeId::of::<T>();
        if let Some(v) = self.lock().shared.get(&id) {
            return v.clone().downcast::<T>().expect("keyed by its type");
        }
        let v = Arc::new(make());
        self.lock()
            .shared
            .entry(id)
            .or_insert_with(|| v.clone())
            .clone()
            .downcast::<T>()
            .expect("keyed by its type")
    }

    /// Pipelines created on this device so far (cache misses).
    pub fn pipelines_created(&self) -> u64 {
        self.lock().created
    }

    /// Pipelines the cache holds now (at most [`PIPELINE_CACHE_BOUND`]).
    pub fn pipelines_cached(&self) -> usize {
        self.lock().pipelines.len()
    }
}
