//! Mesh topology shared by the techniques: vertices welded by position (so
//! that meshes split by normals or uvs are still seen as connected), and
//! whether a mesh bounds a solid.

use super::{Mesh, Scene};
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

/// A position as the bits of its coordinates, −0 taken as +0: equal
/// positions, and only they, have equal keys.
fn position_key(p: Vec3) -> [u32; 3] {
    p.to_array().map(|c| (c + 0.0).to_bits())
}

impl Welded {
    pub fn of(mesh: &Mesh) -> Welded {
        let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.positions.len());
        let mut positions = vec![];
        let remap = mesh
            .positions
            .iter()
            .map(|&p| {
                *first.entry(position_key(p)).or_insert_with(|| {
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

/// How far (1 − cos) a triangle's normal may turn from its set's mean for
/// the set to count as flat: 1e-8, about 0.008°.
const FLAT_TOLERANCE: f64 = 1e-8;

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

/// A mesh's solidity: what it encloses, and its convex parts.
pub struct Solidity {
    pub kind: SolidKind,
    /// Per vertex of the mesh, its convex part (numbered from 1 within the
    /// mesh) or 0: in a set that is neither flat nor closed and convex, or
    /// welded to a vertex of another set.
    pub vertex_parts: Vec<u32>,
    /// The number of convex parts.
    pub parts: u32,
    /// Per part (ID − 1), whether it is flat (an open sheet, such as a
    /// floor), not closed around a volume.
    pub flat_parts: Vec<bool>,
}

impl Mesh {
    /// What the mesh encloses ([`Mesh::solidity`]).
    pub fn solid_kind(&self) -> SolidKind {
        self.solidity().kind
    }

    /// Bounds a solid: closed after welding (every edge run as often in one
    /// direction as in the other) and wound outward, with a volume (the
    /// signed volume Σ a·(b × c)/6 positive and not a rounding residue of the
    /// bounding box's). A double-sided sheet is closed but encloses nothing;
    /// a mesh wound inward has a negative volume. Only such a mesh's back
    /// faces are, seen from anywhere, behind its front faces. Convex when
    /// every edge is (a closed surface convex at every edge is convex in
    /// each connected part).
    ///
    /// Its convex parts, in any mesh, closed or open, are the sets of
    /// triangles joined across shared edges that share no vertex with
    /// another set (two boxes meeting at a corner are one surface but not
    /// one convex body) and are either convex at every edge (so closed)
    /// around a volume, or flat (a floor): such a part never shadows its
    /// own lit side (Hourcade & Nicolas 1985 give each one an ID in the
    /// map).
    pub fn solidity(&self) -> Solidity {
        let welded = Welded::of(self);
        // The welded triangles and the mesh's own triangle each comes from.
        let (triangles, sources): (Vec<[u32; 3]>, Vec<usize>) = self
            .indices
            .chunks_exact(3)
            .enumerate()
            .map(|(i, t)| ([t[0], t[1], t[2]].map(|v| welded.remap[v as usize]), i))
            .filter(|(w, _)| w[0] != w[1] && w[1] != w[2] && w[2] != w[0])
            .unzip();
        if triangles.is_empty() {
            return Solidity {
                kind: SolidKind::NotSolid,
                vertex_parts: vec![0; self.positions.len()],
                parts: 0,
                flat_parts: vec![],
            };
        }
        let p = |i: u32| welded.positions[i as usize].as_dvec3();
        // Signed volume under each triangle, Σ a·(b × c)/6 over a closed set,
        // and its area vector (b − a) × (c − a).
        let volumes: Vec<f64> = triangles
            .iter()
            .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0)
            .collect();
        let areas: Vec<DVec3> = triangles
            .iter()
            .map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])))
            .collect();
        let extent = self.bounds().size().as_dvec3();
        let extent = extent.x.max(extent.y).max(extent.z);
        let least_volume = 1e-9 * extent.powi(3);
        let mut shape = edge_shape(&triangles, &p, 1e-6 * extent);
        let kind =
            if unbalanced_edges(&triangles) > 0 || volumes.iter().sum::<f64>() <= least_volume {
                SolidKind::NotSolid
            } else if shape.concave.iter().any(|&c| c) {
                SolidKind::Concave
            } else {
                SolidKind::Convex
            };
        // Parts: sets of triangles joined across edges (indexed by their
        // root triangle), usable while alone at every welded vertex and
        // either convex at every edge (so closed) around a volume, or flat.
        let component: Vec<usize> = (0..triangles.len()).map(|t| shape.root(t)).collect();
        let mut usable = vec![true; triangles.len()];
        let mut convex = vec![true; triangles.len()];
        let mut volume = vec![0.0; triangles.len()];
        let mut area = vec![DVec3::ZERO; triangles.len()];
        let mut owner = vec![usize::MAX; welded.positions.len()];
        for (t, tri) in triangles.iter().enumerate() {
            let c = component[t];
            convex[c] &= !shape.concave[t];
            volume[c] += volumes[t];
            area[c] += areas[t];
            for &v in tri {
                let first = &mut owner[v as usize];
                if *first == usize::MAX {
                    *first = c;
                } else if *first != c {
                    usable[c] = false;
                    usable[*first] = false;
                }
            }
        }
        // Flat: every triangle with an area faces the set's mean normal
        // (edge-joined triangles facing one way lie in one plane).
        let mut flat = vec![true; triangles.len()];
        for (t, &c) in component.iter().enumerate() {
            let own = areas[t].normalize_or_zero();
            flat[c] &=
                own == DVec3::ZERO || own.dot(area[c].normalize_or_zero()) >= 1.0 - FLAT_TOLERANCE;
        }
        let mut id_of = vec![0u32; triangles.len()];
        let mut parts = 0;
        let mut flat_parts = vec![];
        let mut vertex_parts = vec![0; self.positions.len()];
        for (t, &c) in component.iter().enumerate() {
            let closed_convex = convex[c] && volume[c] > least_volume;
            if !usable[c] || !(closed_convex || flat[c]) {
                continue;
            }
            if id_of[c] == 0 {
                parts += 1;
                id_of[c] = parts;
                flat_parts.push(!closed_convex);
            }
            for &v in &self.indices[sources[t] * 3..sources[t] * 3 + 3] {
                vertex_parts[v as usize] = id_of[c];
            }
        }
        Solidity {
            kind,
            vertex_parts,
            parts,
            flat_parts,
        }
    }
}

