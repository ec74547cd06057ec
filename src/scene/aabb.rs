//! Axis-aligned bounding boxes.

use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn from_points(pts: impl IntoIterator<Item = Vec3>) -> Aabb {
        pts.into_iter().fold(Aabb::EMPTY, |b, p| b.with_point(p))
    }
    pub fn with_point(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }
    /// A length small against the box (10⁻⁴ of its diagonal): how far a
    /// depth range or a bounding sphere is widened so that surfaces lying
    /// on the bounds stay inside it after rounding, whatever the scene's
    /// scale (the built-ins span 1 m to 2 km).
    pub fn margin(&self) -> f32 {
        self.size().length() * 1e-4
    }
    /// The radius of the sphere around the box, widened by [`Aabb::margin`].
    pub fn bounding_radius(&self) -> f32 {
        self.size().length() * 0.5 + self.margin()
    }
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }
    pub fn transformed(&self, m: Mat4) -> Aabb {
        Aabb::from_points(self.corners().map(|c| m.transform_point3(c)))
    }
}
