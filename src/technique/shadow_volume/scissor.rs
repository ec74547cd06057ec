//! The screen rectangle a light's range can light, which bounds the
//! stencil work of its volumes.

use crate::scene::{Light, LightType};
use glam::{Mat4, Vec3};

/// Screen rectangle (x, y, w, h) in pixels that a light's range sphere can
/// cover; `None` when it is off screen, the whole frame when unbounded or
/// when the sphere reaches behind the camera.
pub fn range_scissor(light: &Light, view_proj: Mat4, width: u32, height: u32) -> Option<[u32; 4]> {
    let full = Some([0, 0, width, height]);
    if light.kind == LightType::Directional || light.range <= 0.0 {
        return full;
    }
    let r = Vec3::splat(light.range);
    let corners =
        crate::scene::Aabb::from_points([light.position - r, light.position + r]).corners();
    let mut lo = glam::Vec2::splat(f32::INFINITY);
    let mut hi = glam::Vec2::splat(f32::NEG_INFINITY);
    for c in corners {
        let p = view_proj * c.extend(1.0);
        if p.w <= 1e-6 {
            return full;
        }
        let ndc = p.truncate().truncate() / p.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    let to_px = |x: f32, size: u32| ((x.clamp(-1.0, 1.0) * 0.5 + 0.5) * size as f32) as u32;
    let (x0, x1) = (
        to_px(lo.x, width),
        to_px(hi.x, width).saturating_add(1).min(width),
    );
    // NDC y up, pixels down.
    let (y0, y1) = (
        to_px(-hi.y, height),
        to_px(-lo.y, height).saturating_add(1).min(height),
    );
    if hi.x < -1.0 || lo.x > 1.0 || hi.y < -1.0 || lo.y > 1.0 || x1 <= x0 || y1 <= y0 {
        return None;
    }
    Some([x0, y0, x1 - x0, y1 - y0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scissor_of_a_light_range_in_front_of_the_camera() {
        let cam = crate::scene::Camera::new(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO);
        let vp = cam.projection(1.0) * cam.view();
        let mut l = Light::point(Vec3::ZERO, 1.0);
        assert_eq!(
            range_scissor(&l, vp, 100, 100),
            Some([0, 0, 100, 100]),
            "unbounded"
        );
        l.range = 1.0;
        let [x, y, w, h] = range_scissor(&l, vp, 100, 100).unwrap();
        assert!(
            x > 20 && y > 20 && w < 60 && h < 60 && w > 5,
            "{x} {y} {w} {h}"
        );
        assert!(x + w / 2 >= 48 && x + w / 2 <= 52, "centred");
        l.position = Vec3::new(100.0, 0.0, 0.0);
        assert_eq!(range_scissor(&l, vp, 100, 100), None, "off screen");
        l.position = Vec3::new(0.0, 0.0, 10.5);
        assert_eq!(
            range_scissor(&l, vp, 100, 100),
            Some([0, 0, 100, 100]),
            "around the camera"
        );
    }
}
