//! The view depths at which a camera meets the scene's geometry: its
//! frustum clipped to each cluster's bounds, not to the scene's one box. A
//! camera standing in a scene sees nothing before its floor meets the
//! frustum's lower plane, and cascades split from the near plane spend
//! their finest maps on that empty space; Filament likewise splits its
//! cascades over the view-space depths of the visible receivers
//! (`computeSceneCascadeParams`' `vsNearFar`).

use super::setup::clip_to_bounds;
use crate::scene::{Aabb, Camera};

/// The least and greatest view depth, within `[camera.near, reach]`, of the
/// points where the camera's frustum (frame aspect `aspect`) meets any of
/// `parts`; `None` when it meets none.
pub fn geometry_depths(
    camera: &Camera,
    aspect: f32,
    parts: &[Aabb],
    reach: f32,
) -> Option<(f32, f32)> {
    let near = camera.near;
    let reach = reach.max(near * 1.001);
    let frustum = camera.slice_corners(aspect, near, reach);
    let view = camera.view();
    let depth = |p: glam::Vec3| -view.transform_point3(p).z;
    let mut range: Option<(f32, f32)> = None;
    for part in parts.iter().filter(|b| !b.is_empty()) {
        // A box whose corners' depths lie within the range found so far
        // cannot widen it; one wholly before or past the slice misses it.
        let (lo, hi) = part
            .corners()
            .into_iter()
            .map(depth)
            .fold((f32::MAX, f32::MIN), |(lo, hi), d| (lo.min(d), hi.max(d)));
        if hi < near || lo > reach || range.is_some_and(|(a, b)| lo >= a && hi <= b) {
            continue;
        }
        for d in clip_to_bounds(&frustum, part).into_iter().map(depth) {
            let d = d.clamp(near, reach);
            range = Some(range.map_or((d, d), |(a, b)| (a.min(d), b.max(d))));
        }
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A camera 1.6 above an infinite-looking floor, level, 50° high: the
    /// floor meets the frustum's lower plane at 1.6 / tan 25° ahead, and
    /// its far edge 20 ahead bounds the view.
    #[test]
    fn a_floor_is_seen_from_where_the_frustum_meets_it() {
        let camera = Camera {
            near: 0.1,
            far: 200.0,
            ..Camera::new(Vec3::new(0.0, 1.6, 0.0), Vec3::new(0.0, 1.6, -1.0))
        };
        let floor = Aabb {
            min: Vec3::new(-20.0, 0.0, -20.0),
            max: Vec3::new(20.0, 0.0, 20.0),
        };
        let (near, far) = geometry_depths(&camera, 1.0, &[floor], 100.0).unwrap();
        let expected = 1.6 / 25f32.to_radians().tan();
        assert!(
            (near - expected).abs() < 1e-3 * expected,
            "{near} vs {expected}"
        );
        assert!((far - 20.0).abs() < 1e-3, "{far}");
        // A post 5 ahead, 1 to the side: seen from its face at depth 5.
        let post = Aabb {
            min: Vec3::new(0.9, 0.0, -5.1),
            max: Vec3::new(1.0, 3.0, -4.9),
        };
        let (near, far) = geometry_depths(&camera, 1.0, &[post], 100.0).unwrap();
        assert!(
            (near - 4.9).abs() < 1e-3 && (far - 5.1).abs() < 1e-3,
            "{near} {far}"
        );
        // Behind the camera: not seen.
        let behind = Aabb {
            min: Vec3::new(-1.0, 0.0, 2.0),
            max: Vec3::new(1.0, 3.0, 3.0),
        };
        assert_eq!(geometry_depths(&camera, 1.0, &[behind], 100.0), None);
    }
}
