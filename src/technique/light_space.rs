//! Light-space math shared by the techniques: the planar shadow matrix, the
//! bias matrix, and light frusta fitted around bounds.

use crate::scene::{Aabb, Light, LightType};
use glam::{Mat4, Vec3, Vec4};

/// Planar projection from light `l` (homogeneous: w = 1 point, w = 0
/// directional) onto plane `p` (`p·x = 0` for points on it):
/// `M = (p·l)·I − l·pᵀ`, row i = `(p·l)·δij − l_i·p_j`. For any point `v`,
/// `M v` lies on the plane and on the line through `l` and `v`
/// ([000] §2, [001] §2, [003]; [000] eq. 24 and [001] §2.4 carry typos).
pub fn shadow_matrix(p: Vec4, l: Vec4) -> Mat4 {
    let d = p.dot(l);
    Mat4::from_cols(
        Vec4::X * d - l * p.x,
        Vec4::Y * d - l * p.y,
        Vec4::Z * d - l * p.z,
        Vec4::W * d - l * p.w,
    )
}

/// Maps light clip space to texture space for wgpu: `u = 0.5 x + 0.5`,
/// `v = −0.5 y + 0.5` (texture rows go down), depth unchanged (already
/// [0, 1]).
pub fn bias_matrix() -> Mat4 {
    Mat4::from_cols(
        Vec4::new(0.5, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -0.5, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 1.0, 0.0),
        Vec4::new(0.5, 0.5, 0.0, 1.0),
    )
}

/// A light's view and projection.
#[derive(Clone, Copy, Debug)]
pub struct LightFrustum {
    pub view: Mat4,
    pub proj: Mat4,
    pub near: f32,
    pub far: f32,
    /// True for an orthographic projection (directional lights).
    pub orthographic: bool,
}

impl LightFrustum {
    pub fn view_proj(&self) -> Mat4 {
        self.proj * self.view
    }
    /// World → texture coordinates (u, v, depth).
    pub fn texture_matrix(&self) -> Mat4 {
        bias_matrix() * self.view_proj()
    }
}

