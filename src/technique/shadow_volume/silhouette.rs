//! The casters' welded geometry shared by the CPU and GPU extrusion, the
//! per-caster choices of a frame (skip, silhouette or per-triangle volume,
//! z-pass or z-fail) and the CPU extrusion.
//!
//! A volume is an index list over a virtual vertex buffer: index `2v` is
//! welded vertex v as it is, `2v + 1` the same vertex extruded away from the
//! light (the vertex shader does the extrusion). Faces of a volume wind
//! counter-clockwise seen from outside.

use super::adjacency::{Adjacency, Edge, NO_FACE};
use crate::scene::{Aabb, Scene};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;

/// A face as the GPU reads it: global welded vertices, the caster it
/// belongs to, its object-space plane.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Face {
    pub v: [u32; 3],
    pub caster: u32,
    pub plane: Vec4,
}

/// One caster object's slice of the global arrays.
#[derive(Clone, Debug)]
pub struct Caster {
    pub object: usize,
    pub faces: std::ops::Range<usize>,
    pub edges: std::ops::Range<usize>,
    /// Largest side-quad index count any lighting can give.
    pub side_bound: usize,
    pub closed: bool,
    pub world_bounds: Aabb,
    pub model: Mat4,
}

/// Every caster's welded geometry, concatenated: vertex and face indices
/// are global.
#[derive(Clone, Debug, Default)]
pub struct VolumeMesh {
    /// xyz object-space position, w the scene object id (bits).
    pub positions: Vec<Vec4>,
    pub faces: Vec<Face>,
    pub edges: Vec<Edge>,
    pub casters: Vec<Caster>,
}

impl VolumeMesh {
    /// From the scene's shadow casters; `adjacency[m]` is mesh m's (built
    /// for every mesh a caster uses).
    pub fn new(scene: &Scene, adjacency: &[Option<Adjacency>]) -> VolumeMesh {
        let mut vm = VolumeMesh::default();
        for (object, o) in scene.objects.iter().enumerate() {
            if !o.casts_shadow || o.shadow_plane {
                continue;
            }
            let Some(a) = adjacency[o.mesh].as_ref() else {
                continue;
            };
            let (v0, f0, e0) = (vm.positions.len() as u32, vm.faces.len(), vm.edges.len());
            let caster = vm.casters.len() as u32;
            let id = f32::from_bits(object as u32);
            vm.positions
                .extend(a.positions.iter().map(|p| p.extend(id)));
            // A mirrored object draws a winding-reversed copy of its mesh
            // (see `Object::winding_reversed`), whose winding planes point
            // inwards in object space: negated, they point outwards again,
            // so `P·L > 0` still means lit, and the lit faces' (reversed)
            // windings are counter-clockwise in world space.
            let facing = if o.winding_reversed { -1.0 } else { 1.0 };
            vm.faces
                .extend(a.triangles.iter().zip(&a.planes).map(|(t, &plane)| Face {
                    v: t.map(|i| i + v0),
                    caster,
                    plane: plane * facing,
                }));
            let face = |f: u32| {
                if f == NO_FACE {
                    NO_FACE
                } else {
                    f + ((f0 as u32) << 1)
                }
            };
            vm.edges.extend(a.edges.iter().map(|e| Edge {
                a: e.a + v0,
                b: e.b + v0,
                faces: e.faces.map(face),
            }));
            vm.casters.push(Caster {
                object,
                faces: f0..vm.faces.len(),
                edges: e0..vm.edges.len(),
                side_bound: a.max_side_indices(),
                closed: a.is_closed(),
                world_bounds: scene.meshes[o.mesh].bounds().transformed(o.transform),
                model: o.transform,
            });
        }
        vm
    }
}

/// How a caster's volume is built this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeKind {
    /// Its volume cannot touch the view frustum.
    Skip,
    /// Side quads on silhouette edges (+ caps when counted with z-fail).
    Silhouette,
    /// Every triangle's own closed volume, unlit triangles turned to face
    /// the light (exact for any triangle soup); the side quads in which
    /// neighbouring triangles' volumes cancel are left out, which changes
    /// no stencil count and avoids rasterising the same sliver twice with
    /// opposite windings (where coverage rules can differ).
    Triangles,
}

/// A caster's volume for this frame and how it is counted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CasterPlan {
    pub kind: VolumeKind,
    pub zfail: bool,
    /// The light in the caster's object space (w = 0: directional, towards the light).
    pub light: Vec4,
    /// Caps are drawn where the volume needs them; false only for
    /// `caps=false`, which leaves z-fail volumes open to show that failure.
    pub capped: bool,
}

