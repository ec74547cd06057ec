//! The BVH (obvhs' compressed wide BVH) over a scene's shadow casters,
//! shared by everything that traces shadow rays: the reference technique,
//! `compare` and the viewer's heatmap.

use super::{Scene, scene_fingerprint};
use glam::Vec3;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use std::sync::{Arc, Mutex, Weak};
use std::time::Instant;

/// BVH over the world-space triangles of a scene's shadow casters.
pub struct CasterBvh {
    key: u64,
    bvh: Option<CwBvh>,
    triangles: Vec<Triangle>,
    pub build_ms: f64,
}

impl CasterBvh {
    pub fn build(scene: &Scene) -> CasterBvh {
        let t = Instant::now();
        let key = scene_fingerprint(scene);
        let triangles: Vec<Triangle> = scene
            .world_triangles(|o| o.casts_shadow && !o.shadow_plane)
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
        CasterBvh {
            key,
            bvh,
            triangles,
            build_ms: t.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// The BVH of `scene`'s casters, shared between all users while alive;
    /// `held` is returned as is when it still matches the scene.
    pub fn for_scene(scene: &Scene, held: Option<&Arc<CasterBvh>>) -> Arc<CasterBvh> {
        static CACHE: Mutex<Vec<(u64, Weak<CasterBvh>)>> = Mutex::new(Vec::new());
        let key = scene_fingerprint(scene);
        if let Some(h) = held.filter(|h| h.key == key) {
            return h.clone();
        }
        let mut cache = CACHE.lock().unwrap_or_else(|e| e.into_inner());
        cache.retain(|(_, w)| w.strong_count() > 0);
        if let Some(b) = cache
            .iter()
            .find(|(k, _)| *k == key)
            .and_then(|(_, w)| w.upgrade())
        {
            return b;
        }
        let b = Arc::new(CasterBvh::build(scene));
        cache.push((key, Arc::downgrade(&b)));
        b
    }

    /// True when nothing blocks the segment from `origin` along `dir` (unit)
    /// up to distance `tmax`.
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        let Some(bvh) = &self.bvh else { return true };
        // obvhs' traversal misses hits when a direction component is −0.0
        // (a sun along (0, −1, 0) gives the ray (−0, 1, −0)): use +0.0.
        let dir = Vec3::select(dir.cmpeq(Vec3::ZERO), Vec3::ZERO, dir);
        let ray = Ray::new(origin.into(), dir.into(), 0.0, tmax);
        bvh.ray_traverse_miss(ray, |r, id| {
            self.triangles[bvh.primitive_indices[id] as usize].intersect(r)
        })
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Memory of the triangles, BVH nodes and index table.
    pub fn bytes(&self) -> u64 {
        let nodes = self.bvh.as_ref().map_or(0, |b| {
            b.nodes.len() * std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>()
                + b.primitive_indices.len() * 4
        });
        (self.triangles.len() * std::mem::size_of::<Triangle>() + nodes) as u64
    }
}
