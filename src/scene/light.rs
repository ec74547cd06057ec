//! Lights: point, spot and directional, with optional areas for soft
//! shadows.

use anyhow::{Result, bail};
use glam::{Vec3, Vec4};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    Point,
    Spot,
    Directional,
}

impl std::str::FromStr for LightType {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "point" => LightType::Point,
            "spot" => LightType::Spot,
            "directional" => LightType::Directional,
            _ => bail!("unknown light type '{s}' (valid: point, spot, directional)"),
        })
    }
}

/// Area of a light for soft shadows.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase")]
pub enum LightArea {
    /// Spherical light (point/spot) or angular disk (directional: radius is
    /// the tangent of the half-angle).
    Sphere { radius: f32 },
    /// Rectangle facing the light direction (for directional: tangents).
    Rect { width: f32, height: f32 },
}

/// A light in world space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    #[serde(rename = "type")]
    pub kind: LightType,
    pub position: Vec3,
    /// Direction the light travels (spot, directional), normalised.
    pub direction: Vec3,
    pub color: Vec3,
    pub intensity: f32,
    /// Distance at which point/spot light attenuates to zero; 0 = no falloff.
    pub range: f32,
    /// Spot cone half-angles in degrees.
    pub inner_cone_deg: f32,
    pub outer_cone_deg: f32,
    pub area: Option<LightArea>,
}

impl Light {
    pub fn point(position: Vec3, intensity: f32) -> Light {
        Light {
            kind: LightType::Point,
            position,
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
            intensity,
            range: 0.0,
            inner_cone_deg: 25.0,
            outer_cone_deg: 35.0,
            area: None,
        }
    }
    pub fn spot(position: Vec3, target: Vec3, intensity: f32, inner: f32, outer: f32) -> Light {
        Light {
            kind: LightType::Spot,
            direction: (target - position).normalize(),
            inner_cone_deg: inner,
            outer_cone_deg: outer,
            ..Light::point(position, intensity)
        }
    }
    pub fn directional(direction: Vec3, intensity: f32) -> Light {
        Light {
            kind: LightType::Directional,
            direction: direction.normalize(),
            position: -direction.normalize() * 50.0,
            ..Light::point(Vec3::ZERO, intensity)
        }
    }
    /// Homogeneous light position: `(P, 1)` for point and spot lights,
    /// `(−D, 0)` (towards the light) for directional lights.
    pub fn homogeneous(&self) -> Vec4 {
        match self.kind {
            LightType::Directional => (-self.direction).extend(0.0),
            _ => self.position.extend(1.0),
        }
    }
    /// True where this light's direct light can reach a surface point `p`
    /// with normal `n`: the surface faces the light (N·L > 0), lies inside a
    /// spot light's outer cone and within the range (when one is set).
    pub fn reaches(&self, p: Vec3, n: Vec3) -> bool {
        let to_light = match self.kind {
            LightType::Directional => -self.direction,
            _ => self.position - p,
        };
        n.dot(to_light) > 0.0 && self.shines_on(p)
    }

    /// True where this light emits towards `p` at all: inside a spot
    /// light's outer cone and within the range (when one is set).
    pub fn shines_on(&self, p: Vec3) -> bool {
        if self.kind == LightType::Directional {
            return true;
        }
        let to_light = self.position - p;
        let d = to_light.length();
        let in_cone =
            self.kind != LightType::Spot || (-to_light / d).dot(self.cone_axis()) > self.cone_cos();
        in_cone && (self.range <= 0.0 || d < self.range)
    }

    /// A spot light's unit axis.
    pub fn cone_axis(&self) -> Vec3 {
        self.direction.normalize()
    }

    /// The cosine of a spot light's outer cone.
    pub fn cone_cos(&self) -> f32 {
        self.outer_cone_deg.to_radians().cos()
    }

    pub fn validate(&self) -> Result<()> {
        // The constructors normalise the direction: a zero one becomes NaN.
        if !self.direction.is_finite() {
            match self.kind {
                LightType::Directional => bail!("directional light has no direction: it is zero"),
                LightType::Spot => bail!(
                    "spot light has no direction: it is zero, or the spot is aimed at its own position"
                ),
                LightType::Point => {}
            }
        }
        let ok = self.position.is_finite()
            && self.direction.is_finite()
            && self.color.is_finite()
            && self.intensity.is_finite()
            && self.range.is_finite();
        if !ok {
            bail!("light has a non-finite field: {self:?}");
        }
        if self.color.min_element() < 0.0 || self.intensity < 0.0 || self.range < 0.0 {
            bail!(
                "light colour, intensity and range must be non-negative (colour {}, intensity {}, range {})",
                self.color,
                self.intensity,
                self.range
            );
        }
        match self.area {
            Some(LightArea::Sphere { radius }) if !(radius.is_finite() && radius > 0.0) => bail!(
                "light area radius must be a positive finite number, got {radius} (leave the area out for a hard light)"
            ),
            Some(LightArea::Rect { width, height })
                if !(width.is_finite() && width > 0.0 && height.is_finite() && height > 0.0) =>
            {
                bail!(
                    "light area size must be two positive finite numbers, got {width} x {height} (leave the area out for a hard light)"
                )
            }
            _ => {}
        }
        if self.kind != LightType::Point && self.direction.length_squared() < 1e-12 {
            bail!("{:?} light needs a non-zero direction", self.kind);
        }
        if self.kind == LightType::Spot
            && !(0.0 < self.outer_cone_deg
                && self.outer_cone_deg < 90.0
                && self.inner_cone_deg <= self.outer_cone_deg)
        {
            bail!(
                "spot cone must satisfy 0 < inner <= outer < 90 degrees (inner {}, outer {})",
                self.inner_cone_deg,
                self.outer_cone_deg
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_with_bad_areas_or_negative_values_are_refused() {
        for area in [
            LightArea::Sphere { radius: -1.0 },
            LightArea::Sphere { radius: f32::NAN },
            LightArea::Sphere {
                radius: f32::INFINITY,
            },
            LightArea::Rect {
                width: 1.0,
                height: 0.0,
            },
        ] {
            let mut l = Light::point(Vec3::Y, 1.0);
            l.area = Some(area);
            assert!(l.validate().is_err(), "{area:?}");
        }
        let mut l = Light::point(Vec3::Y, 1.0);
        l.intensity = -1.0;
        assert!(l.validate().is_err());
        l.intensity = 1.0;
        l.area = Some(LightArea::Sphere { radius: 0.2 });
        l.validate().unwrap();
    }
}
