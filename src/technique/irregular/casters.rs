//! The caster triangles the irregular z-buffer tests its samples against:
//! every shadow-casting object's triangles in world space, with their
//! texture coordinates and object (for cut-outs), listed once per scene.

use crate::scene::Scene;
use bytemuck::{Pod, Zeroable};
use glam::Vec4;

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
}

/// The triangles of `scene`'s shadow casters, wound in world space as in
/// their mesh (an object mirrored by its transform has two corners
/// swapped), so that a solid's stay wound outward; opaque materials' first,
/// each part in the scene's order. The back faces a double-sided material
/// added are left out: the exact test does not depend on a triangle's
/// winding, so they would test every sample twice.
pub fn caster_triangles(scene: &Scene) -> Casters {
    let (mut opaque, mut see_through) = (vec![], vec![]);
    for (index, o) in scene.objects.iter().enumerate() {
        if !o.casts_shadow || o.shadow_plane {
            continue;
        }
        let m = &scene.meshes[o.mesh];
        let front_faces = if m.sides_doubled {
            m.triangle_count() / 2
        } else {
            m.triangle_count()
        };
        let object = f32::from_bits(index as u32);
        let mirrored = o.transform.determinant() < 0.0;
        let out = if scene.materials[o.material].is_see_through() {
            &mut see_through
        } else {
            &mut opaque
        };
        for t in m.indices.chunks_exact(3).take(front_faces) {
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
            out.push(CasterTriangle {
                a,
                b,
                c,
                v: Vec4::new(va, vb, vc, object),
            });
        }
    }
    let count = opaque.len() as u32;
    opaque.append(&mut see_through);
    Casters {
        triangles: opaque,
        opaque: count,
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
        let t = &triangles[0];
        let object = t.v.w.to_bits() as usize;
        let o = &scene.objects[object];
        let m = &scene.meshes[o.mesh];
        let first = o
            .transform
            .transform_point3(m.positions[m.indices[0] as usize]);
        assert!((t.a.truncate() - first).length() < 1e-5);
        assert!(o.casts_shadow);
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
