//! Perspective shadow maps, PSM (Stamminger & Drettakis 2002; [000] §4, [001] §3, [002] §2):
//! the map is rendered in the camera's post-perspective space (PPS), where
//! objects near the camera are already large. A directional light becomes
//! a point light there, at h = M·(−L, 0) with M the camera's view-projection:
//! every point at infinity lands on the plane z = f/(f − n) beyond the far
//! plane. With h.w > 0 the light shines from in front of the camera; with
//! h.w < 0 it is behind the camera and PPS reverses the order along each
//! light ray (the paper's inverted case); with h.w ≈ 0 (light across the
//! view) it stays directional and the map is orthographic in PPS.
//!
//! Like LiSPSM and TSM the map stores depth linear along the light in world
//! space, so the reversed order needs no inverted projection: the map's
//! x/y are a projective image of the world in which each light ray is one
//! texel, whatever side of the camera it runs. Casters behind the camera
//! would still leave PPS, so the paper's **virtual camera** moves back along
//! the view until every caster that can shade the visible part of the scene
//! stands at least the view's near depth before its eye.

use super::Warped;
use crate::scene::{Aabb, Camera};
use crate::technique::shadow_map::projection::setup::{
    clip_to_bounds, light_view_of_scene, linear_depth_row,
};
use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};

/// Below this |h.w| / |h.xyz| the light runs across the view: it stays a
/// directional light in PPS (orthographic map there).
const DIRECTIONAL_IN_PPS: f64 = 1e-6;

/// The camera whose post-perspective space holds the map: the real one
/// moved back along its view by `shift` so that every caster is in front of
/// its near plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VirtualCamera {
    pub eye: Vec3,
    pub near: f32,
    pub far: f32,
    /// How far it stands behind the real camera.
    pub shift: f32,
}

/// The virtual camera for a view whose visible part spans view depths
/// `z_near`..`z_far` and whose casters reach `caster_near` (negative behind
/// the eye): moved back by max(0, z_near − caster_near), so every caster
/// stands at least z_near before it, with its near and far planes kept in
/// place in the world (Kozlov 2004's shift; keeping the near plane at z_near
/// from the moved eye would flatten the whole view onto PPS's far plane).
pub fn virtual_camera(
    camera: &Camera,
    (z_near, z_far): (f32, f32),
    caster_near: f32,
) -> VirtualCamera {
    let shift = (z_near - caster_near).max(0.0);
    let forward = (camera.target - camera.eye).normalize();
    VirtualCamera {
        eye: camera.eye - forward * shift,
        near: z_near + shift,
        far: z_far + shift,
        shift,
    }
}

/// The region that can cast onto `body`: the body's box in the light's view
/// stretched towards the light to the scene's edge, inside the scene.
pub fn caster_region(light_dir: Vec3, scene: &Aabb, body: &[Vec3]) -> Vec<Vec3> {
    let (view, scene_ls) = light_view_of_scene(light_dir, scene);
    let b = Aabb::from_points(body.iter().map(|p| view.transform_point3(*p)));
    let inverse = view.inverse();
    let mut corners = [Vec3::ZERO; 8];
    for (i, c) in corners.iter_mut().enumerate() {
        let pick = |bit: usize, lo: f32, hi: f32| if (i >> bit) & 1 == 0 { lo } else { hi };
        *c = inverse.transform_point3(Vec3::new(
            pick(0, b.min.x, b.max.x),
            pick(1, b.min.y, b.max.y),
            pick(2, b.min.z, scene_ls.max.z.max(b.min.z)),
        ));
    }
    clip_to_bounds(&corners, scene)
}