impl CasterPlan {
    /// Light and dark caps are needed to count a volume with z-fail; a
    /// per-triangle volume always has them (it must be closed on its own);
    /// a skipped caster has none.
    pub fn caps(&self) -> bool {
        if !self.capped {
            return false;
        }
        match self.kind {
            VolumeKind::Skip => false,
            VolumeKind::Silhouette => self.zfail,
            VolumeKind::Triangles => true,
        }
    }

    /// True where face `f` faces the light (`P·L > 0`).
    pub fn lit(&self, vm: &VolumeMesh, f: u32) -> bool {
        vm.faces[f as usize].plane.dot(self.light) > 0.0
    }

    /// Face `f`'s weight in the edge multiplicity: 1 when lit; when unlit,
    /// 0 for silhouettes and −1 for per-triangle volumes (turned to face the
    /// light).
    fn weight(&self, vm: &VolumeMesh, f: u32) -> i32 {
        match (self.kind, self.lit(vm, f)) {
            (_, true) => 1,
            (VolumeKind::Triangles, false) => -1,
            _ => 0,
        }
    }

    /// The caster's edges that get side quads, with their multiplicity.
    pub fn extruded_edges<'a>(
        &'a self,
        vm: &'a VolumeMesh,
        c: &Caster,
    ) -> impl Iterator<Item = (&'a Edge, i32)> + 'a {
        let edges = if self.kind == VolumeKind::Skip {
            &vm.edges[..0]
        } else {
            &vm.edges[c.edges.clone()]
        };
        edges
            .iter()
            .map(|e| (e, e.multiplicity(|f| self.weight(vm, f))))
            .filter(|&(_, m)| m != 0)
    }

    /// Largest index count this caster's volume can take.
    pub fn index_bound(&self, c: &Caster, dark_cap: bool) -> usize {
        let faces = c.faces.len();
        let cap = if dark_cap { 6 } else { 3 };
        match self.kind {
            VolumeKind::Skip => 0,
            VolumeKind::Silhouette => c.side_bound + if self.caps() { cap * faces } else { 0 },
            VolumeKind::Triangles => 12 * c.edges.len() + cap * faces,
        }
    }
}

/// Frustum planes `(n, d)`, inside where `n·p + d ≥ 0`, of a reversed
/// [0,1]-depth view-projection (Gribb & Hartmann 2001): left, right,
/// bottom, top, near (z_ndc ≤ 1).
/// The far plane is left out: volumes reach it by design.
pub fn frustum_planes(view_proj: Mat4) -> [Vec4; 5] {
    let r = |i| view_proj.row(i);
    [
        r(3) + r(0),
        r(3) - r(0),
        r(3) + r(1),
        r(3) - r(1),
        r(3) - r(2),
    ]
}

fn outside(plane: Vec4, corners: &[Vec3; 8]) -> bool {
    corners
        .iter()
        .all(|c| plane.truncate().dot(*c) + plane.w < 0.0)
}

/// False when the volume of a caster with world bounds `b` (every point of
/// `b` swept away from the light `light`, homogeneous) lies entirely
/// outside one of `planes`: all corners outside and the sweep moving
/// further out.
pub fn volume_may_touch(planes: &[Vec4], b: &Aabb, light: Vec4) -> bool {
    let corners = b.corners();
    !planes.iter().any(|&p| {
        let n = p.truncate();
        outside(p, &corners)
            && corners.iter().all(|&c| {
                // Extrusion direction at c: away from the light.
                let dir = if light.w == 0.0 {
                    -light.truncate()
                } else {
                    c - light.truncate()
                };
                n.dot(dir) <= 0.0
            })
    })
}