/// How a closed, outward-wound surface folds at its edges: which triangles
/// have a concave edge, and which are joined across edges.
struct EdgeShape {
    /// Per triangle: a neighbour rises above its plane, or an edge has no
    /// single twin.
    concave: Vec<bool>,
    /// Union-find parents joining triangles that share an edge.
    parent: Vec<usize>,
}

impl EdgeShape {
    /// The representative of triangle `t`'s connected set (halving the
    /// path on the way).
    fn root(&mut self, mut t: usize) -> usize {
        while self.parent[t] != t {
            self.parent[t] = self.parent[self.parent[t]];
            t = self.parent[t];
        }
        t
    }
}

/// The edges of a closed, outward-wound surface (welded `triangles` over
/// positions `p`): a triangle is concave where a neighbour rises more than
/// `tolerance` above its plane or an edge is shared by more than two
/// triangles.
fn edge_shape(triangles: &[[u32; 3]], p: &impl Fn(u32) -> DVec3, tolerance: f64) -> EdgeShape {
    let mut across: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(triangles.len() * 3);
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            across
                .entry((t[k], t[(k + 1) % 3]))
                .or_default()
                .push(i as u32);
        }
    }
    let mut shape = EdgeShape {
        concave: vec![false; triangles.len()],
        parent: (0..triangles.len()).collect(),
    };
    for (i, t) in triangles.iter().enumerate() {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            match across.get(&(v, u)).map(Vec::as_slice) {
                Some([twin]) => {
                    let twin = *twin as usize;
                    let w = triangles[twin]
                        .into_iter()
                        .find(|&w| w != u && w != v)
                        .expect("a welded triangle has three corners");
                    shape.concave[i] |= normal.dot(p(w) - a) > tolerance;
                    let (ra, rb) = (shape.root(i), shape.root(twin));
                    shape.parent[ra.max(rb)] = ra.min(rb);
                }
                _ => shape.concave[i] = true,
            }
        }
    }
    shape
}

/// How far above a flat part's plane (the sine of the angle) another
/// mesh's triangle may rise across an edge they share and still count as
/// going on level with it or falling away: about 0.06°.
const RISES_ABOVE: f32 = 1e-3;

