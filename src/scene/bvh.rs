//! The acceleration structure over a scene's shadow casters, shared by
//! everything that traces shadow rays: the reference technique, `compare`
//! and the viewer's heatmap. Two kernels: obvhs' compressed wide BVH (pure
//! Rust, always there) and Embree 3 (loaded at run time when installed).

use super::{Scene, scene_fingerprint};
use glam::Vec3;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use std::sync::{Arc, Mutex, Weak};
use std::time::Instant;

/// Which ray-tracing kernel answers shadow rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TraceKernel {
    /// obvhs' CWBVH with its Möller–Trumbore test.
    Obvhs,
    /// Embree 3's `rtcOccluded1`, robust mode, high build quality.
    Embree,
}

enum Tracer {
    Obvhs {
        bvh: Option<CwBvh>,
        triangles: Vec<Triangle>,
    },
    Embree(super::embree::EmbreeScene),
}

/// The acceleration structure over the world-space triangles of a scene's
/// shadow casters.
pub struct CasterBvh {
    key: (u64, TraceKernel),
    tracer: Tracer,
    pub build_ms: f64,
}

impl CasterBvh {
    /// The structure of `scene`'s casters for `kernel`; errors when Embree
    /// is asked for and cannot be loaded or built.
    pub fn build(scene: &Scene, kernel: TraceKernel) -> Result<CasterBvh, String> {
        let t = Instant::now();
        let key = (scene_fingerprint(scene), kernel);
        let world = scene.world_triangles(|o| o.casts_shadow && !o.shadow_plane);
        let tracer = match kernel {
            TraceKernel::Embree => Tracer::Embree(super::embree::EmbreeScene::build(&world)?),
            TraceKernel::Obvhs => {
                let triangles: Vec<Triangle> = world
                    .into_iter()
                    .map(|[a, b, c]| Triangle {
                        v0: a.into(),
                        v1: b.into(),
                        v2: c.into(),
                    })
                    .collect();
                let bvh = (!triangles.is_empty()).then(|| {
                    obvhs::cwbvh::builder::build_cwbvh_from_tris(
                        &triangles,
                        obvhs::BvhBuildParams::medium_build(),
                        &mut std::time::Duration::default(),
                    )
                });
                Tracer::Obvhs { bvh, triangles }
            }
        };
        Ok(CasterBvh {
            key,
            tracer,
            build_ms: t.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// The structure of `scene`'s casters for `kernel`, shared between all
    /// users while alive; `held` is returned as is when it still matches.
    pub fn for_scene(
        scene: &Scene,
        held: Option<&Arc<CasterBvh>>,
        kernel: TraceKernel,
    ) -> Result<Arc<CasterBvh>, String> {
        type Cache = Vec<((u64, TraceKernel), Weak<CasterBvh>)>;
        static CACHE: Mutex<Cache> = Mutex::new(Vec::new());
        let key = (scene_fingerprint(scene), kernel);
        if let Some(h) = held.filter(|h| h.key == key) {
            return Ok(h.clone());
        }
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        cache.retain(|(_, w)| w.strong_count() > 0);
        if let Some(b) = cache
            .iter()
            .find(|(k, _)| *k == key)
            .and_then(|(_, w)| w.upgrade())
        {
            return Ok(b);
        }
        let b = Arc::new(CasterBvh::build(scene, kernel)?);
        cache.push((key, Arc::downgrade(&b)));
        Ok(b)
    }

    pub fn kernel(&self) -> TraceKernel {
        self.key.1
    }

    /// True when nothing blocks the segment from `origin` along `dir` (unit)
    /// up to distance `tmax`.
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        match &self.tracer {
            Tracer::Embree(e) => e.unoccluded(origin, dir, tmax),
            Tracer::Obvhs { bvh: None, .. } => true,
            Tracer::Obvhs {
                bvh: Some(bvh),
                triangles,
            } => {
                // obvhs' traversal misses hits when a direction component is
                // −0.0 (a sun along (0, −1, 0) gives the ray (−0, 1, −0)): use +0.0.
                let dir = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::ZERO, dir);
                let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
                bvh.ray_traverse_miss(ray, |r, id| {
                    triangles[bvh.primitive_indices[id] as usize].intersect(r)
                })
            }
        }
    }

    /// Memory of the triangles, BVH nodes and index table (obvhs), or of
    /// Embree's vertex and index buffers.
    pub fn bytes(&self) -> u64 {
        match &self.tracer {
            Tracer::Embree(e) => e.bytes(),
            Tracer::Obvhs { bvh, triangles } => {
                let nodes = bvh.as_ref().map_or(0, |b| {
                    b.nodes.len() * std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>()
                        + b.primitive_indices.len() * 4
                });
                (triangles.len() * std::mem::size_of::<Triangle>() + nodes) as u64
            }
        }
    }
}