/// Planes of the region between the light and the near-plane rectangle
/// `corners` (in order around it): a caster's volume can contain part of
/// the near rectangle only if the caster meets this region (Everitt &
/// Kilgard 2002's "near-plane clip volume"). `None` when the light lies in
/// the near plane (then every caster needs z-fail).
pub fn near_clip_region(corners: [Vec3; 4], light: Vec4) -> Option<Vec<Vec4>> {
    let centre = corners.iter().sum::<Vec3>() / 4.0;
    let normal = (corners[1] - corners[0]).cross(corners[3] - corners[0]);
    let towards = if light.w == 0.0 {
        light.truncate()
    } else {
        light.truncate() - centre
    };
    let lift = normal.dot(towards);
    if lift.abs() <= 1e-6 * normal.length() * towards.length() {
        return None;
    }
    // A point strictly inside: between the rectangle and the light.
    let inside = centre
        + if light.w == 0.0 {
            towards.normalize()
        } else {
            towards * 0.5
        };
    let orient = |n: Vec3, through: Vec3| {
        let p = n.extend(-n.dot(through));
        if p.dot(inside.extend(1.0)) < 0.0 {
            -p
        } else {
            p
        }
    };
    let mut planes = vec![orient(normal, centre)];
    for i in 0..4 {
        let (a, b) = (corners[i], corners[(i + 1) % 4]);
        let n = if light.w == 0.0 {
            (b - a).cross(towards)
        } else {
            (a - light.truncate()).cross(b - light.truncate())
        };
        planes.push(orient(n, a));
    }
    Some(planes)
}

/// True when `b` may meet the region of [`near_clip_region`].
pub fn meets(region: &[Vec4], b: &Aabb) -> bool {
    let corners = b.corners();
    !region.iter().any(|&p| outside(p, &corners))
}

/// Side quad of edge `u → v` (as a lit face winds it), outward.
fn quad(out: &mut Vec<u32>, u: u32, v: u32) {
    out.extend_from_slice(&[2 * v, 2 * u, 2 * u + 1, 2 * v, 2 * u + 1, 2 * v + 1]);
}

/// Light cap (the face) and dark cap (the face extruded, reversed).
fn caps(out: &mut Vec<u32>, [i, j, k]: [u32; 3], dark_cap: bool) {
    out.extend_from_slice(&[2 * i, 2 * j, 2 * k]);
    if dark_cap {
        out.extend_from_slice(&[2 * i + 1, 2 * k + 1, 2 * j + 1]);
    }
}

/// One caster's volume indices and its silhouette edge count.
pub fn caster_volume(
    vm: &VolumeMesh,
    c: &Caster,
    plan: &CasterPlan,
    dark_cap: bool,
) -> (Vec<u32>, usize) {
    let mut out = vec![];
    let mut silhouettes = 0;
    for (e, m) in plan.extruded_edges(vm, c) {
        if plan.kind == VolumeKind::Silhouette {
            silhouettes += 1;
        }
        let (u, v) = if m > 0 { (e.a, e.b) } else { (e.b, e.a) };
        for _ in 0..m.unsigned_abs() {
            quad(&mut out, u, v);
        }
    }
    if plan.caps() {
        for f in c.faces.clone() {
            let [i, j, k] = vm.faces[f].v;
            match (plan.kind, plan.lit(vm, f as u32)) {
                (_, true) => caps(&mut out, [i, j, k], dark_cap),
                (VolumeKind::Triangles, false) => caps(&mut out, [i, k, j], dark_cap),
                _ => {}
            }
        }
    }
    (out, silhouettes)
}

