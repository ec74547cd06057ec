//! Mesh adjacency for shadow volumes: vertices welded by position (so that
//! meshes split by normals or uvs are still closed), per-face planes and an
//! edge table. Each edge record holds two vertices and up to two face uses;
//! an edge shared by more than two faces (non-manifold) is split into
//! several records, which is exact because an edge's silhouette
//! multiplicity is a sum over its faces (see [`Edge::multiplicity`]).

use crate::scene::Mesh;
use crate::scene::topology::{Welded, unbalanced_edges};
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// No face (an open edge's second use).
pub const NO_FACE: u32 = u32::MAX;

/// An edge `a → b` (`a < b`) and up to two faces that use it, each encoded
/// as `face << 1 | reversed`, where `reversed` means the face's winding
/// runs `b → a`; [`NO_FACE`] when absent. The GPU reads the same layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct Edge {
    pub a: u32,
    pub b: u32,
    pub faces: [u32; 2],
}

impl Edge {
    /// The edge's multiplicity: Σ over its faces of `weight(face)` times +1
    /// when the face runs `a → b`, −1 when it runs `b → a`. With weight 1
    /// for lit faces and 0 for the others it is the silhouette multiplicity:
    /// a closed, consistently wound edge gives 0 when both or neither face
    /// is lit and ±1 on the silhouette, an open edge of a lit face ±1 (an
    /// open edge counts as a silhouette). The side quad is extruded |m|
    /// times along `a → b` when m > 0, `b → a` when m < 0.
    pub fn multiplicity(&self, weight: impl Fn(u32) -> i32) -> i32 {
        self.faces
            .iter()
            .filter(|&&f| f != NO_FACE)
            .map(|&f| if f & 1 == 0 { 1 } else { -1 } * weight(f >> 1))
            .sum()
    }

    /// The largest |multiplicity| that weights in {0, 1} can give.
    pub fn max_multiplicity(&self) -> u32 {
        match self.faces {
            [f, NO_FACE] | [NO_FACE, f] if f != NO_FACE => 1,
            [f, g] if (f & 1) == (g & 1) => 2,
            _ => 1,
        }
    }
}

/// Welded triangles, their planes and the edge table of one mesh.
#[derive(Clone, Debug, Default)]
pub struct Adjacency {
    /// The first occurrence of each distinct position, in mesh order.
    pub positions: Vec<Vec3>,
    /// Triangles over welded vertices; triangles that weld to a line or a
    /// point are dropped.
    pub triangles: Vec<[u32; 3]>,
    /// Plane of each triangle, `(n, −n·a)` with `n = (b − a) × (c − a)`
    /// normalised, shared by all faces of a flat region:
    /// `plane · (L, 1) > 0` when a point light at L sees its front.
    pub planes: Vec<Vec4>,
    pub edges: Vec<Edge>,
    /// Edges used by one face.
    pub open_edges: usize,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Two-face edges that both faces run in the same direction.
    pub inconsistent_edges: usize,
    /// Edges run more often one way than the other (open, inconsistent or
    /// an odd fin): where the lit faces' boundary is not a closed surface.
    pub unbalanced_edges: usize,
    pub degenerate_triangles: usize,
}

impl Adjacency {
    /// Closed (an oriented closed surface, possibly non-manifold, such as
    /// two boxes sharing an edge or a double-sided sheet): every edge is run
    /// as often in one direction as in the other. Silhouette volumes with
    /// multiplicities are then exact.
    pub fn is_closed(&self) -> bool {
        self.unbalanced_edges == 0
    }

    /// One line for logs: triangles, edges and what keeps the mesh open.
    pub fn summary(&self) -> String {
        format!(
            "{} triangles, {} edges: {} open, {} non-manifold, {} inconsistently wound, {} degenerate triangles dropped: {}",
            self.triangles.len(),
            self.edges.len(),
            self.open_edges,
            self.non_manifold_edges,
            self.inconsistent_edges,
            self.degenerate_triangles,
            if self.is_closed() {
                "closed"
            } else {
                "not closed"
            }
        )
    }

    /// Index count of the largest side-quad set any lighting can give.
    pub fn max_side_indices(&self) -> usize {
        self.edges
            .iter()
            .map(|e| 6 * e.max_multiplicity() as usize)
            .sum()
    }

