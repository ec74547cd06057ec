//! The convex body B a warped map covers (Wimmer et al. 2004, §4): the
//! camera's view between the depths it sees, inside the scene, and — with
//! `fit=samples` — inside the prism along the light around the pixels the
//! map shades (SDSM's support extents, Lauritzen, Salvi & Lefohn 2011).
//! Without the prism, B spans the whole width of the view wherever the
//! scene does: a camera on open ground sees far less of it laterally than
//! its frustum holds, and the warp spreads its texels over all of it.

use super::super::convex::{
    HalfSpace, box_planes, from_view, hexahedron_planes, polytope_vertices,
};
use super::super::roll::{Supports, turn_angle};
use super::super::setup::clip_to_bounds;
use crate::scene::Aabb;
use glam::{Mat4, Vec2, Vec3};

/// The kernel's reach past the outermost pixel the prism holds, as a
/// fraction of the prism's half-width per texel of the map's side: a
/// warped map's texels differ in size across it, so 16 texels of an
/// unwarped map over the same width, where the PCF grid, the normal offset
/// and the coarsest texels at the body's far end stay inside the map.
const KERNEL_REACH_TEXELS: f32 = 16.0;

/// The pixels a single warped map shades: their support extents in the
/// image of the light view `view` (world → light view, rigid), from the
/// frame's reduction.
#[derive(Clone, Copy, Debug)]
pub struct SeenPrism {
    pub view: Mat4,
    pub supports: Supports,
}

impl SeenPrism {
    /// The prism's faces in world space, widened for the kernel of a map
    /// `size` texels wide.
    fn planes(&self, size: u32) -> Vec<HalfSpace> {
        let widened = self
            .supports
            .widened(2.0 * KERNEL_REACH_TEXELS / size.max(1) as f32);
        widened
            .0
            .iter()
            .enumerate()
            .flat_map(|(k, &[lo, hi])| {
                let a = Vec2::from_angle(turn_angle(k)).extend(0.0);
                [(a, hi), (-a, -lo)].map(|half_space| from_view(self.view, half_space))
            })
            .collect()
    }
}

/// B for the view slice `corners` ([`Camera::slice_corners`](crate::scene::Camera::slice_corners)
/// order) in `scene`, cut by `prism` where the frame's reduction has one:
/// the vertices of the convex solid. The uncut body where the cut leaves
/// nothing (a prism measured for another view).
pub fn warp_body(
    corners: &[Vec3; 8],
    scene: &Aabb,
    prism: Option<&SeenPrism>,
    size: u32,
) -> Vec<Vec3> {
    let Some(prism) = prism else {
        return clip_to_bounds(corners, scene);
    };
    let mut planes = hexahedron_planes(corners);
    planes.extend(box_planes(scene));
    planes.extend(prism.planes(size));
    let scale = (scene.size().length() + (corners[7] - corners[0]).length()).max(1.0);
    let cut = polytope_vertices(&planes, scale);
    if cut.is_empty() {
        clip_to_bounds(corners, scene)
    } else {
        cut
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prism_narrows_the_body_to_the_seen_pixels_and_keeps_the_light_axis() {
        // The light looks down −y; its view's image is world x, z.
        let view =
            glam::camera::rh::view::look_to_mat4(Vec3::new(0.0, 10.0, 0.0), -Vec3::Y, Vec3::Z);
        let scene = Aabb {
            min: Vec3::new(-10.0, 0.0, -10.0),
            max: Vec3::new(10.0, 5.0, 10.0),
        };
        // Pixels seen around x ∈ [2, 3], z ∈ [−1, 1] on the ground.
        let seen = [(2.0, -1.0), (3.0, -1.0), (2.0, 1.0), (3.0, 1.0)]
            .map(|(x, z)| view.transform_point3(Vec3::new(x, 0.0, z)).truncate());
        let prism = SeenPrism {
            view,
            supports: Supports::of_points(seen).unwrap(),
        };
        // A slice that holds the whole scene.
        let corners: [Vec3; 8] = std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { -20.0 } else { 20.0 },
                if i & 2 == 0 { -20.0 } else { 20.0 },
                if i & 4 == 0 { -20.0 } else { 20.0 },
            )
        });
        let body = warp_body(&corners, &scene, Some(&prism), 2048);
        let b = Aabb::from_points(body.iter().copied());
        // Widened by the kernel's reach (a few hundredths), no more.
        assert!(b.min.x > 1.9 && b.max.x < 3.1, "{b:?}");
        assert!(b.min.z > -1.1 && b.max.z < 1.1, "{b:?}");
        // Along the light, the scene's whole height: casters above stay in.
        assert!(
            (b.min.y - 0.0).abs() < 1e-3 && (b.max.y - 5.0).abs() < 1e-3,
            "{b:?}"
        );
        // Without a prism, the scene's box.
        let whole = Aabb::from_points(warp_body(&corners, &scene, None, 2048));
        assert!((whole.min - scene.min).length() < 1e-3 && (whole.max - scene.max).length() < 1e-3);
    }
}
