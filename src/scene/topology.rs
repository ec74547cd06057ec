//! Mesh topology shared by the techniques: vertices welded by position (so
//! that meshes split by normals or uvs are still seen as connected), and
//! whether a mesh bounds a solid.

use super::Mesh;
use glam::{DVec3, Vec3};
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

/// What a mesh encloses, for a depth pass that stores back faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolidKind {
    /// Open, inconsistently wound, wound inward or enclosing nothing.
    NotSolid,
    /// A solid whose every part is convex (each edge folds away from its
    /// neighbour's plane): it never shadows its own lit side.
    Convex,
    /// A solid with a concave edge somewhere: it can shadow itself.
    Concave,
}

impl Mesh {
    /// Bounds a solid: closed after welding (every edge run as often in one
    /// direction as in the other) and wound outward, with a volume (the
    /// signed volume Σ a·(b × c)/6 positive and not a rounding residue of the
    /// bounding box's). A double-sided sheet is closed but encloses nothing;
    /// a mesh wound inward has a negative volume. Only such a mesh's back
    /// faces are, seen from anywhere, behind its front faces. Convex when
    /// every edge is (a closed surface convex at every edge is convex in
    /// each connected part).
    pub fn solid_kind(&self) -> SolidKind {
        let welded = Welded::of(self);
        let triangles = welded.triangles(self);
        if triangles.is_empty() || unbalanced_edges(&triangles) > 0 {
            return SolidKind::NotSolid;
        }
        let p = |i: u32| welded.positions[i as usize].as_dvec3();
        let volume: f64 = triangles
            .iter()
            .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0)
            .sum();
        let extent = self.bounds().size().as_dvec3();
        let extent = extent.x.max(extent.y).max(extent.z);
        if volume <= 1e-9 * extent.powi(3) {
            SolidKind::NotSolid
        } else if concave_edges(&triangles, &p, 1e-6 * extent) > 0 {
            SolidKind::Concave
        } else {
            SolidKind::Convex
        }
    }
}

/// The edges of a closed, outward-wound surface (welded `triangles` over
/// positions `p`) where a triangle's neighbour rises more than `tolerance`
/// above its plane; an edge shared by more than two triangles counts.
fn concave_edges(triangles: &[[u32; 3]], p: &impl Fn(u32) -> DVec3, tolerance: f64) -> usize {
    let mut across: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(triangles.len() * 3);
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            across
                .entry((t[k], t[(k + 1) % 3]))
                .or_default()
                .push(i as u32);
        }
    }
    let mut concave = 0;
    for t in triangles {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            match across.get(&(v, u)).map(Vec::as_slice) {
                Some([twin]) => {
                    let w = triangles[*twin as usize]
                        .into_iter()
                        .find(|&w| w != u && w != v)
                        .expect("a welded triangle has three corners");
                    if normal.dot(p(w) - a) > tolerance {
                        concave += 1;
                    }
                }
                _ => concave += 1,
            }
        }
    }
    concave
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
        assert_eq!(cube.solid_kind(), SolidKind::Convex);
        let mut open = cube.clone();
        open.indices.truncate(open.indices.len() - 6);
        assert_eq!(
            open.solid_kind(),
            SolidKind::NotSolid,
            "a box without one side is open"
        );
        let mut inverted = cube.clone();
        for t in inverted.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        assert_eq!(inverted.solid_kind(), SolidKind::NotSolid, "wound inward");
        let mut double_sided = sheet();
        double_sided.indices.extend([0, 1, 2, 0, 2, 3]);
        assert_eq!(sheet().solid_kind(), SolidKind::NotSolid, "one-sided sheet");
        assert_eq!(
            double_sided.solid_kind(),
            SolidKind::NotSolid,
            "closed, but encloses nothing"
        );
    }

    #[test]
    fn spheres_boxes_and_cylinders_are_convex_a_torus_is_not() {
        assert_eq!(shapes::sphere(1.0, 12, 8).solid_kind(), SolidKind::Convex);
        // Its caps are fans of coplanar triangles: not concave.
        assert_eq!(
            shapes::cylinder(1.0, 2.0, 6).solid_kind(),
            SolidKind::Convex
        );
        assert_eq!(
            shapes::torus(1.0, 0.3, 16, 8).solid_kind(),
            SolidKind::Concave
        );
        // Two separate boxes are each convex.
        let mut two = shapes::cuboid(Vec3::ONE);
        let second = shapes::cuboid(Vec3::ONE);
        let base = two.positions.len() as u32;
        two.positions
            .extend(second.positions.iter().map(|p| *p + Vec3::X * 3.0));
        two.normals.extend(&second.normals);
        two.uvs.extend(&second.uvs);
        two.tangents.extend(&second.tangents);
        two.indices.extend(second.indices.iter().map(|i| i + base));
        assert_eq!(two.solid_kind(), SolidKind::Convex);
    }
}
