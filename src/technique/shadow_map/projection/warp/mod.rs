//! Light-space perspective shadow maps, LiSPSM (Wimmer, Scherzer &
//! Purgathofer 2004; [000] §4, [001] §3, [002] §2): a perspective transform inside the light's
//! view, its axis along the view direction projected onto the light's
//! plane, spends more of the map near the camera. The projection centre
//! stands n_opt = (z_n + √(z_n·z_f)) / sin γ before the body (γ the angle
//! between view and light directions); as γ → 0 (light along the view) n
//! grows without bound and the warp relaxes to the uniform map.

mod body;
mod psm;
mod tsm;

pub use self::body::SeenPrism;

use self::body::warp_body;
use self::psm::psm;
use self::tsm::tsm;
use super::setup::{LightSetup, light_view_of_scene, linear_depth_row};
use crate::scene::{Aabb, Camera};
use crate::technique::shadow_map::config::partition::{Warp, WarpParams};
use glam::{Mat4, Vec3, Vec4};

/// Below this sin γ the light runs along the view: no warp (uniform map).
pub const MIN_SIN_GAMMA: f32 = 1e-3;

/// A warped map: its world → light-clip matrix (wgpu depth [0, 1]) and the
/// row that gives a point's depth linear along the light (0 nearest it, 1
/// farthest, over the scene) — what the map stores instead of the
/// perspective's z/w.
#[derive(Clone, Copy, Debug)]
pub struct Warped {
    pub view_proj: Mat4,
    pub depth_row: Vec4,
}

/// sin γ between the camera's view direction and the light direction.
pub fn sin_gamma(camera: &Camera, light_dir: Vec3) -> f32 {
    let v = (camera.target - camera.eye).normalize();
    v.cross(light_dir.normalize()).length()
}

/// The optimal projection-centre distance for view depths `z_near` to
/// `z_far` at sin γ (Wimmer et al. 2004, eq. 4).
pub fn n_opt(z_near: f32, z_far: f32, sin_gamma: f32) -> f32 {
    (z_near + (z_near * z_far).sqrt()) / sin_gamma
}

/// The light's view for the warp: looking along `light_dir` from outside
/// `scene`, its y axis along the view direction projected onto the
/// light's plane (so the camera's near end has the smallest y).
pub fn warp_light_view(camera: &Camera, light_dir: Vec3, scene: &Aabb) -> Mat4 {
    let l = light_dir.normalize();
    let v = (camera.target - camera.eye).normalize();
    let up = (v - l * l.dot(v)).normalize();
    let r = scene.bounding_radius();
    glam::camera::rh::view::look_to_mat4(scene.center() - l * (2.0 * r), l, up)
}

/// The perspective along +y of the light's view with its centre `n` before
/// `y_min`, mapping y ∈ [y_min, y_min + d] to [−1, 1] (x and z unchanged
/// before the division by w = y − y_min + n).
pub fn perspective_along_y(y_min: f32, d: f32, n: f32) -> Mat4 {
    let f = n + d;
    let (a, b) = ((f + n) / (f - n), -2.0 * f * n / (f - n));
    let eye_y = y_min - n;
    Mat4::from_cols(
        Vec4::new(1.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, a, 0.0, 1.0),
        Vec4::new(0.0, 0.0, 1.0, 0.0),
        Vec4::new(0.0, -a * eye_y + b, 0.0, -eye_y),
    )
}

