//! Which casters can shadow what the camera sees under a directional
//! light: a caster shadows a receiver only if it lies on the receiver's
//! ray towards the light, so it must overlap, seen from the light, the
//! camera's view of the scene, and reach nearer the light than the
//! farthest of it. A light view's clip volume (a cascade's square, deep
//! enough for every caster) holds much more than that: the last cascade of
//! a camera looking to the horizon is a square around its bounding sphere,
//! where the view itself is a wedge, and under a low sun only casters within
//! a caster's height over the wedge's sweep towards the sun matter — the
//! caster culling volume of Bittner et al. 2011 ("Shadow caster culling for
//! efficient shadow mapping"), here as the light-image extents of the view
//! along the 16 directions of [`Supports`] (a 16-sided outer polygon).

use super::roll::Supports;
use super::setup::{light_view_of_scene, view_in_scene};
use crate::scene::{Aabb, Camera};
use glam::{Mat4, Vec3};

/// The camera's view of the scene as a directional light sees it.
pub struct CasterCull {
    /// The light's view (looking along its direction; nearer the light is
    /// larger z).
    view: Mat4,
    /// The view's extents in the light's image.
    receivers: Supports,
    /// The least light-view z of the view: the receiver farthest from the
    /// light.
    farthest: f32,
}

impl CasterCull {
    /// The view of `camera` (frame aspect `aspect`) within `scene_bounds`,
    /// under a light travelling along `dir`; `None` when the camera sees
    /// none of the scene (nothing to cull for).
    pub fn of(dir: Vec3, camera: &Camera, aspect: f32, scene_bounds: &Aabb) -> Option<CasterCull> {
        let view = light_view_of_scene(dir, scene_bounds).0;
        let seen: Vec<Vec3> = view_in_scene(
            camera,
            aspect,
            scene_bounds,
            camera.near,
            camera.reach(scene_bounds),
        )
        .into_iter()
        .map(|p| view.transform_point3(p))
        .collect();
        // A margin for the clip's rounding: a thousandth of the scene.
        let margin = scene_bounds.size().length() * 1e-3;
        let receivers = Supports::of_points(seen.iter().map(|p| p.truncate()))?.grown(margin);
        let farthest = seen.iter().map(|p| p.z).fold(f32::MAX, f32::min) - margin;
        Some(CasterCull {
            view,
            receivers,
            farthest,
        })
    }

    /// Whether a caster within `bounds` may shadow part of the view.
    pub fn may_shadow(&self, bounds: &Aabb) -> bool {
        let corners = bounds.corners().map(|c| self.view.transform_point3(c));
        let nearest_light = corners.iter().map(|p| p.z).fold(f32::MIN, f32::max);
        nearest_light >= self.farthest
            && Supports::of_points(corners.iter().map(|p| p.truncate()))
                .is_some_and(|s| s.overlaps(&self.receivers))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_casters_over_the_view_or_sunward_within_their_shadows_reach_are_kept() {
        // A camera 2 m up at the origin looking along −z (60°, square
        // frame) over a 200 m square scene 0 .. 20 m high; the sun 30° up
        // in the +x sky, its light travelling along −x and down. At 30 m
        // ahead the view is ±17.3 m wide.
        let scene = Aabb {
            min: Vec3::new(-100.0, 0.0, -100.0),
            max: Vec3::new(100.0, 20.0, 100.0),
        };
        let mut camera = Camera::new(Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 2.0, -10.0));
        camera.fov_y_deg = 60.0;
        camera.near = 0.1;
        let elevation = 30f32.to_radians();
        let dir = Vec3::new(-elevation.cos(), -elevation.sin(), 0.0);
        let cull = CasterCull::of(dir, &camera, 1.0, &scene).expect("the camera sees the scene");
        // A 2 m × 10 m × 2 m post at (x, z): its shadow reaches
        // 10 / tan 30° = 17.3 m away from the sun.
        let post = |x: f32, z: f32| Aabb {
            min: Vec3::new(x - 1.0, 0.0, z - 1.0),
            max: Vec3::new(x + 1.0, 10.0, z + 1.0),
        };
        assert!(cull.may_shadow(&post(0.0, -30.0)), "in the view");
        assert!(
            cull.may_shadow(&post(30.0, -30.0)),
            "sunward, its shadow reaching x = 11.7"
        );
        assert!(
            !cull.may_shadow(&post(60.0, -30.0)),
            "sunward, its shadow ending at x = 41.7"
        );
        assert!(!cull.may_shadow(&post(-90.0, -30.0)), "away from the sun");
        assert!(!cull.may_shadow(&post(0.0, 50.0)), "behind the camera");
        // The post in the view moved 300 m on along the light: seen from
        // the light it covers the same part of the view, but lies beyond it.
        let beyond = post(0.0, -30.0);
        let beyond = Aabb {
            min: beyond.min + dir * 300.0,
            max: beyond.max + dir * 300.0,
        };
        assert!(!cull.may_shadow(&beyond), "beyond the view along the light");
    }
}
