//! Camera and light matrices against hand-derived values (wgpu: right-handed
//! view space, NDC depth in [0, 1], reversed: near 1, far 0).

use glam::{Vec3, Vec4};
use shadowlab::scene::{Camera, Light};

#[test]
fn perspective_maps_near_to_1_and_far_to_0() {
    let cam = Camera {
        fov_y_deg: 90.0,
        near: 1.0,
        far: 10.0,
        ..Camera::new(Vec3::ZERO, Vec3::NEG_Z)
    };
    let p = cam.projection(1.0);
    // Hand-derived: x' = x·cot(45°) = x, z_ndc = near/(far−near)·(far + z)/(−z).
    let near = p * Vec4::new(0.0, 0.0, -1.0, 1.0);
    let far = p * Vec4::new(0.0, 0.0, -10.0, 1.0);
    assert!((near.z / near.w - 1.0).abs() < 1e-6);
    assert!((far.z / far.w).abs() < 1e-6);
    // A point at 45° up on the near plane lands on the top edge.
    let top = p * Vec4::new(0.0, 1.0, -1.0, 1.0);
    assert!((top.y / top.w - 1.0).abs() < 1e-6);
    // z = −5.5 (midway): 1/9 · (10 − 5.5)/5.5 = 0.5/5.5 = 1/11.
    let mid = p * Vec4::new(0.0, 0.0, -5.5, 1.0);
    assert!((mid.z / mid.w - 1.0 / 11.0).abs() < 1e-6);
}

#[test]
fn view_matrix_puts_the_target_on_negative_z() {
    let cam = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let v = cam.view();
    let t = v.transform_point3(Vec3::ZERO);
    assert!((t - Vec3::new(0.0, 0.0, -5.0)).length() < 1e-6);
    let up = v.transform_point3(Vec3::new(0.0, 1.0, 0.0));
    assert!((up - Vec3::new(0.0, 1.0, -5.0)).length() < 1e-6);
}

#[test]
fn homogeneous_light_positions() {
    assert_eq!(
        Light::point(Vec3::new(1.0, 2.0, 3.0), 1.0).homogeneous(),
        Vec4::new(1.0, 2.0, 3.0, 1.0)
    );
    let d = Light::directional(Vec3::new(0.0, -2.0, 0.0), 1.0);
    assert_eq!(d.homogeneous(), Vec4::new(0.0, 1.0, 0.0, 0.0));
}

#[test]
fn bad_cameras_are_rejected() {
    let mut c = Camera::new(Vec3::ZERO, Vec3::ZERO);
    assert!(c.validate().is_err());
    c = Camera::new(Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO);
    assert!(c.validate().unwrap_err().to_string().contains("parallel"));
    c = Camera::new(Vec3::new(f32::NAN, 0.0, 1.0), Vec3::ZERO);
    assert!(c.validate().is_err());
}

#[test]
fn the_infinite_projection_keeps_points_at_infinity_inside_the_depth_range() {
    let cam = shadowlab::scene::Camera::new(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO);
    let (finite, infinite) = (cam.projection(1.5), cam.projection_infinite(1.5));
    // Same x and y; the near plane still maps to 1.
    assert_eq!(finite.x_axis, infinite.x_axis);
    assert_eq!(finite.y_axis, infinite.y_axis);
    let near = infinite * glam::Vec4::new(0.0, 0.0, -cam.near, 1.0);
    assert!((near.z / near.w - 1.0).abs() < 1e-6);
    // Directions (w = 0) in front of the camera: depth 2^-20, inside (0, 1].
    let view = cam.view();
    for d in [
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.3, -0.2, -1.0),
        (Vec3::ZERO - cam.eye).normalize(),
    ] {
        let c = infinite * view * d.extend(0.0);
        assert!(c.w > 0.0);
        let z = c.z / c.w;
        assert!(
            (z - shadowlab::scene::INFINITE_FAR_EPSILON).abs() < 1e-9 && z > 0.0,
            "{z}"
        );
    }
    // Far points approach that depth from above, monotonically.
    let mut last = 1.0 + 1e-6;
    for dist in [1.0f32, 10.0, 1e3, 1e6] {
        let c = infinite * glam::Vec4::new(0.0, 0.0, -dist, 1.0);
        let z = c.z / c.w;
        assert!(
            z < last && z > shadowlab::scene::INFINITE_FAR_EPSILON * 1.01,
            "{dist}: {z}"
        );
        last = z;
    }
}