/// The LiSPSM matrix covering `body` (world points the map must cover,
/// e.g. the corners of the camera's view or of a cascade's slice), with
/// every caster of `scene` towards the light; `z_near`, `z_far` the body's
/// view depths; `n_override` > 0 replaces n_opt. `None` when the light
/// runs along the view (use the uniform map).
pub fn lispsm(
    camera: &Camera,
    light_dir: Vec3,
    scene: &Aabb,
    body: &[Vec3],
    (z_near, z_far): (f32, f32),
    n_override: f32,
) -> Option<Warped> {
    let sin_g = sin_gamma(camera, light_dir);
    if sin_g < MIN_SIN_GAMMA || body.is_empty() {
        return None;
    }
    let view = warp_light_view(camera, light_dir, scene);
    let scene_ls = scene.transformed(view);
    let body_ls = Aabb::from_points(body.iter().map(|p| view.transform_point3(*p)));
    let d = (body_ls.max.y - body_ls.min.y).max(1e-4);
    let n = if n_override > 0.0 {
        n_override
    } else {
        n_opt(z_near.max(1e-4), z_far.max(z_near * 1.001), sin_g)
    };
    let perspective = perspective_along_y(body_ls.min.y, d, n);
    // The body in warped space, stretched along the light to every caster.
    let mut fit = Aabb::from_points(std::iter::empty());
    for p in body {
        let q = view.transform_point3(*p);
        for z in [scene_ls.min.z, scene_ls.max.z] {
            let c = perspective * Vec4::new(q.x, q.y, z, 1.0);
            fit = fit.with_point(c.truncate() / c.w);
        }
    }
    let (min, max) = (fit.min, fit.max);
    let size = (max - min).max(Vec3::splat(1e-6));
    // x, y to [−1, 1]; z: nearest the light (largest z) to 0.
    let to_clip = Mat4::from_cols(
        Vec4::new(2.0 / size.x, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 2.0 / size.y, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -1.0 / size.z, 0.0),
        Vec4::new(
            -(max.x + min.x) / size.x,
            -(max.y + min.y) / size.y,
            max.z / size.z,
            1.0,
        ),
    );
    Some(Warped {
        view_proj: to_clip * perspective * view,
        depth_row: view.transpose() * linear_depth_row(&scene_ls),
    })
}

/// What the frame's reduction saw, for a warped map fitted to it: the view
/// depths of the pixels and, for one map fitted to the samples, the prism
/// around them ([`SeenPrism`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct SeenView {
    pub depths: Option<(f32, f32)>,
    pub prism: Option<SeenPrism>,
}