/// The PSM matrix covering `body` (world points the map must cover, the
/// view inside the scene, at view depths `z_near`..`z_far`) with every
/// caster of `scene` towards the light: world → light clip, x/y the map,
/// z/w in [0, 1] (the map stores `depth_row`'s linear depth). `None` when the
/// body is empty or the map degenerates (use the uniform map).
pub fn psm(
    camera: &Camera,
    aspect: f32,
    light_dir: Vec3,
    scene: &Aabb,
    body: &[Vec3],
    (z_near, z_far): (f32, f32),
) -> Option<(Warped, VirtualCamera)> {
    if body.is_empty() {
        return None;
    }
    let forward = (camera.target - camera.eye).normalize();
    let casters = caster_region(light_dir, scene, body);
    let depth = |p: &Vec3| (*p - camera.eye).dot(forward);
    let caster_near = casters
        .iter()
        .chain(body)
        .map(depth)
        .fold(f32::MAX, f32::min);
    let virt = virtual_camera(camera, (z_near, z_far), caster_near);
    let view = glam::dcamera::rh::view::look_to_mat4(
        virt.eye.as_dvec3(),
        forward.as_dvec3(),
        camera.up.as_dvec3(),
    );
    let projection = glam::dcamera::rh::proj::directx::perspective(
        (camera.fov_y_deg as f64).to_radians(),
        aspect as f64,
        virt.near as f64,
        virt.far as f64,
    );
    let pps = projection * view;
    let to_pps = |p: &Vec3| pps.project_point3(p.as_dvec3());
    let body_pps: Vec<DVec3> = body.iter().map(to_pps).collect();
    let light = pps * (-light_dir.normalize()).as_dvec3().extend(0.0);
    let image = light_camera(light, &body_pps)?;
    // Fit the body's image to [−1, 1]².
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for q in &body_pps {
        let c = image * q.extend(1.0);
        if c.w <= 0.0 {
            return None;
        }
        let v = c.truncate() / c.w;
        (lo, hi) = (lo.min(v), hi.max(v));
    }
    let size = (hi - lo).max(DVec3::splat(1e-12));
    let fit = DMat4::from_cols(
        DVec4::new(2.0 / size.x, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 2.0 / size.y, 0.0, 0.0),
        DVec4::ZERO,
        DVec4::new(-(hi.x + lo.x) / size.x, -(hi.y + lo.y) / size.y, 0.0, 1.0),
    );
    let mut m = fit * image * pps;
    // z = c·depth with c the smallest w over the body: w is constant along
    // each light ray (its zero plane holds the light), so z/w stays in
    // [0, 1] on every ray through the body, and the matrix stays invertible
    // (its frustum is drawn by the debug view).
    let (light_view, scene_ls) = light_view_of_scene(light_dir, scene);
    let depth_row = light_view.transpose() * linear_depth_row(&scene_ls);
    let w_row = m.row(3);
    let c = body
        .iter()
        .map(|p| w_row.dot(p.as_dvec3().extend(1.0)))
        .fold(f64::MAX, f64::min);
    if c.is_nan() || c <= 0.0 {
        return None;
    }
    m = m.transpose();
    m.z_axis = depth_row.as_dvec4() * c;
    let view_proj: Mat4 = m.transpose().as_mat4();
    if !view_proj.is_finite() {
        return None;
    }
    Some((
        Warped {
            view_proj,
            depth_row,
        },
        virt,
    ))
}

/// The light's camera in PPS for the homogeneous light `h`, seeing every
/// point of `points` (the receivers; their casters lie on the same light
/// rays, which the camera's w = 0 plane, holding the light, never cuts): a perspective from the point h.xyz / h.w looking at
/// their centre (or straight at the infinity plane's side, −z, when some
/// point is not in front of that), or an orthographic view along h.xyz when
/// the light stays directional. Rows x, y, (0), w over PPS (q, 1).
fn light_camera(h: DVec4, points: &[DVec3]) -> Option<DMat4> {
    let dir = h.truncate();
    if dir.length() < 1e-12 {
        return None;
    }
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    let centre = (lo + hi) * 0.5;
    if h.w.abs() < DIRECTIONAL_IN_PPS * dir.length() {
        // Orthographic along the light's PPS direction.
        let n = -dir.normalize();
        let (t1, t2) = n.any_orthonormal_pair();
        return Some(rows(t1.extend(0.0), t2.extend(0.0), DVec4::W));
    }
    let eye = dir / h.w;
    let mut n = (centre - eye).normalize();
    let in_front = |n: DVec3| {
        points
            .iter()
            .all(|q| n.dot(*q - eye) > 1e-9 * (*q - eye).length())
    };
    if !n.is_finite() || !in_front(n) {
        // Every PPS point lies before the infinity plane z = f/(f − n),
        // which holds the light: looking along −z sees them all.
        n = DVec3::NEG_Z;
        if !in_front(n) {
            return None;
        }
    }
    let (t1, t2) = n.any_orthonormal_pair();
    let row = |a: DVec3| a.extend(-a.dot(eye));
    Some(rows(row(t1), row(t2), row(n)))
}

