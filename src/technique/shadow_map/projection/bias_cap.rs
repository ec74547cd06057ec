//! The depth bias's cap of orthographic maps (`slope_bias_clamp`): so
//! many texel widths of depth, per map, cascade or clipmap level.

use super::setup::LightSetup;
use super::setup::MapProjection;

/// The depth bias's cap for `face` of `setup` in the map's depth units:
/// `caps.directional` texel widths of an orthographic map
/// ([`texel_bias_clamp`]), `caps.local` of a spot map or cube face at its
/// mean distance ([`perspective_bias_clamp`]); 0 (no cap) for warped and
/// paraboloid maps.
pub fn bias_clamp(setup: &LightSetup, face: usize, size: u32, caps: BiasCaps) -> f32 {
    if setup.warp_depth.is_some() {
        return 0.0;
    }
    match setup.projection {
        MapProjection::Orthographic => {
            let scale = setup
                .cascades
                .as_ref()
                .and_then(|s| s.texel_scales.get(face).copied())
                .unwrap_or(setup.texel_scale);
            texel_bias_clamp(
                scale / size as f32,
                setup.far - setup.near,
                caps.directional,
            )
        }
        MapProjection::Perspective | MapProjection::Cube => perspective_bias_clamp(
            setup.texel_scale / size as f32,
            (setup.near, setup.far),
            caps.local,
        ),
        MapProjection::Paraboloid => 0.0,
    }
}

/// The caps in texel widths of depth (`slope_bias_clamp`,
/// `slope_bias_clamp_local`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasCaps {
    pub directional: f32,
    pub local: f32,
}

/// The depth bias's cap of a perspective map with texels `texel_at_unit`
/// wide at unit distance and depth range `(near, far)`: `texels` texel
/// widths of depth at the mean distance d = √(near·far), in z/w units —
/// z = f(d − n) / (d(f − n)), so dz/dd = f·n / (d²(f − n)) and one texel at
/// d, τ·d wide, is τ·f·n / (d(f − n)). One cap per map: at a distance d′
/// it allows texels·d′/d texel widths. Rounded to a quarter octave; 0 (no
/// cap) for `texels` = 0.
pub fn perspective_bias_clamp(texel_at_unit: f32, (near, far): (f32, f32), texels: f32) -> f32 {
    if texels <= 0.0 || near <= 0.0 || far <= near {
        return 0.0;
    }
    let d = (near * far).sqrt();
    quarter_octave(texels * texel_at_unit * far * near / (d * (far - near)))
}

fn quarter_octave(x: f32) -> f32 {
    2f32.powf((x.log2() * 4.0).round() / 4.0)
}

/// The depth bias's cap of an orthographic map whose texels are
/// `texel_world` wide over a depth range `depth_range`: `texels` texel
/// widths of depth, rounded to a quarter octave (few pipelines); 0 (no cap)
/// for `texels` = 0.
pub fn texel_bias_clamp(texel_world: f32, depth_range: f32, texels: f32) -> f32 {
    if texels <= 0.0 {
        return 0.0;
    }
    quarter_octave(texels * texel_world / depth_range.max(1e-6))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::shadow_map::CascadeSplit;
    use glam::{Mat4, Vec4};

    fn ortho(texel_scale: f32, cascades: Option<Vec<f32>>) -> LightSetup {
        LightSetup {
            faces: vec![Mat4::IDENTITY; cascades.as_ref().map_or(1, |c| c.len())],
            near: 0.0,
            far: 1024.0,
            projection: MapProjection::Orthographic,
            texel_scale,
            cascades: cascades.map(|texel_scales| CascadeSplit {
                near: 0.1,
                far: vec![1.0; texel_scales.len()],
                texel_scales,
            }),
            warp_depth: None,
            moment_depth: None,
        }
    }

    fn caps(texels: f32) -> BiasCaps {
        BiasCaps {
            directional: texels,
            local: texels,
        }
    }

    #[test]
    fn the_bias_cap_is_texel_widths_of_the_depth_range() {
        // 2048 world units over 2048 texels: 1 per texel; 4 texels of a
        // 1024-unit depth range = 2^-8.
        assert_eq!(
            bias_clamp(&ortho(2048.0, None), 0, 2048, caps(4.0)),
            2f32.powi(-8)
        );
        // 4.5 texels rounds to the nearest quarter octave, 2^(-8 + 1/4)·…
        let c = bias_clamp(&ortho(2048.0, None), 0, 2048, caps(4.5));
        assert!((c.log2() + 7.75).abs() < 1e-5, "{}", c.log2());
        // Each cascade its own texel.
        let cascaded = ortho(1024.0, Some(vec![1024.0, 4096.0]));
        assert_eq!(bias_clamp(&cascaded, 1, 2048, caps(4.0)), 2f32.powi(-7));
        assert_eq!(bias_clamp(&cascaded, 0, 2048, caps(4.0)), 2f32.powi(-9));
        // None for warped or paraboloid maps, or a cap of 0.
        let warped = LightSetup {
            warp_depth: Some(Vec4::Z),
            ..ortho(2048.0, None)
        };
        assert_eq!(bias_clamp(&warped, 0, 2048, caps(4.0)), 0.0);
        let paraboloid = LightSetup {
            projection: MapProjection::Paraboloid,
            ..ortho(2048.0, None)
        };
        assert_eq!(bias_clamp(&paraboloid, 0, 2048, caps(4.0)), 0.0);
        assert_eq!(bias_clamp(&ortho(2048.0, None), 0, 2048, caps(0.0)), 0.0);
        // Each kind of map takes its own cap.
        let split = BiasCaps {
            directional: 4.0,
            local: 0.0,
        };
        assert_eq!(
            bias_clamp(&ortho(2048.0, None), 0, 2048, split),
            2f32.powi(-8)
        );
    }

    #[test]
    fn the_perspective_cap_is_texel_widths_at_the_mean_distance() {
        // near 1, far 16: mean distance 4. A map of 1024 texels over a
        // 90° face (2 units wide at unit distance) has texels 2/1024 wide
        // at unit distance, 8/1024 at 4; z = f(d − n)/(d(f − n)) moves by
        // f·n/(d²(f − n)) = 16/(16·15) per unit there, so 8 texels of depth
        // are 8 · 8/1024 / 15 = 2^-6 · 4/15 ≈ 2^-7.9, rounded to 2^-8.
        let cube = LightSetup {
            projection: MapProjection::Cube,
            near: 1.0,
            far: 16.0,
            ..ortho(2.0, None)
        };
        let c = bias_clamp(&cube, 0, 1024, caps(8.0));
        assert_eq!(c, 2f32.powi(-8), "{}", c.log2());
        // The same depth step by finite difference of z at d = 4.
        let z = |d: f32| 16.0 * (d - 1.0) / (d * 15.0);
        let step = z(4.0 + 8.0 * 8.0 / 1024.0) - z(4.0);
        assert!(
            (step.log2() - c.log2()).abs() < 0.15,
            "{} {}",
            step.log2(),
            c.log2()
        );
        let spot = LightSetup {
            projection: MapProjection::Perspective,
            ..cube.clone()
        };
        assert_eq!(bias_clamp(&spot, 0, 1024, caps(8.0)), c);
        // No cap for a degenerate range.
        let flat = LightSetup { far: 1.0, ..cube };
        assert_eq!(bias_clamp(&flat, 0, 1024, caps(8.0)), 0.0);
    }
}