/// Warps a directional light's setup in place: each face (the one map, or
/// each cascade) by PSM, LiSPSM or TSM over its part of the view of `camera`
/// (one map of `size`²: inside `seen`'s prism where it has one); faces whose
/// light runs along the view stay uniform.
pub fn warp_setup(
    setup: &mut LightSetup,
    (camera, aspect): (&Camera, f32),
    light_dir: Vec3,
    scene: &Aabb,
    (params, size): (&WarpParams, u32),
    seen: SeenView,
) {
    let ranges: Vec<(f32, f32)> = match &setup.cascades {
        Some(split) => std::iter::once(split.near)
            .chain(split.far.iter().copied())
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| (w[0], w[1]))
            .collect(),
        None => vec![
            seen.depths
                .unwrap_or_else(|| (camera.near, camera.reach(scene).max(camera.near * 1.01))),
        ],
    };
    let view = camera.view();
    for (face, (z0, z1)) in setup.faces.iter_mut().zip(ranges) {
        // The body: the part of the view inside the scene (Wimmer et al.'s
        // convex body B), and its view depths for n_opt.
        let prism = seen.prism.as_ref().filter(|_| setup.cascades.is_none());
        let body = warp_body(&camera.slice_corners(aspect, z0, z1), scene, prism, size);
        let depths = body.iter().map(|p| -view.transform_point3(*p).z);
        let near = depths.clone().fold(f32::MAX, f32::min).max(camera.near);
        let far = depths.fold(0.0f32, f32::max).max(near * 1.001);
        let warped = match params.kind {
            Warp::None => None,
            Warp::Psm => psm(camera, aspect, light_dir, scene, &body, (near, far)).map(|(w, _)| w),
            Warp::Lispsm => lispsm(
                camera,
                light_dir,
                scene,
                &body,
                (near, far),
                params.lispsm_n,
            ),
            Warp::Tsm => tsm(
                camera,
                light_view_of_scene(light_dir, scene).0,
                scene,
                &body,
                (near, far),
                params.tsm_focus,
            ),
        };
        if let Some(w) = warped {
            *face = w.view_proj;
            setup.warp_depth = Some(w.depth_row);
            // Warped depth is linear along the light, not the window's.
            setup.moment_depth = None;
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::technique::shadow_map::projection::setup::clip_to_bounds;

    pub(in crate::technique::shadow_map) fn ndc(m: Mat4, p: Vec3) -> Vec3 {
        let c = m * p.extend(1.0);
        c.truncate() / c.w
    }

    /// A 1 m step on the ground beside a camera at (0, 2, 40) looking at the
    /// origin spans more than 3× the map that the same step 60 m away does.
    pub(in crate::technique::shadow_map) fn assert_magnifies_near_the_camera(view_proj: Mat4) {
        let span = |p: Vec3| {
            (ndc(view_proj, p + Vec3::X) - ndc(view_proj, p))
                .truncate()
                .length()
        };
        let (near, far) = (Vec3::new(0.0, 0.0, 35.0), Vec3::new(0.0, 0.0, -20.0));
        assert!(
            span(near) > 3.0 * span(far),
            "{} vs {}",
            span(near),
            span(far)
        );
    }

    #[test]
    fn the_perspective_maps_its_range_to_minus_one_one() {
        // y from 2 to 7 with the centre 3 before y = 2 (at y = −1).
        let p = perspective_along_y(2.0, 5.0, 3.0);
        assert!((ndc(p, Vec3::new(0.0, 2.0, 0.0)).y + 1.0).abs() < 1e-5);
        assert!((ndc(p, Vec3::new(0.0, 7.0, 0.0)).y - 1.0).abs() < 1e-5);
        // x and z shrink with the distance from the centre: 1 / (y + 1).
        let q = ndc(p, Vec3::new(6.0, 5.0, -3.0));
        assert!((q.x - 1.0).abs() < 1e-5 && (q.z + 0.5).abs() < 1e-5, "{q}");
    }

    #[test]
    fn n_opt_follows_the_paper_and_grows_as_the_light_turns_into_the_view() {
        // z_n = 1, z_f = 100: (1 + 10) / sin γ.
        assert!((n_opt(1.0, 100.0, 1.0) - 11.0).abs() < 1e-5);
        assert!((n_opt(1.0, 100.0, 0.5) - 22.0).abs() < 1e-5);
        let cam = Camera::new(Vec3::new(0.0, 2.0, 10.0), Vec3::new(0.0, 2.0, 0.0));
        assert!((sin_gamma(&cam, Vec3::new(0.0, -1.0, 0.0)) - 1.0).abs() < 1e-6);
        assert!(sin_gamma(&cam, Vec3::new(0.0, 0.0, -1.0)) < 1e-6);
    }

    /// Every body point lands inside the map; points near the camera get
    /// more of the map than with the uniform fit (the purpose of the warp);
    /// with the light along the view the warp is off.
    #[test]
    fn the_warp_covers_the_body_and_magnifies_near_the_camera() {
        let scene = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 10.0, 50.0),
        };
        let cam = Camera::new(Vec3::new(0.0, 2.0, 40.0), Vec3::new(0.0, 0.0, 0.0));
        let body = cam.slice_corners(1.5, 0.5, 80.0);
        let light = Vec3::new(1.0, -1.0, 0.2);
        let w = lispsm(&cam, light, &scene, &body, (0.5, 80.0), 0.0).unwrap();
        for p in body {
            let q = ndc(w.view_proj, p);
            assert!(
                q.x.abs() <= 1.0 + 1e-3 && q.y.abs() <= 1.0 + 1e-3,
                "{p} → {q}"
            );
            // Depth covers the scene's casters (corners outside the scene
            // may fall outside [0, 1]; nothing is there).
            let inside_scene = p.cmpge(scene.min).all() && p.cmple(scene.max).all();
            assert!(
                !inside_scene || (-1e-3..=1.0 + 1e-3).contains(&q.z),
                "{p} → {q}"
            );
        }
        assert_magnifies_near_the_camera(w.view_proj);
        // Depth still orders points along the light: nearer the light, smaller.
        let ground = Vec3::new(5.0, 0.0, 10.0);
        let above = ground - light.normalize() * 3.0;
        assert!(ndc(w.view_proj, above).z < ndc(w.view_proj, ground).z);
        let (a, b) = (ndc(w.view_proj, above), ndc(w.view_proj, ground));
        assert!(
            (a.truncate() - b.truncate()).length() < 1e-4,
            "same texel: {a} {b}"
        );
        // The stored depth is linear along the light: 3 m towards the light
        // is 3 / (the scene's extent along the light) less, anywhere.
        let lin = |p: Vec3| w.depth_row.dot(p.extend(1.0));
        let ls = scene.transformed(warp_light_view(&cam, light, &scene));
        let extent = ls.size().z + 2.0 * ls.margin();
        for ground in [Vec3::new(5.0, 0.0, 10.0), Vec3::new(-30.0, 4.0, -40.0)] {
            let step = lin(ground) - lin(ground - light.normalize() * 3.0);
            assert!(
                (step - 3.0 / extent).abs() < 1e-4,
                "{step} vs {}",
                3.0 / extent
            );
        }
        // Over the scene it spans [0, 1], 0 at the corner nearest the light.
        let depths: Vec<f32> = scene.corners().iter().map(|c| lin(*c)).collect();
        let (lo, hi) = depths
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &d| (a.min(d), b.max(d)));
        assert!(
            lo > 0.0 && lo < 1e-3 && hi < 1.0 && hi > 1.0 - 1e-3,
            "{lo} {hi}"
        );
        // The light along the view direction: no warp.
        let along = cam.target - cam.eye;
        assert!(lispsm(&cam, along, &scene, &body, (0.5, 80.0), 0.0).is_none());
    }

    /// A single warped map warps the view between the depths the camera
    /// saw: the seen slice stays inside the map under every warp and takes
    /// more of it than under the whole view's warp.
    #[test]
    fn one_warped_map_warps_the_seen_depths() {
        use crate::technique::shadow_map::projection::setup::MapProjection;
        let scene = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 10.0, 50.0),
        };
        let cam = Camera::new(Vec3::new(0.0, 2.0, 40.0), Vec3::new(0.0, 0.0, 0.0));
        let light = Vec3::new(1.0, -1.0, 0.2);
        let (z0, z1) = (20.0, 35.0);
        let slice = clip_to_bounds(&cam.slice_corners(1.5, z0, z1), &scene);
        // The area of the map the slice's image spans (its box in NDC).
        let share = |kind: Warp, seen: Option<(f32, f32)>| {
            let mut setup = LightSetup {
                faces: vec![Mat4::IDENTITY],
                near: 0.0,
                far: 1.0,
                projection: MapProjection::Orthographic,
                texel_scale: 1.0,
                cascades: None,
                warp_depth: None,
                moment_depth: None,
            };
            let params = WarpParams {
                kind,
                lispsm_n: 0.0,
                tsm_focus: 0.0,
            };
            let seen = SeenView {
                depths: seen,
                prism: None,
            };
            warp_setup(
                &mut setup,
                (&cam, 1.5),
                light,
                &scene,
                (&params, 2048),
                seen,
            );
            assert!(setup.warp_depth.is_some(), "{kind:?}");
            let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            for c in &slice {
                let q = ndc(setup.faces[0], *c);
                assert!(
                    q.x.abs() <= 1.0 + 1e-3 && q.y.abs() <= 1.0 + 1e-3,
                    "{kind:?} {c} → {q}"
                );
                (lo, hi) = (lo.min(q), hi.max(q));
            }
            (hi.x - lo.x) * (hi.y - lo.y) / 4.0
        };
        for kind in [Warp::Psm, Warp::Lispsm, Warp::Tsm] {
            let whole = share(kind, None);
            let seen = share(kind, Some((z0, z1)));
            assert!(
                seen > 1.2 * whole && seen > 0.5,
                "{kind:?}: {seen} vs {whole}"
            );
        }
    }
}