/// The matrix with rows x, y, 0, w.
fn rows(x: DVec4, y: DVec4, w: DVec4) -> DMat4 {
    DMat4::from_cols(x, y, DVec4::ZERO, w).transpose()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::shadow_map::projection::warp::tests::{
        assert_magnifies_near_the_camera, ndc,
    };

    fn setting() -> (Camera, Aabb) {
        let scene = Aabb {
            min: Vec3::new(-50.0, 0.0, -50.0),
            max: Vec3::new(50.0, 10.0, 50.0),
        };
        let cam = Camera::new(Vec3::new(0.0, 2.0, 40.0), Vec3::new(0.0, 0.0, 0.0));
        (cam, scene)
    }

    fn body(cam: &Camera, scene: &Aabb) -> Vec<Vec3> {
        clip_to_bounds(&cam.slice_corners(1.5, 0.5, 80.0), scene)
    }

    /// Covers the body, magnifies near the camera, one texel per light ray,
    /// depth linear along the light.
    #[test]
    fn the_map_covers_the_body_and_magnifies_near_the_camera() {
        let (cam, scene) = setting();
        let body = body(&cam, &scene);
        // Light from the side, ahead of the camera and behind it (inverted).
        for light in [
            Vec3::new(1.0, -1.0, 0.2),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, 1.0),
        ] {
            let (w, _) = psm(&cam, 1.5, light, &scene, &body, (0.5, 80.0)).unwrap();
            for p in &body {
                let q = ndc(w.view_proj, *p);
                assert!(
                    q.x.abs() <= 1.0 + 1e-3
                        && q.y.abs() <= 1.0 + 1e-3
                        && (-1e-4..=1.0 + 1e-4).contains(&q.z),
                    "{light}: {p} → {q}"
                );
            }
            assert_magnifies_near_the_camera(w.view_proj);
            // Invertible: the debug view draws its frustum.
            assert!(w.view_proj.determinant().abs() > 0.0 && w.view_proj.inverse().is_finite());
            for ground in [Vec3::new(5.0, 0.0, 10.0), Vec3::new(-30.0, 0.0, -40.0)] {
                let up = ground - light.normalize() * 3.0;
                let (a, b) = (ndc(w.view_proj, up), ndc(w.view_proj, ground));
                assert!(
                    (a - b).truncate().length() < 1e-4,
                    "{light}: same texel {a} {b}"
                );
                assert!(w.depth_row.dot(up.extend(1.0)) < w.depth_row.dot(ground.extend(1.0)));
            }
        }
    }

    /// A caster behind the eye moves the virtual camera back by exactly
    /// what puts it on the near plane; with none behind, no shift.
    #[test]
    fn the_virtual_camera_moves_back_behind_the_casters() {
        let cam = Camera::new(Vec3::new(0.0, 2.0, 40.0), Vec3::new(0.0, 2.0, 0.0));
        let v = virtual_camera(&cam, (0.5, 80.0), -7.5);
        assert!(
            (v.shift - 8.0).abs() < 1e-5
                && (v.near - 8.5).abs() < 1e-5
                && (v.far - 88.0).abs() < 1e-4
        );
        assert!((v.eye - Vec3::new(0.0, 2.0, 48.0)).length() < 1e-5);
        assert_eq!(virtual_camera(&cam, (0.5, 80.0), 3.0).shift, 0.0);
        // A light from behind the camera over a scene that extends behind
        // it: casters there shift it, and still land in front of it.
        let (cam, scene) = setting();
        let body = body(&cam, &scene);
        let light = Vec3::new(0.3, -1.0, -1.0);
        let (_, v) = psm(&cam, 1.5, light, &scene, &body, (0.5, 80.0)).unwrap();
        assert!(v.shift > 0.0, "{v:?}");
        let forward = (cam.target - cam.eye).normalize();
        for p in caster_region(light, &scene, &body) {
            assert!((p - v.eye).dot(forward) >= 0.5 - 1e-3, "{p} behind {v:?}");
        }
    }

    /// The light across the view stays directional in PPS; a light straight
    /// down the view is the PPS light on the view axis: still a valid map.
    #[test]
    fn lights_across_and_along_the_view_give_valid_maps() {
        let (cam, scene) = setting();
        let body = body(&cam, &scene);
        let across = (cam.target - cam.eye).normalize().cross(Vec3::Y);
        let along = cam.target - cam.eye;
        for light in [across, along] {
            let (w, _) = psm(&cam, 1.5, light, &scene, &body, (0.5, 80.0)).unwrap();
            for p in &body {
                let q = ndc(w.view_proj, *p);
                assert!(
                    q.x.abs() <= 1.0 + 1e-3 && q.y.abs() <= 1.0 + 1e-3,
                    "{light}: {q}"
                );
            }
        }
    }
}
