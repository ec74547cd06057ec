//! Mesh topology shared by the techniques: vertices welded by position (so
//! that meshes split by normals or uvs are still seen as connected), and
//! whether a mesh bounds a solid.

use super::Mesh;
use glam::Vec3;
use std::collections::HashMap;

/// Vertices welded by position: the first vertex with a given position
/// (−0 = +0) stands for all.
pub struct Welded {
    /// The first occurrence of each distinct position, in mesh order.
    pub positions: Vec<Vec3>,
    /// For each vertex of the mesh, its welded index.
    pub remap: Vec<u32>,
}

impl Welded {
    pub fn of(mesh: &Mesh) -> Welded {
        let key = |p: Vec3| p.to_array().map(|c| (c + 0.0).to_bits());
        let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.positions.len());
        let mut positions = vec![];
        let remap = mesh
            .positions
            .iter()
            .map(|&p| {
                *first.entry(key(p)).or_insert_with(|| {
                    positions.push(p);
                    positions.len() as u32 - 1
                })
            })
            .collect();
        Welded { positions, remap }
    }

    /// The mesh's triangles over welded vertices, without those that weld
    /// to a line or a point.
    pub fn triangles(&self, mesh: &Mesh) -> Vec<[u32; 3]> {
        mesh.indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]].map(|i| self.remap[i as usize]))
            .filter(|w| w[0] != w[1] && w[1] != w[2] && w[2] != w[0])
            .collect()
    }
}

/// The edges of welded `triangles` run more often one way than the other
/// (open, inconsistently wound or an odd fin): 0 for an oriented closed
/// surface.
pub fn unbalanced_edges(triangles: &[[u32; 3]]) -> usize {
    let mut balance: HashMap<(u32, u32), i32> = HashMap::with_capacity(triangles.len() * 2);
    for t in triangles {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            *balance.entry((u.min(v), u.max(v))).or_default() += if u < v { 1 } else { -1 };
        }
    }
    balance.values().filter(|&&b| b != 0).count()
}

impl Mesh {
    /// Bounds a solid: closed after welding (every edge run as often in one
    /// direction as in the other) and wound outward, with a volume (the
    /// signed volume Σ a·(b × c)/6 positive and not a rounding residue of the
    /// bounding box's). A double-sided sheet is closed but encloses nothing;
    /// a mesh wound inward has a negative volume. Only such a mesh's back
    /// faces are, seen from anywhere, behind its front faces.
    pub fn bounds_solid(&self) -> bool {
        let welded = Welded::of(self);
        let triangles = welded.triangles(self);
        if triangles.is_empty() || unbalanced_edges(&triangles) > 0 {
            return false;
        }
        let p = |i: u32| welded.positions[i as usize].as_dvec3();
        let volume: f64 = triangles
            .iter()
            .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0)
            .sum();
        let extent = self.bounds().size().as_dvec3();
        volume > 1e-9 * extent.x.max(extent.y).max(extent.z).powi(3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;

    fn sheet() -> Mesh {
        Mesh {
            name: "sheet".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z],
            indices: vec![0, 2, 1, 0, 3, 2],
            ..Default::default()
        }
    }

    #[test]
    fn a_box_bounds_a_solid_and_an_open_or_flat_or_inverted_one_does_not() {
        let cube = shapes::cuboid(Vec3::ONE);
        assert!(cube.bounds_solid());
        let mut open = cube.clone();
        open.indices.truncate(open.indices.len() - 6);
        assert!(!open.bounds_solid(), "a box without one side is open");
        let mut inverted = cube.clone();
        for t in inverted.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert!(!inverted.bounds_solid(), "wound inward");
        let mut double_sided = sheet();
        double_sided.indices.extend([0, 1, 2, 0, 2, 3]);
        assert!(!sheet().bounds_solid(), "one-sided sheet");
        assert!(!double_sided.bounds_solid(), "closed, but encloses nothing");
    }
}
