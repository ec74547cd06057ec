//! The acceleration structure over a scene's shadow casters, shared by
//! everything that traces shadow rays: the reference technique, `compare`
//! and the viewer's heatmap. Two kernels: obvhs' compressed wide BVH (pure
//! Rust, always there) and Embree 3 (loaded at run time when installed).

use super::opacity::{CasterOpacity, Transmittance};
use super::{Scene, scene_fingerprint};
use crate::clock::Instant;
use glam::Vec3;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use std::sync::{Arc, Mutex, Weak};

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
        opacity: Option<CasterOpacity>,
    },
    Embree(super::embree::EmbreeScene),
}

/// obvhs's `build_cwbvh_from_tris` with its medium-build parameters, less
/// its timer (std's `Instant`, which panics in the browser build): PLOC,
/// reinsertion, then the compressed wide BVH.
fn build_cwbvh(triangles: &[Triangle]) -> CwBvh {
    let config = obvhs::BvhBuildParams::medium_build();
    let mut bvh2 = obvhs::ploc::PlocBuilder::with_capacity(triangles.len()).build(
        config.ploc_search_distance,
        triangles,
        (0..triangles.len() as u32).collect(),
        config.sort_precision,
        config.search_depth_threshold,
    );
    obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(
        &mut bvh2,
        config.reinsertion_batch_ratio,
        None,
    );
    obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(
        &bvh2,
        config.max_prims_per_leaf.clamp(1, 3),
        true,
        false,
    )
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
        let casters = |o: &super::Object| o.casts_shadow && !o.shadow_plane;
        let world = scene.world_triangles(casters);
        let opacity = CasterOpacity::of(scene, casters);
        let tracer = match kernel {
            TraceKernel::Embree => {
                Tracer::Embree(super::embree::EmbreeScene::build(&world, opacity)?)
            }
            TraceKernel::Obvhs => {
                let triangles: Vec<Triangle> = world
                    .into_iter()
                    .map(|[a, b, c]| Triangle {
                        v0: a.into(),
                        v1: b.into(),
                        v2: c.into(),
                    })
                    .collect();
                let bvh = (!triangles.is_empty()).then(|| build_cwbvh(&triangles));
                Tracer::Obvhs {
                    bvh,
                    triangles,
                    opacity,
                }
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

    /// The light that reaches `origin` along `dir` (unit) from distance
    /// `tmax`: 1 when nothing blocks the segment, 0 when an opaque surface
    /// (or a cut-out where it is solid) does, the product of the
    /// translucent surfaces' transmittances otherwise.
    pub fn transmittance(&self, origin: Vec3, dir: Vec3, tmax: f32) -> f32 {
        match &self.tracer {
            Tracer::Embree(e) => e.transmittance(origin, dir, tmax),
            Tracer::Obvhs { bvh: None, .. } => 1.0,
            Tracer::Obvhs {
                bvh: Some(bvh),
                triangles,
                opacity,
            } => {
                // obvhs' traversal misses hits when a direction component is
                // −0.0 (a sun along (0, −1, 0) gives the ray (−0, 1, −0)): use +0.0.
                let dir = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::ZERO, dir);
                let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
                let mut light = Transmittance::default();
                let missed = bvh.ray_traverse_miss(ray, |r, id| {
                    let prim = bvh.primitive_indices[id] as usize;
                    let tri = &triangles[prim];
                    let t = tri.intersect(r);
                    match opacity {
                        Some(o) if t < r.tmax && o.is_see_through(prim) => {
                            let (u, v) = barycentric(tri, origin, dir);
                            if light.cross(o.crossing(prim, u, v)) {
                                t
                            } else {
                                f32::INFINITY
                            }
                        }
                        _ => t,
                    }
                });
                if missed { light.value } else { 0.0 }
            }
        }
    }

    /// Memory of the triangles, BVH nodes and index table (obvhs), or of
    /// Embree's vertex and index buffers.
    pub fn bytes(&self) -> u64 {
        match &self.tracer {
            Tracer::Embree(e) => e.bytes(),
            Tracer::Obvhs { bvh, triangles, .. } => {
                let nodes = bvh.as_ref().map_or(0, |b| {
                    b.nodes.len() * std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>()
                        + b.primitive_indices.len() * 4
                });
                (triangles.len() * std::mem::size_of::<Triangle>() + nodes) as u64
            }
        }
    }
}

/// The barycentric coordinates `(u, v)` of where the ray from `o` along `d`
/// meets the plane of `tri`: the point `(1 − u − v)·v0 + u·v1 + v·v2`
/// (Möller & Trumbore 1997).
fn barycentric(tri: &Triangle, o: Vec3, d: Vec3) -> (f32, f32) {
    let (v0, v1, v2) = (Vec3::from(tri.v0), Vec3::from(tri.v1), Vec3::from(tri.v2));
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    let s = o - v0;
    let q = s.cross(e1);
    (s.dot(p) / det, d.dot(q) / det)
}
