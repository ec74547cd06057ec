//! The perspective camera and its projections (wgpu's [0, 1] depth,
//! reversed: the near plane at 1).

use super::Aabb;
use anyhow::{Result, bail};
use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// The NDC depth of the near plane under [`Camera::projection`] (reversed:
/// the far plane lies at 0); a camera ray starts there.
pub const NEAR_PLANE_DEPTH: f32 = 1.0;

/// How far above 0 points at infinity land with
/// [`Camera::projection_infinite`]: 2^-20, sixteen steps of a 24-bit depth buffer.
pub const INFINITE_FAR_EPSILON: f32 = 1.0 / (1u32 << 20) as f32;

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
    pub near: f32,
    pub far: f32,
}

impl Camera {
    pub fn new(eye: Vec3, target: Vec3) -> Camera {
        Camera {
            eye,
            target,
            up: Vec3::Y,
            fov_y_deg: 50.0,
            near: 0.1,
            far: 200.0,
        }
    }
    /// How far the camera's view of a scene bounded by `scene` can reach:
    /// to the far side of the scene's bounding sphere, at most the far
    /// plane (every visible point lies within this view depth).
    pub fn reach(&self, scene: &Aabb) -> f32 {
        (self.eye.distance(scene.center()) + scene.bounding_radius()).min(self.far)
    }
    /// The eight world-space corners of the view between view depths `z0`
    /// and `z1`, seen with frame `aspect` (bit 0: x side, bit 1: y side,
    /// bit 2: the far depth).
    pub fn slice_corners(&self, aspect: f32, z0: f32, z1: f32) -> [Vec3; 8] {
        let inv_view = self.view().inverse();
        let ty = (self.fov_y_deg.to_radians() * 0.5).tan();
        let tx = ty * aspect;
        let mut out = [Vec3::ZERO; 8];
        for (k, z) in [z0, z1].into_iter().enumerate() {
            for (j, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
                .into_iter()
                .enumerate()
            {
                out[k * 4 + j] = inv_view.transform_point3(Vec3::new(sx * tx * z, sy * ty * z, -z));
            }
        }
        out
    }
    /// Right-handed look-at view matrix.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }
    /// Perspective projection onto wgpu's [0,1] depth range, reversed (the
    /// near plane at depth 1, the far plane at 0: with a float depth buffer
    /// the relative precision stays nearly uniform to any distance):
    /// `z_ndc = near/(far−near) · (far + z_view)/(−z_view)`.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective(
            self.fov_y_deg.to_radians(),
            aspect,
            self.far,
            self.near,
        )
    }
    /// [`Camera::projection`] with the far plane at infinity, re-derived for
    /// reversed [0,1] depth: with clip z = a·z_e + b and w = −z_e (z_e < 0
    /// in front), z_ndc = −a − b/z_e, which tends to −a as z_e → −∞ and is 1
    /// at z_e = −near when b = near·(1 + a). Taking −a =
    /// [`INFINITE_FAR_EPSILON`] keeps points at infinity (w = 0 in, e.g.,
    /// shadow-volume extrusions) inside the clip volume and in front of the
    /// cleared depth 0 despite rounding.
    pub fn projection_infinite(&self, aspect: f32) -> Mat4 {
        let mut m = self.projection(aspect);
        let a = -INFINITE_FAR_EPSILON;
        m.z_axis.z = a;
        m.w_axis.z = self.near * (1.0 + a);
        m
    }

    /// Whether the camera looks along its up vector, which then defines no
    /// roll.
    pub fn looks_along_up(&self) -> bool {
        (self.target - self.eye).cross(self.up).length_squared() < 1e-12
    }

    /// The camera with an up it can use where none was given and the
    /// default one lies along the view: −z (a view straight down shows −z
    /// up, as a map shows north), or +y for a view along z; with a warning.
    pub fn with_usable_up(self) -> Camera {
        if !self.looks_along_up() {
            return self;
        }
        let mut camera = Camera {
            up: Vec3::NEG_Z,
            ..self
        };
        if camera.looks_along_up() {
            camera.up = Vec3::Y;
        }
        log::warn!(
            "the camera looks along its up vector {}; up taken as {}",
            self.up,
            camera.up
        );
        camera
    }

    pub fn validate(&self) -> Result<()> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            bail!("camera has a non-finite vector");
        }
        if (self.target - self.eye).length_squared() < 1e-12 {
            bail!("camera eye and target coincide");
        }
        if self.looks_along_up() {
            bail!("camera up vector is parallel to the view direction");
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            bail!(
                "camera fov must be in (0, 180) degrees, got {}",
                self.fov_y_deg
            );
        }
        if !(self.near > 0.0 && self.far > self.near) {
            bail!(
                "camera needs 0 < near < far (near {}, far {})",
                self.near,
                self.far
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera looking straight down or up the world's y takes −z as its
    /// up, one looking along z keeps +y; a usable up is kept as it is.
    #[test]
    fn a_camera_looking_along_its_up_takes_another() {
        let down = Camera::new(Vec3::new(1.0, 5.0, 2.0), Vec3::new(1.0, 0.0, 2.0));
        assert!(down.looks_along_up() && down.validate().is_err());
        let fixed = down.with_usable_up();
        assert_eq!(fixed.up, Vec3::NEG_Z);
        assert!(fixed.validate().is_ok());
        // Seen from above, −z is the top of the frame: a point towards −z
        // projects above the centre.
        let seen = fixed.view().transform_point3(Vec3::new(1.0, 0.0, 1.0));
        let clip = fixed.projection(1.0) * seen.extend(1.0);
        assert!(clip.y / clip.w > 0.0, "{clip}");
        let up_z = Camera {
            up: Vec3::Z,
            ..Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO)
        };
        assert_eq!(up_z.with_usable_up().up, Vec3::Y);
        let usable = Camera::new(Vec3::new(0.0, 2.0, 5.0), Vec3::ZERO);
        assert_eq!(usable.with_usable_up(), usable);
    }

    /// The reach is the distance to the scene's centre plus its bounding
    /// radius (√3 for a box of side 2, widened by its margin), cut at the
    /// far plane.
    #[test]
    fn the_view_reaches_the_far_side_of_the_scene_within_the_far_plane() {
        let scene = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let camera = Camera::new(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO);
        let radius = 3f32.sqrt() + 2.0 * 3f32.sqrt() * 1e-4;
        assert!((camera.reach(&scene) - (10.0 + radius)).abs() < 1e-4);
        let near_sighted = Camera { far: 5.0, ..camera };
        assert_eq!(near_sighted.reach(&scene), 5.0);
    }
}
