//! The caster triangles the irregular z-buffer tests its samples against:
//! every shadow-casting object's triangles in world space, with their
//! texture coordinates and object (for cut-outs), listed once per scene in
//! spatially compact clusters, each with its bounds, so that a frame
//! dispatches only the clusters that can shadow what it sees (`cull`).

use crate::scene::clusters::clustered;
use crate::scene::{Aabb, Scene};
use bytemuck::{Pod, Zeroable};
use glam::Vec4;

/// The most triangles in one caster cluster: a few hundred keep a
/// cluster's bounds tight on a terrain or a city block, and the clusters
/// few enough to test each frame.
const CASTER_CLUSTER_TRIANGLES: usize = 512;

/// A run of the caster list whose triangles lie within `bounds`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CasterCluster {
    pub first: u32,
    pub count: u32,
    /// World bounds of its triangles.
    pub bounds: Aabb,
}

/// One caster triangle as `CasterTriangle` of irregular.wgsl reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct CasterTriangle {
    /// World positions; w the vertex's u.
    pub a: Vec4,
    pub b: Vec4,
    pub c: Vec4,
    /// The vertices' v; w the object index (bits).
    pub v: Vec4,
}

/// The caster triangles of a scene, those of opaque materials first.
pub struct Casters {
    pub triangles: Vec<CasterTriangle>,
    /// How many lead the list: the triangles of opaque materials, which the
    /// test passes built without the see-through code run over
    /// (`TestPass::Opaque`).
    pub opaque: u32,
    /// The list's clusters, in its order (none holds opaque and
    /// see-through triangles both).
    pub clusters: Vec<CasterCluster>,
}

/// The triangles of `scene`'s shadow casters, wound in world space as in
/// their mesh (an object mirrored by its transform has two corners
/// swapped), so that a solid's stay wound outward; opaque materials' first,
/// each object in the scene's order, its triangles in the clusters of
/// [`clustered`]. The back faces a double-sided material added are left
/// out: the exact test does not depend on a triangle's winding, so they
/// would test every sample twice.
pub fn caster_triangles(scene: &Scene) -> Casters {
    let (mut opaque, mut see_through) = (Casters::empty(), Casters::empty());
    for (index, o) in scene.objects.iter().enumerate() {
        if !o.casts_shadow || o.shadow_plane {
            continue;
        }
        let m = &scene.meshes[o.mesh];
        // A double-sided mesh's back faces use the second half of its
        // vertices (`Mesh::make_double_sided`).
        let front_vertices = if m.sides_doubled {
            m.positions.len() / 2
        } else {
            m.positions.len()
        };
        let object = f32::from_bits(index as u32);
        let mirrored = o.transform.determinant() < 0.0;
        let out = if scene.materials[o.material].is_see_through() {
            &mut see_through
        } else {
            &mut opaque
        };
        let runs = clustered(m, CASTER_CLUSTER_TRIANGLES);
        for cluster in &runs.clusters {
            let range =
                cluster.first_index as usize..(cluster.first_index + cluster.index_count) as usize;
            let first = out.triangles.len();
            for t in runs.indices[range].chunks_exact(3) {
                if t[0] as usize >= front_vertices {
                    continue;
                }
                let corner = |k: usize| {
                    let i = t[k] as usize;
                    let uv = m.uvs.get(i).copied().unwrap_or_default();
                    (
                        o.transform.transform_point3(m.positions[i]).extend(uv.x),
                        uv.y,
                    )
                };
                let (second, third) = if mirrored { (2, 1) } else { (1, 2) };
                let ((a, va), (b, vb), (c, vc)) = (corner(0), corner(second), corner(third));
                out.triangles.push(CasterTriangle {
                    a,
                    b,
                    c,
                    v: Vec4::new(va, vb, vc, object),
                });
            }
            let added = &out.triangles[first..];
            if !added.is_empty() {
                out.clusters.push(CasterCluster {
                    first: first as u32,
                    count: added.len() as u32,
                    bounds: Aabb::from_points(
                        added
                            .iter()
                            .flat_map(|t| [t.a, t.b, t.c].map(|p| p.truncate())),
                    ),
                });
            }
        }
    }
    let count = opaque.triangles.len() as u32;
    opaque
        .clusters
        .extend(see_through.clusters.iter().map(|c| CasterCluster {
            first: c.first + count,
            ..*c
        }));
    opaque.triangles.append(&mut see_through.triangles);
    Casters {
        opaque: count,
        ..opaque
    }
}

