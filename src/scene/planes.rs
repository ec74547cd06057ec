//! Receiver planes of a scene (planar shadows, and `compare`'s split of
//! the error by receiver): its `ShadowPlane` objects, else its largest
//! planar shadow receiver.

use super::{Object, Scene};
use glam::{Vec3, Vec4};

/// At most this many receiver planes are used.
pub const MAX_PLANES: usize = 8;

/// A receiver plane `(A, B, C, D)` with unit normal, from a scene object.
#[derive(Clone, Debug, PartialEq)]
pub struct ReceiverPlane {
    pub equation: Vec4,
    pub object: usize,
}

fn plane_of(a: Vec3, b: Vec3, c: Vec3) -> Option<Vec4> {
    let n = (b - a).cross(c - a).try_normalize()?;
    Some(n.extend(-n.dot(a)))
}

fn world_positions(scene: &Scene, o: &Object) -> impl Iterator<Item = Vec3> {
    scene.meshes[o.mesh]
        .positions
        .iter()
        .map(move |&p| o.transform.transform_point3(p))
}

/// The receiver planes of a scene: its `shadow_plane` objects (plane of the
/// first triangle), else the largest planar shadow-receiving object; none
/// where the scene has neither.
pub fn receiver_planes(scene: &Scene) -> Vec<ReceiverPlane> {
    let mut planes = vec![];
    for (i, o) in scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.shadow_plane)
    {
        let m = &scene.meshes[o.mesh];
        if let Some(t) = m.indices.chunks_exact(3).next() {
            let p = |k: usize| o.transform.transform_point3(m.positions[t[k] as usize]);
            if let Some(eq) = plane_of(p(0), p(1), p(2)) {
                planes.push(ReceiverPlane {
                    equation: eq,
                    object: i,
                });
            }
        }
    }
    if !planes.is_empty() {
        planes.truncate(MAX_PLANES);
        return planes;
    }
    let tol = scene.bounds().size().length().max(1e-3) * 1e-5;
    let mut best: Option<(f32, ReceiverPlane)> = None;
    for (i, o) in scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.receives_shadow)
    {
        let m = &scene.meshes[o.mesh];
        let Some(t) = m.indices.chunks_exact(3).next() else {
            continue;
        };
        let p = |k: u32| o.transform.transform_point3(m.positions[k as usize]);
        let Some(eq) = plane_of(p(t[0]), p(t[1]), p(t[2])) else {
            continue;
        };
        if world_positions(scene, o).any(|v| eq.dot(v.extend(1.0)).abs() > tol) {
            continue;
        }
        let area: f32 = m
            .indices
            .chunks_exact(3)
            .map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length() * 0.5)
            .sum();
        if best.as_ref().is_none_or(|(a, _)| area > *a) {
            best = Some((
                area,
                ReceiverPlane {
                    equation: eq,
                    object: i,
                },
            ));
        }
    }
    match best {
        Some((area, p)) => {
            log::info!(
                "planar: no ShadowPlane object; using the largest planar receiver '{}' (area {area:.2})",
                scene.objects[p.object].name
            );
            vec![p]
        }
        // The planar technique says so; other users (compare's on-plane
        // pixels) need no plane.
        None => vec![],
    }
}