/// The CPU extrusion: z-pass and z-fail index lists and the silhouette edge
/// count, casters in parallel.
pub fn volumes(vm: &VolumeMesh, plans: &[CasterPlan], dark_cap: bool) -> ([Vec<u32>; 2], usize) {
    let parts: Vec<(Vec<u32>, usize)> = vm
        .casters
        .par_iter()
        .zip(plans)
        .map(|(c, p)| caster_volume(vm, c, p, dark_cap))
        .collect();
    let mut lists = [vec![], vec![]];
    let mut silhouettes = 0;
    for ((indices, s), p) in parts.into_iter().zip(plans) {
        lists[p.zfail as usize].extend(indices);
        silhouettes += s;
    }
    (lists, silhouettes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Object, shapes};

    fn one_box() -> (Scene, VolumeMesh) {
        let mut s = Scene::new("box");
        let m = s.add_mesh(shapes::cuboid(Vec3::ONE));
        let mat = s.add_material(Material::color("grey", Vec3::ONE));
        s.objects
            .push(Object::from_name("Box", m, mat, Mat4::IDENTITY));
        let adj = vec![Some(Adjacency::of(&s.meshes[0]))];
        let vm = VolumeMesh::new(&s, &adj);
        (s, vm)
    }

    #[test]
    fn a_box_under_a_light_above_has_a_four_edge_silhouette() {
        let (_, vm) = one_box();
        let plan = CasterPlan {
            kind: VolumeKind::Silhouette,
            zfail: false,
            light: Vec4::new(0.0, 10.0, 0.0, 1.0),
            capped: true,
        };
        let ([zpass, zfail], silhouettes) = volumes(&vm, &[plan], true);
        // Only the top face is lit: its 4 edges (2 triangles) are the silhouette.
        assert_eq!(silhouettes, 4);
        assert_eq!(zpass.len(), 4 * 6);
        assert!(zfail.is_empty());
        let zfail_plan = CasterPlan {
            zfail: true,
            ..plan
        };
        let ([_, zfail], _) = volumes(&vm, &[zfail_plan], true);
        assert_eq!(
            zfail.len(),
            4 * 6 + 2 * 6,
            "sides + light and dark caps of 2 triangles"
        );
    }

    #[test]
    fn the_volume_of_a_closed_mesh_is_closed_and_outward() {
        // Every directed edge of a closed, consistently wound triangle set
        // appears as often as its reverse; the volume's signed volume is
        // positive (outward winding) with the extruded vertices at a finite
        // distance.
        let (_, vm) = one_box();
        let light = Vec4::new(0.3, 4.0, 0.2, 1.0);
        for kind in [VolumeKind::Silhouette, VolumeKind::Triangles] {
            let plan = CasterPlan {
                kind,
                zfail: true,
                light,
                capped: true,
            };
            let ([_, idx], _) = volumes(&vm, &[plan], true);
            let pos = |i: u32| {
                let p = vm.positions[(i / 2) as usize].truncate();
                if i.is_multiple_of(2) {
                    p
                } else {
                    p + (p - light.truncate()) * 3.0
                }
            };
            let mut directed = std::collections::HashMap::<(u32, u32), i32>::new();
            let mut volume = 0.0;
            for t in idx.chunks_exact(3) {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    *directed.entry((a.min(b), a.max(b))).or_default() +=
                        if a < b { 1 } else { -1 };
                }
                volume += pos(t[0]).dot(pos(t[1]).cross(pos(t[2]))) / 6.0;
            }
            assert!(directed.values().all(|&n| n == 0), "{kind:?} not closed");
            assert!(volume > 0.1, "{kind:?}: signed volume {volume}");
        }
    }

    #[test]
    fn near_clip_region_contains_what_lies_between_light_and_near_rectangle() {
        let corners = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let light = Vec4::new(0.0, 0.0, 10.0, 1.0);
        let r = near_clip_region(corners, light).unwrap();
        let small = |c: Vec3| Aabb::from_points([c - 0.1, c + 0.1]);
        assert!(meets(&r, &small(Vec3::new(0.0, 0.0, 5.0))));
        assert!(
            !meets(&r, &small(Vec3::new(0.0, 0.0, -5.0))),
            "behind the rectangle"
        );
        assert!(
            !meets(&r, &small(Vec3::new(3.0, 0.0, 2.0))),
            "beside the pyramid"
        );
        assert!(
            !meets(&r, &small(Vec3::new(0.0, 0.0, 12.0))),
            "beyond the light"
        );
        let sun = Vec4::new(0.0, 0.0, 1.0, 0.0);
        let r = near_clip_region(corners, sun).unwrap();
        assert!(meets(&r, &small(Vec3::new(0.5, 0.5, 100.0))));
        assert!(!meets(&r, &small(Vec3::new(3.0, 0.0, 100.0))));
        assert!(near_clip_region(corners, Vec4::new(5.0, 0.0, 0.0, 1.0)).is_none());
    }

    #[test]
    fn a_volume_behind_a_frustum_plane_and_moving_away_is_culled() {
        let vp = glam::camera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 100.0)
            * glam::camera::rh::view::look_at_mat4(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
        let planes = frustum_planes(vp);
        // A box behind the camera, the light further in front: its volume
        // points away from the frustum.
        let b = Aabb::from_points([Vec3::new(-0.5, -0.5, 4.5), Vec3::new(0.5, 0.5, 5.5)]);
        assert!(!volume_may_touch(
            &planes,
            &b,
            Vec4::new(0.0, 0.0, -3.0, 1.0)
        ));
        // The light behind the box: the volume sweeps into the frustum.
        assert!(volume_may_touch(
            &planes,
            &b,
            Vec4::new(0.0, 0.0, 10.0, 1.0)
        ));
        // A box in view is never culled.
        let seen = Aabb::from_points([Vec3::new(-0.5, -0.5, -5.5), Vec3::new(0.5, 0.5, -4.5)]);
        assert!(volume_may_touch(
            &planes,
            &seen,
            Vec4::new(0.0, 0.0, -3.0, 1.0)
        ));
    }
}