impl Casters {
    fn empty() -> Casters {
        Casters {
            triangles: vec![],
            opaque: 0,
            clusters: vec![],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    /// Every caster triangle is listed once, in world space, with its
    /// object, opaque materials' first; a double-sided material's added
    /// back faces are not.
    #[test]
    fn casters_are_listed_once_in_world_space() {
        let scene = builtin::by_name("foliage").unwrap().unwrap();
        let casters = caster_triangles(&scene);
        let triangles = &casters.triangles;
        let expected: usize = scene
            .objects
            .iter()
            .filter(|o| o.casts_shadow && !o.shadow_plane)
            .map(|o| {
                let m = &scene.meshes[o.mesh];
                m.triangle_count() / if m.sides_doubled { 2 } else { 1 }
            })
            .sum();
        assert_eq!(triangles.len(), expected);
        assert!(scene.meshes.iter().any(|m| m.sides_doubled));
        // Each triangle is one of its object's front faces in world space.
        for t in triangles {
            let o = &scene.objects[t.v.w.to_bits() as usize];
            let m = &scene.meshes[o.mesh];
            let front = m.triangle_count() / if m.sides_doubled { 2 } else { 1 };
            let world = |i: u32| o.transform.transform_point3(m.positions[i as usize]);
            let found = m.indices.chunks_exact(3).take(front).any(|f| {
                (world(f[0]) - t.a.truncate()).length() < 1e-5
                    && (world(f[1]) - t.b.truncate()).length() < 1e-5
                    && (world(f[2]) - t.c.truncate()).length() < 1e-5
            });
            assert!(o.casts_shadow && found, "{t:?}");
        }
        // The clusters tile the list, each within its bounds.
        let mut next = 0;
        for c in &casters.clusters {
            assert_eq!(c.first, next);
            next += c.count;
            for t in &triangles[c.first as usize..next as usize] {
                for p in [t.a, t.b, t.c] {
                    let p = p.truncate();
                    assert!(p.cmpge(c.bounds.min).all() && p.cmple(c.bounds.max).all());
                }
            }
        }
        assert_eq!(next as usize, triangles.len());
        // Opaque materials' triangles lead, the see-through ones follow.
        let see_through = |t: &CasterTriangle| {
            let o = &scene.objects[t.v.w.to_bits() as usize];
            scene.materials[o.material].is_see_through()
        };
        let opaque = casters.opaque as usize;
        assert!(0 < opaque && opaque < triangles.len(), "{opaque}");
        assert!(!triangles[..opaque].iter().any(see_through));
        assert!(triangles[opaque..].iter().all(see_through));
    }

    /// A solid stays wound outward in world space under a mirroring
    /// transform (the triangle pass skips a solid's faces turned away from
    /// the light by their winding).
    #[test]
    fn mirrored_solids_stay_wound_outward() {
        use crate::scene::{Material, shapes};
        use glam::{Mat4, Vec3};
        for scale in [
            Vec3::ONE,
            Vec3::new(-1.0, 1.0, 1.0),
            Vec3::new(1.0, -2.0, -1.0),
            Vec3::splat(-1.0),
        ] {
            let mut scene = Scene::new("mirror");
            let mesh = scene.add_mesh(shapes::cuboid(Vec3::new(1.0, 2.0, 3.0)));
            let material = scene.add_material(Material::default());
            let transform =
                Mat4::from_translation(Vec3::new(4.0, 1.0, -2.0)) * Mat4::from_scale(scale);
            scene.add_object("box", mesh, material, transform);
            let volume: f32 = caster_triangles(&scene)
                .triangles
                .iter()
                .map(|t| t.a.truncate().dot(t.b.truncate().cross(t.c.truncate())) / 6.0)
                .sum();
            let expected = 6.0 * (scale.x * scale.y * scale.z).abs();
            assert!(
                (volume - expected).abs() < 1e-3,
                "{scale}: volume {volume}, expected {expected}"
            );
        }
    }
}
