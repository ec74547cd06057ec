//! Camera and light manipulation of the viewer and the browser page: orbit
//! (left drag), zoom (middle drag or wheel), pan (right drag) as in the
//! source documents' demos, WASD fly, and moving a light in the view plane.

use crate::scene::{Camera, NEAR_PLANE_DEPTH};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// Rotates the eye around the target: `dx`, `dy` in radians (yaw, pitch).
pub fn orbit(c: &mut Camera, dx: f32, dy: f32) {
    let offset = c.eye - c.target;
    let r = offset.length();
    let yaw = offset.x.atan2(offset.z) - dx;
    let pitch = ((offset.y / r).clamp(-1.0, 1.0).asin() + dy).clamp(-1.55, 1.55);
    c.eye = c.target
        + Vec3::new(
            yaw.sin() * pitch.cos(),
            pitch.sin(),
            yaw.cos() * pitch.cos(),
        ) * r;
    c.up = Vec3::Y;
}

/// Moves the eye towards (factor < 1) or away from the target.
pub fn zoom(c: &mut Camera, factor: f32) {
    let offset = (c.eye - c.target) * factor.clamp(0.05, 20.0);
    if offset.length() > c.near * 2.0 {
        c.eye = c.target + offset;
    }
}

/// Moves eye and target along the view plane by a fraction of the distance.
pub fn pan(c: &mut Camera, dx: f32, dy: f32) {
    let fwd = (c.target - c.eye).normalize();
    let right = fwd.cross(c.up).normalize();
    let up = right.cross(fwd);
    let d = (c.target - c.eye).length();
    let shift = (-right * dx + up * dy) * d;
    c.eye += shift;
    c.target += shift;
}

/// Flies eye and target: `forward`, `right`, `up` in world units.
pub fn fly(c: &mut Camera, forward: f32, right: f32, up: f32) {
    let fwd = (c.target - c.eye).normalize();
    let r = fwd.cross(c.up).normalize();
    let shift = fwd * forward + r * right + Vec3::Y * up;
    c.eye += shift;
    c.target += shift;
}

/// The world-space ray through window pixel `p` (frame.json's conventions).
pub fn pixel_ray(view_proj: Mat4, size: Vec2, p: Vec2) -> (Vec3, Vec3) {
    let inv = view_proj.inverse();
    let ndc = Vec2::new(2.0 * p.x / size.x - 1.0, 1.0 - 2.0 * p.y / size.y);
    // On the near plane and farther along (depth 0.5): both finite with a
    // far plane at infinity too.
    let a = inv * Vec4::new(ndc.x, ndc.y, NEAR_PLANE_DEPTH, 1.0);
    let b = inv * Vec4::new(ndc.x, ndc.y, 0.5, 1.0);
    let (a, b) = (a.truncate() / a.w, b.truncate() / b.w);
    (a, (b - a).normalize())
}

/// Window pixel of a world point, or `None` behind the camera.
pub fn project(view_proj: Mat4, size: Vec2, p: Vec3) -> Option<Vec2> {
    let c = view_proj * p.extend(1.0);
    (c.w > 0.0).then(|| {
        Vec2::new(
            (c.x / c.w * 0.5 + 0.5) * size.x,
            (0.5 - c.y / c.w * 0.5) * size.y,
        )
    })
}

/// Where the ray through pixel `p` meets the plane through `anchor` facing
/// the camera (dragging a light icon).
pub fn drag_point(c: &Camera, view_proj: Mat4, size: Vec2, p: Vec2, anchor: Vec3) -> Option<Vec3> {
    let (o, d) = pixel_ray(view_proj, size, p);
    let n = (c.target - c.eye).normalize();
    let denom = d.dot(n);
    (denom.abs() > 1e-6).then(|| o + d * ((anchor - o).dot(n) / denom))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_keeps_distance_and_zoom_scales_it() {
        let mut c = Camera::new(Vec3::new(0.0, 2.0, 5.0), Vec3::ZERO);
        let r = c.eye.length();
        orbit(&mut c, 0.7, 0.2);
        assert!((c.eye.length() - r).abs() < 1e-4);
        zoom(&mut c, 0.5);
        assert!((c.eye.length() - r * 0.5).abs() < 1e-4);
        let t = c.target;
        pan(&mut c, 0.1, 0.0);
        assert!((c.target - t).length() > 0.0);
    }

    #[test]
    fn projected_point_maps_back_onto_its_ray() {
        let c = Camera::new(Vec3::new(1.0, 3.0, 6.0), Vec3::ZERO);
        let vp = c.projection(16.0 / 9.0) * c.view();
        let size = Vec2::new(1280.0, 720.0);
        let p = Vec3::new(0.5, 0.8, -0.3);
        let px = project(vp, size, p).unwrap();
        let (o, d) = pixel_ray(vp, size, px);
        let closest = o + d * (p - o).dot(d);
        assert!((closest - p).length() < 1e-3);
        let q = drag_point(&c, vp, size, px, p).unwrap();
        assert!((q - p).length() < 1e-3);
    }
}
