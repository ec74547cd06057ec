//! Triangle clusters: a mesh's triangles reordered into spatially compact
//! runs, each with its own bounds, so that a view that sees part of a large
//! mesh (a shadow cascade over the near end of a merged landscape tile)
//! draws only the clusters it sees — the per-cluster culling of meshlet
//! renderers, done once on the CPU.

use super::{Aabb, Mesh};
use glam::Vec3;

/// The most triangles in one cluster: small enough that a cascade a few
/// metres wide skips most of a merged tile, large enough that a draw call
/// per cluster costs nothing next to its triangles.
pub const CLUSTER_TRIANGLES: usize = 2048;

/// One run of a mesh's reordered triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cluster {
    /// First index into [`Clustered::indices`] (a multiple of 3).
    pub first_index: u32,
    pub index_count: u32,
    /// Mesh-space bounds of the run's vertices.
    pub bounds: Aabb,
}

/// A mesh's index list reordered into clusters.
pub struct Clustered {
    pub indices: Vec<u32>,
    pub clusters: Vec<Cluster>,
}

/// Splits `mesh`'s triangles into clusters of at most `max_triangles`: the
/// triangle set is halved at the median centroid along the longest axis of
/// its centroids' bounds until each half is small enough (a median-split
/// kd-tree's leaves, in tree order). A mesh no larger than one cluster keeps
/// its order.
pub fn clustered(mesh: &Mesh, max_triangles: usize) -> Clustered {
    let max_triangles = max_triangles.max(1);
    let triangle = |t: usize| {
        let i = &mesh.indices[3 * t..3 * t + 3];
        [i[0], i[1], i[2]]
    };
    let corners = |t: usize| triangle(t).map(|i| mesh.positions[i as usize]);
    let centroid = |t: usize| {
        let [a, b, c] = corners(t);
        (a + b + c) / 3.0
    };
    let mut order: Vec<usize> = (0..mesh.indices.len() / 3).collect();
    let mut runs = vec![];
    split(&mut order, 0, max_triangles, &centroid, &mut runs);
    let mut indices = Vec::with_capacity(mesh.indices.len());
    let clusters = runs
        .into_iter()
        .map(|(start, len)| {
            let first_index = indices.len() as u32;
            let mut bounds = Aabb::from_points(corners(order[start]));
            for &t in &order[start..start + len] {
                indices.extend(triangle(t));
                bounds = corners(t).into_iter().fold(bounds, Aabb::with_point);
            }
            Cluster {
                first_index,
                index_count: 3 * len as u32,
                bounds,
            }
        })
        .collect();
    Clustered { indices, clusters }
}

/// Median-splits `order` (triangles from `start` on in the full order)
/// until each run holds at most `max` triangles; pushes (start, length).
fn split(
    order: &mut [usize],
    start: usize,
    max: usize,
    centroid: &impl Fn(usize) -> Vec3,
    runs: &mut Vec<(usize, usize)>,
) {
    if order.len() <= max {
        if !order.is_empty() {
            runs.push((start, order.len()));
        }
        return;
    }
    let extent = Aabb::from_points(order.iter().map(|&t| centroid(t))).size();
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        centroid(a)[axis].total_cmp(&centroid(b)[axis])
    });
    let (low, high) = order.split_at_mut(mid);
    split(low, start, max, centroid, runs);
    split(high, start + mid, max, centroid, runs);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;

    #[test]
    fn clusters_cover_every_triangle_once_and_bound_their_own() {
        // A 64 × 64-cell grid: 8192 triangles over [−1, 1]², in clusters of
        // at most 1000 → 16 runs of 512 (halving 8192 four times).
        let mesh = shapes::plane(2.0, 2.0, 64);
        let c = clustered(&mesh, 1000);
        assert_eq!(c.clusters.len(), 16);
        assert!(c.clusters.iter().all(|k| k.index_count == 3 * 512));
        let mut original: Vec<[u32; 3]> =
            mesh.indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
        let mut reordered: Vec<[u32; 3]> =
            c.indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
        original.sort();
        reordered.sort();
        assert_eq!(original, reordered, "a permutation of whole triangles");
        for k in &c.clusters {
            let tris = &c.indices[k.first_index as usize..(k.first_index + k.index_count) as usize];
            let b = Aabb::from_points(tris.iter().map(|&i| mesh.positions[i as usize]));
            assert_eq!(b, k.bounds);
            // 512 triangles of a 64 × 64 grid: a 16 × 16-cell square, a
            // quarter of the side (1/32 of the area), up to a cell of slack.
            let s = k.bounds.size();
            assert!(s.x <= 0.5 + 1e-5 && s.z <= 0.5 + 1e-5, "compact: {s}");
        }
    }

    #[test]
    fn a_mesh_of_one_cluster_keeps_its_order() {
        let mesh = shapes::plane(2.0, 2.0, 4);
        let c = clustered(&mesh, CLUSTER_TRIANGLES);
        assert_eq!(c.indices, mesh.indices);
        assert_eq!(c.clusters.len(), 1);
        assert_eq!(c.clusters[0].bounds, mesh.bounds());
    }
}