/// The up vector of a light's view along `dir`: the world's up, or +z
/// for a light looking (nearly) straight up or down.
pub fn up_for(dir: Vec3) -> Vec3 {
    if dir.normalize().dot(Vec3::Y).abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// The tightest frustum of the light around the sphere bounding `bounds`,
/// widened by `margin` (a fraction of the radius): perspective from a point
/// or spot light, orthographic along a directional light. `None` when a
/// local light lies inside the (widened) sphere.
pub fn fit_bounds(light: &Light, bounds: &Aabb, margin: f32) -> Option<LightFrustum> {
    let c = bounds.center();
    let r = (bounds.size().length() * 0.5).max(1e-4) * (1.0 + margin);
    match light.kind {
        LightType::Directional => {
            let dir = light.direction.normalize();
            let eye = c - dir * (2.0 * r);
            Some(LightFrustum {
                view: glam::camera::rh::view::look_to_mat4(eye, dir, up_for(dir)),
                proj: glam::camera::rh::proj::directx::orthographic(-r, r, -r, r, r, 3.0 * r),
                near: r,
                far: 3.0 * r,
                orthographic: true,
            })
        }
        _ => {
            let to = c - light.position;
            let d = to.length();
            if d <= r * 1.0001 {
                return None;
            }
            let half = (r / d).asin();
            let near = (d - r).max(d * 1e-3);
            let far = d + r;
            Some(LightFrustum {
                view: glam::camera::rh::view::look_to_mat4(light.position, to / d, up_for(to)),
                proj: glam::camera::rh::proj::directx::perspective(2.0 * half, 1.0, near, far),
                near,
                far,
                orthographic: false,
            })
        }
    }
}

/// Whether `bounds` lies wholly outside the clip volume of `view_proj`
/// (wgpu: −w ≤ x, y ≤ w, 0 ≤ z ≤ w): all eight corners outside one of its
/// planes, tested in homogeneous coordinates (exact for corners behind the
/// eye too). Conservative: a box beside a frustum corner is kept.
pub fn outside_clip_volume(bounds: &Aabb, view_proj: Mat4) -> bool {
    let corners = bounds
        .corners()
        .map(|c| view_proj * Vec4::new(c.x, c.y, c.z, 1.0));
    let planes: [fn(Vec4) -> f32; 6] = [
        |c| c.w + c.x,
        |c| c.w - c.x,
        |c| c.w + c.y,
        |c| c.w - c.y,
        |c| c.z,
        |c| c.w - c.z,
    ];
    planes
        .iter()
        .any(|inside| corners.iter().all(|c| inside(*c) < 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shadow_matrix_projects_onto_the_floor_from_a_point_light() {
        // Floor y = 0 (p = (0,1,0,0)), light at (0, 4, 0): the point (1, 2, 0)
        // lies halfway, so its shadow is at (2, 0, 0).
        let m = shadow_matrix(Vec4::new(0.0, 1.0, 0.0, 0.0), Vec4::new(0.0, 4.0, 0.0, 1.0));
        let s = m * Vec4::new(1.0, 2.0, 0.0, 1.0);
        assert!((s.truncate() / s.w - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
        // Hand-derived matrix: d = 4; rows (4,0,0,0), (0,0,0,0), (0,0,4,0), (0,−1,0,4).
        let expect = Mat4::from_cols(
            Vec4::new(4.0, 0.0, 0.0, 0.0),
            Vec4::new(0.0, 0.0, 0.0, -1.0),
            Vec4::new(0.0, 0.0, 4.0, 0.0),
            Vec4::new(0.0, 0.0, 0.0, 4.0),
        );
        assert_eq!(m, expect);
    }

    #[test]
    fn shadow_matrix_for_directional_light_and_tilted_plane() {
        // Directional light travelling along (1, −1, 0): l = (−1, 1, 0, 0).
        // Floor y = 0: (3, 2, 1) slides along (1, −1, 0) by 2 → (5, 0, 1).
        let m = shadow_matrix(
            Vec4::new(0.0, 1.0, 0.0, 0.0),
            Vec4::new(-1.0, 1.0, 0.0, 0.0),
        );
        let s = m * Vec4::new(3.0, 2.0, 1.0, 1.0);
        assert!((s.truncate() / s.w - Vec3::new(5.0, 0.0, 1.0)).length() < 1e-6);
        // Tilted plane x + y = 2 ((1,1,0,−2)/√2), point light at (0, 0, 0)...
        // the ray from the light through (0.5, 0.5, 3) meets the plane at (1, 1, 6).
        let p = Vec4::new(1.0, 1.0, 0.0, -2.0) / 2f32.sqrt();
        let m = shadow_matrix(p, Vec4::new(0.0, 0.0, 0.0, 1.0));
        let s = m * Vec4::new(0.5, 0.5, 3.0, 1.0);
        assert!(
            (s.truncate() / s.w - Vec3::new(1.0, 1.0, 6.0)).length() < 1e-5,
            "{s}"
        );
        // Every projected point lies on the plane.
        for v in [
            Vec4::new(0.3, 0.1, -2.0, 1.0),
            Vec4::new(-1.0, 0.2, 0.5, 1.0),
        ] {
            let s = m * v;
            assert!(p.dot(s / s.w).abs() < 1e-5);
        }
    }

    #[test]
    fn bias_matrix_maps_clip_corners_to_texture_corners() {
        let b = bias_matrix();
        assert_eq!(
            b * Vec4::new(-1.0, 1.0, 0.25, 1.0),
            Vec4::new(0.0, 0.0, 0.25, 1.0)
        );
        assert_eq!(
            b * Vec4::new(1.0, -1.0, 0.5, 1.0),
            Vec4::new(1.0, 1.0, 0.5, 1.0)
        );
    }

    #[test]
    fn fitted_frustum_contains_the_bounds() {
        let b = Aabb {
            min: Vec3::new(-1.0, 0.0, -1.0),
            max: Vec3::new(1.0, 2.0, 1.0),
        };
        for light in [
            Light::point(Vec3::new(3.0, 6.0, 2.0), 1.0),
            Light::directional(Vec3::new(0.3, -1.0, 0.2), 1.0),
        ] {
            let f = fit_bounds(&light, &b, 0.0).unwrap();
            for c in b.corners() {
                let t = f.texture_matrix() * c.extend(1.0);
                let t = t.truncate() / t.w;
                assert!(
                    (0.0..=1.0).contains(&t.x)
                        && (0.0..=1.0).contains(&t.y)
                        && (0.0..=1.0).contains(&t.z),
                    "{t}"
                );
            }
        }
        assert!(fit_bounds(&Light::point(Vec3::new(0.0, 1.0, 0.0), 1.0), &b, 0.0).is_none());
    }

    #[test]
    fn boxes_outside_a_clip_volume_are_culled_and_others_kept() {
        use glam::camera::rh::proj::directx::orthographic;
        // An orthographic box x, y in [-1, 1], depth 0..10 along −z.
        let vp = orthographic(-1.0, 1.0, -1.0, 1.0, 0.0, 10.0);
        let b = |min: Vec3, max: Vec3| Aabb { min, max };
        assert!(!outside_clip_volume(
            &b(Vec3::splat(-0.5), Vec3::splat(0.5) - Vec3::Z),
            vp
        ));
        // Straddling an edge: kept.
        assert!(!outside_clip_volume(
            &b(Vec3::new(0.9, 0.0, -2.0), Vec3::new(3.0, 0.5, -1.0)),
            vp
        ));
        // Wholly right of x = 1, above y = 1, behind the near plane, past the far plane.
        assert!(outside_clip_volume(
            &b(Vec3::new(1.1, 0.0, -2.0), Vec3::new(3.0, 0.5, -1.0)),
            vp
        ));
        assert!(outside_clip_volume(
            &b(Vec3::new(0.0, 1.5, -2.0), Vec3::new(0.5, 2.0, -1.0)),
            vp
        ));
        assert!(outside_clip_volume(
            &b(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.5, 0.5, 2.0)),
            vp
        ));
        assert!(outside_clip_volume(
            &b(Vec3::new(0.0, 0.0, -12.0), Vec3::new(0.5, 0.5, -11.0)),
            vp
        ));
        // Perspective: a box behind the eye is culled, one in front kept.
        let persp = glam::camera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 100.0);
        assert!(outside_clip_volume(
            &b(Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, 1.0, 3.0)),
            persp
        ));
        assert!(!outside_clip_volume(
            &b(Vec3::new(-1.0, -1.0, -3.0), Vec3::new(1.0, 1.0, -1.0)),
            persp
        ));
    }
}