    pub fn of(mesh: &Mesh) -> Adjacency {
        let welded = Welded::of(mesh);
        let triangles = welded.triangles(mesh);
        let degenerate_triangles = mesh.indices.len() / 3 - triangles.len();
        let positions = welded.positions;
        let planes = triangles
            .par_iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let n = (b - a).cross(c - a);
                n.extend(-n.dot(a))
            })
            .collect();
        // Edge uses sorted by their (min, max) vertex pair.
        let mut uses: Vec<(u64, u32)> = triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| {
                (0..3).map(move |k| {
                    let (u, v) = (t[k], t[(k + 1) % 3]);
                    let (a, b) = (u.min(v), u.max(v));
                    (
                        ((a as u64) << 32) | b as u64,
                        (f as u32) << 1 | (u > v) as u32,
                    )
                })
            })
            .collect();
        uses.par_sort_unstable();
        let mut adjacency = Adjacency {
            unbalanced_edges: unbalanced_edges(&triangles),
            positions,
            triangles,
            planes,
            degenerate_triangles,
            ..Default::default()
        };
        for group in uses.chunk_by(|x, y| x.0 == y.0) {
            let (a, b) = ((group[0].0 >> 32) as u32, group[0].0 as u32);
            match group.len() {
                1 => adjacency.open_edges += 1,
                2 if (group[0].1 & 1) == (group[1].1 & 1) => adjacency.inconsistent_edges += 1,
                2 => {}
                _ => adjacency.non_manifold_edges += 1,
            }
            for pair in group.chunks(2) {
                adjacency.edges.push(Edge {
                    a,
                    b,
                    faces: [pair[0].1, pair.get(1).map_or(NO_FACE, |u| u.1)],
                });
            }
        }
        adjacency.share_coplanar_planes();
        adjacency
    }

    /// Gives every face of a flat region (faces joined by edges whose
    /// planes agree within rounding) one plane: that of the region's largest
    /// face, normalised. Rounding in the vertices would otherwise light a
    /// grazing wall's triangles inconsistently and put silhouettes inside
    /// it.
    fn share_coplanar_planes(&mut self) {
        let n = self.triangles.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn root(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        let unit = |p: Vec4| {
            let p = p.as_dvec4();
            p / p.truncate().length().max(f64::MIN_POSITIVE)
        };
        let scale = self
            .positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()))
            .max(1e-6) as f64;
        for e in &self.edges {
            let [f, g] = e.faces;
            if f == NO_FACE || g == NO_FACE || (f & 1) == (g & 1) {
                continue;
            }
            let (f, g) = (f >> 1, g >> 1);
            let (pf, pg) = (unit(self.planes[f as usize]), unit(self.planes[g as usize]));
            if pf.truncate().dot(pg.truncate()) > 1.0 - 1e-9 && (pf.w - pg.w).abs() < 1e-6 * scale {
                let (a, b) = (root(&mut parent, f), root(&mut parent, g));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        let area = |p: Vec4| p.truncate().length_squared();
        let mut best: Vec<u32> = (0..n as u32).collect();
        for f in 0..n as u32 {
            let r = root(&mut parent, f) as usize;
            if area(self.planes[f as usize]) > area(self.planes[best[r] as usize]) {
                best[r] = f;
            }
        }
        let shared: Vec<Vec4> = (0..n)
            .map(|f| {
                let r = root(&mut parent, f as u32) as usize;
                unit(self.planes[best[r] as usize]).as_vec4()
            })
            .collect();
        self.planes = shared;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;

    #[test]
    fn a_cube_with_split_normals_welds_closed() {
        let m = shapes::cuboid(Vec3::ONE);
        assert_eq!(m.positions.len(), 24, "split per face");
        let a = Adjacency::of(&m);
        assert_eq!(a.positions.len(), 8);
        assert_eq!(a.triangles.len(), 12);
        assert_eq!(a.edges.len(), 18);
        assert!(a.is_closed(), "{}", a.summary());
    }

    #[test]
    fn an_open_quad_has_four_open_edges() {
        let m = shapes::plane(1.0, 1.0, 1);
        let a = Adjacency::of(&m);
        assert_eq!(a.open_edges, 4);
        assert_eq!(a.edges.len(), 5);
        assert!(!a.is_closed());
    }

    #[test]
    fn multiplicity_counts_lit_faces_with_their_direction() {
        let e = Edge {
            a: 0,
            b: 1,
            faces: [0 << 1, 1 << 1 | 1],
        };
        assert_eq!(e.multiplicity(|_| 1), 0);
        assert_eq!(e.multiplicity(|f| (f == 0) as i32), 1);
        assert_eq!(e.multiplicity(|f| (f == 1) as i32), -1);
        // Per-triangle weights (lit +1, unlit −1): a silhouette doubles.
        assert_eq!(e.multiplicity(|f| if f == 0 { 1 } else { -1 }), 2);
        assert_eq!(e.max_multiplicity(), 1);
        let open = Edge {
            a: 0,
            b: 1,
            faces: [3 << 1 | 1, NO_FACE],
        };
        assert_eq!(open.multiplicity(|_| 1), -1);
        assert_eq!(open.multiplicity(|_| 0), 0);
    }

    #[test]
    fn a_fin_on_a_shared_edge_is_non_manifold() {
        // A third triangle (a fin) on an edge of a closed cube.
        let mut m = shapes::cuboid(Vec3::ONE);
        let (p, q) = (
            m.positions[m.indices[0] as usize],
            m.positions[m.indices[1] as usize],
        );
        let base = m.positions.len() as u32;
        m.positions.extend([p, q, Vec3::new(3.0, 3.0, 3.0)]);
        m.normals.extend([Vec3::Y; 3]);
        m.uvs.extend([glam::Vec2::ZERO; 3]);
        m.indices.extend([base, base + 1, base + 2]);
        let a = Adjacency::of(&m);
        assert_eq!(a.non_manifold_edges, 1);
        assert_eq!(a.open_edges, 2);
        assert_eq!(
            a.edges.len(),
            18 + 1 + 2,
            "3 uses split into 2 records, 2 new open edges"
        );
        assert_eq!(a.unbalanced_edges, 3);
        assert!(!a.is_closed());
    }

    #[test]
    fn a_double_sided_sheet_and_two_boxes_sharing_an_edge_are_closed() {
        let mut sheet = shapes::plane(1.0, 1.0, 2);
        sheet.make_double_sided();
        let a = Adjacency::of(&sheet);
        assert!(a.non_manifold_edges > 0);
        assert!(a.is_closed(), "{}", a.summary());
        let mut boxes = shapes::cuboid(Vec3::ONE);
        boxes.append(
            &shapes::cuboid(Vec3::ONE),
            glam::Mat4::from_translation(Vec3::new(1.0, 1.0, 0.0)),
        );
        let a = Adjacency::of(&boxes);
        assert_eq!(a.non_manifold_edges, 1);
        assert!(a.is_closed(), "{}", a.summary());
    }

    #[test]
    fn a_flat_shaded_sphere_with_split_normals_welds_closed() {
        let mut m = shapes::sphere(0.7, 24, 12);
        m.unweld_flat();
        assert_eq!(
            m.positions.len(),
            m.indices.len(),
            "every triangle has its own vertices"
        );
        let a = Adjacency::of(&m);
        assert!(a.positions.len() < m.positions.len() / 4);
        assert!(a.is_closed(), "{}", a.summary());
        assert_eq!((a.open_edges, a.non_manifold_edges), (0, 0));
    }

    #[test]
    fn round_shapes_with_seams_and_poles_weld_closed() {
        for m in [
            shapes::sphere(0.7, 32, 16),
            shapes::torus(1.0, 0.3, 24, 12),
            shapes::cylinder(0.5, 2.0, 20),
            shapes::cuboid_subdivided(Vec3::new(1.0, 2.0, 3.0), 8),
        ] {
            let a = Adjacency::of(&m);
            assert!(a.is_closed(), "{}: {}", m.name, a.summary());
        }
    }

    #[test]
    fn the_faces_of_a_flat_region_share_one_plane() {
        // A subdivided box moved far from the origin: rounding tilts its
        // triangles' own planes slightly; each side must still light as one.
        let mut m = Mesh::default();
        m.append(
            &shapes::cuboid_subdivided(Vec3::new(1.3, 9.7, 1.1), 8),
            glam::Mat4::from_translation(Vec3::new(27.3, 4.85, -31.7)),
        );
        let a = Adjacency::of(&m);
        let mut distinct: Vec<[u32; 4]> = a
            .planes
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 6);
        for p in &a.planes {
            assert!((p.truncate().length() - 1.0).abs() < 1e-6);
        }
    }
}