/// Per object of `scene`, whether one of its flat parts (`solidity`, per
/// mesh) shares an edge with a triangle of another drawn mesh placed with
/// the same transform that goes on level with the part or falls away from
/// it: a glTF mesh's primitives (one per material) are separate meshes of
/// one surface, so a face cut at a material's border, or a box's top whose
/// sides are another primitive, meets its neighbour there, and a receiver
/// with that part compares the neighbour's texels against one depth, not
/// along its plane: where the plane rises towards the light, the neighbour
/// lies nearer the light than that depth (acne along the edge). Such an
/// object's parts are not used. A neighbour that rises above the part (a
/// wall on a floor) keeps them: one depth is what spares the floor the
/// wall's foot (`receiver_plane`).
pub fn parts_meeting_other_meshes(scene: &Scene, solidity: &[Solidity]) -> Vec<bool> {
    let mut placed: HashMap<[u32; 16], Vec<usize>> = HashMap::new();
    for (i, o) in scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| !o.shadow_plane)
    {
        let transform = o.transform.to_cols_array().map(|c| (c + 0.0).to_bits());
        placed.entry(transform).or_default().push(i);
    }
    let mut meets = vec![false; scene.objects.len()];
    for members in placed.values() {
        let mut meshes: Vec<usize> = members.iter().map(|&i| scene.objects[i].mesh).collect();
        meshes.sort_unstable();
        meshes.dedup();
        if meshes.len() < 2
            || meshes
                .iter()
                .all(|&m| !solidity[m].flat_parts.contains(&true))
        {
            continue;
        }
        let edges = edge_opposites(scene, &meshes);
        for &i in members {
            let m = scene.objects[i].mesh;
            meets[i] = flat_part_edges(&scene.meshes[m], &solidity[m]).any(|(edge, at, normal)| {
                edges.get(&edge).is_some_and(|opposite| {
                    opposite.iter().any(|&(other, corner)| {
                        let away = (corner - at).normalize_or_zero();
                        other != m && away != Vec3::ZERO && away.dot(normal) <= RISES_ABOVE
                    })
                })
            });
        }
    }
    meets
}

/// An edge between two positions, the same either way round.
type EdgeKey = ([u32; 3], [u32; 3]);

fn edge_key(a: Vec3, b: Vec3) -> EdgeKey {
    let (a, b) = (position_key(a), position_key(b));
    if a <= b { (a, b) } else { (b, a) }
}

/// `mesh`'s triangles with an area: their first vertex, corners and unit
/// normal.
fn triangles_with_normals(mesh: &Mesh) -> impl Iterator<Item = (u32, [Vec3; 3], Vec3)> + '_ {
    mesh.indices.chunks_exact(3).filter_map(|t| {
        let c = [t[0], t[1], t[2]].map(|v| mesh.positions[v as usize]);
        Some((t[0], c, (c[1] - c[0]).cross(c[2] - c[0]).try_normalize()?))
    })
}

/// The triangles' edges of `meshes`, each with the mesh and the third
/// corner of every triangle along it.
fn edge_opposites(scene: &Scene, meshes: &[usize]) -> HashMap<EdgeKey, Vec<(usize, Vec3)>> {
    let mut edges: HashMap<EdgeKey, Vec<(usize, Vec3)>> = HashMap::new();
    for &m in meshes {
        for (_, c, _) in triangles_with_normals(&scene.meshes[m]) {
            for k in 0..3 {
                let edge = edge_key(c[k], c[(k + 1) % 3]);
                edges.entry(edge).or_default().push((m, c[(k + 2) % 3]));
            }
        }
    }
    edges
}

