//! Convex solids given by their planes: the faces of a view slice, of a
//! box, and the vertices of their intersection with any other half-spaces
//! (a warp's body cut to the pixels seen, a spot map's view of the
//! frustum).

use crate::scene::Aabb;
use glam::{Mat3, Mat4, Vec3};

/// A half-space `(n, d)`: the points p with n·p ≤ d.
pub type HalfSpace = (Vec3, f32);

/// A convex hexahedron's six face planes (corners numbered as
/// [`super::setup::clip_to_bounds`] takes them), each `(n, d)`: n outwards, n·p ≤ d inside.
pub fn hexahedron_planes(corners: &[Vec3; 8]) -> Vec<HalfSpace> {
    let centre = corners.iter().copied().sum::<Vec3>() / 8.0;
    (0..3)
        .flat_map(|axis| [0, 1].map(move |side| (axis, side)))
        .map(|(axis, side)| {
            let on: Vec<Vec3> = (0..8)
                .filter(|i| (i >> axis) & 1 == side)
                .map(|i| corners[i])
                .collect();
            // Face corners in bit order; the diagonal pairs span the face.
            let mut n = (on[3] - on[0]).cross(on[2] - on[1]).normalize_or_zero();
            if n.dot(on[0] - centre) < 0.0 {
                n = -n;
            }
            (n, n.dot(on[0]))
        })
        .collect()
}

/// A box's six faces, outwards.
pub fn box_planes(b: &Aabb) -> Vec<HalfSpace> {
    (0..3)
        .flat_map(|axis| {
            let n = Vec3::AXES[axis];
            [(n, b.max[axis]), (-n, -b.min[axis])]
        })
        .collect()
}

/// A half-space of a rigid view's space (a·v ≤ b, v = R·p + t) in world
/// space: (Rᵀa)·p ≤ b − a·t.
pub fn from_view(view: Mat4, (a, b): HalfSpace) -> HalfSpace {
    let t = view.w_axis.truncate();
    (Mat3::from_mat4(view).transpose() * a, b - a.dot(t))
}

/// The vertices of the convex solid {p : n·p ≤ d for every plane}: the
/// meeting points of each three planes that lie inside all the others
/// (within a tolerance relative to `scale`, the solid's size).
pub fn polytope_vertices(planes: &[HalfSpace], scale: f32) -> Vec<Vec3> {
    let tolerance = 1e-4 * scale;
    let inside = |p: Vec3| planes.iter().all(|&(n, d)| n.dot(p) - d <= tolerance);
    let mut out = vec![];
    for (i, &(n0, d0)) in planes.iter().enumerate() {
        for (j, &(n1, d1)) in planes.iter().enumerate().skip(i + 1) {
            let n01 = n0.cross(n1);
            if n01.length_squared() < 1e-10 {
                continue;
            }
            for &(n2, d2) in &planes[j + 1..] {
                let det = n01.dot(n2);
                if det.abs() < 1e-6 {
                    continue;
                }
                // Cramer's rule in its vector form.
                let p = (n1.cross(n2) * d0 + n2.cross(n0) * d1 + n01 * d2) / det;
                if p.is_finite() && inside(p) {
                    out.push(p);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box_planes() -> Vec<HalfSpace> {
        box_planes(&Aabb {
            min: Vec3::NEG_ONE,
            max: Vec3::ONE,
        })
    }

    #[test]
    fn a_box_of_half_spaces_has_its_eight_corners() {
        let v = polytope_vertices(&unit_box_planes(), 2.0);
        assert_eq!(v.len(), 8);
        assert!(v.iter().all(|p| (p.abs() - Vec3::ONE).length() < 1e-5));
    }

    #[test]
    fn a_plane_across_the_box_cuts_off_its_corner() {
        let mut planes = unit_box_planes();
        // x + y + z ≤ 2: cuts the corner (1, 1, 1) at (1, 1, 0) and its turns.
        planes.push((Vec3::ONE.normalize(), 2.0 / 3f32.sqrt()));
        let v = polytope_vertices(&planes, 2.0);
        assert!(!v.iter().any(|p| (*p - Vec3::ONE).length() < 1e-4));
        for want in [
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ] {
            assert!(v.iter().any(|p| (*p - want).length() < 1e-4), "{want}");
        }
    }
}