/// The edges of `mesh`'s triangles in flat parts, each with a point on it
/// and the triangle's unit normal.
fn flat_part_edges<'a>(
    mesh: &'a Mesh,
    solidity: &'a Solidity,
) -> impl Iterator<Item = (EdgeKey, Vec3, Vec3)> + 'a {
    let flat = |v: u32| {
        let part = solidity.vertex_parts[v as usize];
        part != 0 && solidity.flat_parts[part as usize - 1]
    };
    triangles_with_normals(mesh)
        .filter(move |&(first, _, _)| flat(first))
        .flat_map(|(_, c, n)| (0..3).map(move |k| (edge_key(c[k], c[(k + 1) % 3]), c[k], n)))
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
        let cube = shapes::cuboid(Vec3::ONE);
        let two = joined(&cube, &cube, Vec3::X * 3.0);
        assert_eq!(two.solid_kind(), SolidKind::Convex);
    }

    /// A sheet's flat part loses its ID where another mesh placed with the
    /// same transform shares an edge with it and goes on level with it or
    /// falls away (a box top whose sides are another primitive), not where
    /// it rises (a wall on a floor) or is placed elsewhere.
    #[test]
    fn flat_parts_meeting_a_level_or_falling_neighbour_are_not_used() {
        use crate::scene::{Material, Scene};
        use glam::Mat4;
        let quad = |far: Vec3| Mesh {
            name: "neighbour".into(),
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::X + far, far],
            indices: vec![0, 1, 2, 0, 2, 3],
            ..Default::default()
        };
        let cases = [
            (Vec3::Y, Mat4::IDENTITY, false),
            (-Vec3::Y, Mat4::IDENTITY, true),
            (-Vec3::Z, Mat4::IDENTITY, true),
            (-Vec3::Y, Mat4::from_translation(Vec3::Z * 5.0), false),
        ];
        for (far, placed, meets) in cases {
            let mut scene = Scene::new("edges");
            let grey = scene.add_material(Material::color("grey", Vec3::ONE));
            let floor = scene.add_mesh(sheet());
            scene.add_object("Floor", floor, grey, Mat4::IDENTITY);
            let neighbour = scene.add_mesh(quad(far));
            scene.add_object("Neighbour", neighbour, grey, placed);
            let solidity: Vec<Solidity> = scene.meshes.iter().map(|m| m.solidity()).collect();
            assert_eq!(solidity[0].flat_parts, vec![true]);
            let flagged = parts_meeting_other_meshes(&scene, &solidity);
            assert_eq!(
                flagged[0], meets,
                "neighbour towards {far}, placed {placed}"
            );
        }
    }

    /// `a` with `b`'s triangles appended, moved by `shift`.
    fn joined(a: &Mesh, b: &Mesh, shift: Vec3) -> Mesh {
        let mut m = a.clone();
        let base = m.positions.len() as u32;
        m.positions.extend(b.positions.iter().map(|p| *p + shift));
        m.normals.extend(&b.normals);
        m.uvs.extend(&b.uvs);
        m.tangents.extend(&b.tangents);
        m.indices.extend(b.indices.iter().map(|i| i + base));
        m
    }

    #[test]
    fn convex_parts_are_numbered_per_vertex_and_concave_or_touching_ones_are_not() {
        let cube = shapes::cuboid(Vec3::ONE);
        let n = cube.positions.len();
        let two = joined(&cube, &cube, Vec3::X * 3.0);
        let s = two.solidity();
        assert_eq!((s.kind, s.parts), (SolidKind::Convex, 2));
        assert!(s.vertex_parts[..n].iter().all(|&p| p == 1));
        assert!(s.vertex_parts[n..].iter().all(|&p| p == 2));
        // A box beside a torus: the mesh is concave, the box still a part.
        let torus = shapes::torus(1.0, 0.3, 16, 8);
        let mixed = joined(&cube, &torus, Vec3::X * 4.0);
        let s = mixed.solidity();
        assert_eq!((s.kind, s.parts), (SolidKind::Concave, 1));
        assert!(s.vertex_parts[..n].iter().all(|&p| p == 1));
        assert!(s.vertex_parts[n..].iter().all(|&p| p == 0));
        // Two boxes meeting at a corner share a welded vertex: no parts.
        let touching = joined(&cube, &cube, Vec3::ONE);
        let s = touching.solidity();
        assert_eq!(s.parts, 0);
        assert!(s.vertex_parts.iter().all(|&p| p == 0));
        // An open box has none either.
        let mut open = cube.clone();
        open.indices.truncate(open.indices.len() - 6);
        assert_eq!(open.solidity().parts, 0);
    }

    #[test]
    fn flat_sets_are_parts_in_open_meshes_too_and_bent_ones_are_not() {
        // A floor: open, flat, one part.
        let floor = shapes::plane(4.0, 4.0, 4);
        let s = floor.solidity();
        assert_eq!((s.kind, s.parts), (SolidKind::NotSolid, 1));
        assert!(s.vertex_parts.iter().all(|&p| p == 1));
        // A box standing off the floor in the same (open) mesh: two parts.
        let cube = shapes::cuboid(Vec3::ONE);
        let scene = joined(&floor, &cube, Vec3::Y * 2.0);
        let s = scene.solidity();
        assert_eq!((s.kind, s.parts), (SolidKind::NotSolid, 2));
        let n = floor.positions.len();
        assert!(s.vertex_parts[..n].iter().all(|&p| p == 1));
        assert!(s.vertex_parts[n..].iter().all(|&p| p == 2));
        // The floor with one vertex raised by a millimetre is not flat,
        // nor is a rolling ground; the open box's sides are not flat.
        let mut bent = floor.clone();
        let centre = bent
            .positions
            .iter()
            .position(|p| *p == Vec3::ZERO)
            .unwrap();
        bent.positions[centre].y = 1e-3;
        assert_eq!(bent.solidity().parts, 0);
        let ground = shapes::heightfield(4.0, 8, |x, z| 0.1 * (x + z).sin());
        assert_eq!(ground.solidity().parts, 0);
        let mut open = cube.clone();
        open.indices.truncate(open.indices.len() - 6);
        assert_eq!(open.solidity().parts, 0);
    }
}
