//! The depth bias's cap of orthographic maps (`slope_bias_clamp`): so
//! many texel widths of depth, per map, cascade or clipmap level.

use super::setup::LightSetup;
use super::setup::MapProjection;

/// The depth bias's cap for `face` of `setup` in the map's depth units
/// ([`texel_bias_clamp`]); 0 (no cap) for perspective and warped maps.
pub fn bias_clamp(setup: &LightSetup, face: usize, size: u32, texels: f32) -> f32 {
    if setup.projection != MapProjection::Orthographic || setup.warp_depth.is_some() {
        return 0.0;
    }
    let scale = setup
        .cascades
        .as_ref()
        .and_then(|s| s.texel_scales.get(face).copied())
        .unwrap_or(setup.texel_scale);
    texel_bias_clamp(scale / size as f32, setup.far - setup.near, texels)
}

/// The depth bias's cap of an orthographic map whose texels are
/// `texel_world` wide over a depth range `depth_range`: `texels` texel
/// widths of depth, rounded to a quarter octave (few pipelines); 0 (no cap)
/// for `texels` = 0.
pub fn texel_bias_clamp(texel_world: f32, depth_range: f32, texels: f32) -> f32 {
    if texels <= 0.0 {
        return 0.0;
    }
    let clamp = texels * texel_world / depth_range.max(1e-6);
    2f32.powf((clamp.log2() * 4.0).round() / 4.0)
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
        }
    }

    #[test]
    fn the_bias_cap_is_texel_widths_of_the_depth_range() {
        // 2048 world units over 2048 texels: 1 per texel; 4 texels of a
        // 1024-unit depth range = 2^-8.
        assert_eq!(
            bias_clamp(&ortho(2048.0, None), 0, 2048, 4.0),
            2f32.powi(-8)
        );
        // 4.5 texels rounds to the nearest quarter octave, 2^(-8 + 1/4)·…
        let c = bias_clamp(&ortho(2048.0, None), 0, 2048, 4.5);
        assert!((c.log2() + 7.75).abs() < 1e-5, "{}", c.log2());
        // Each cascade its own texel.
        let cascaded = ortho(1024.0, Some(vec![1024.0, 4096.0]));
        assert_eq!(bias_clamp(&cascaded, 1, 2048, 4.0), 2f32.powi(-7));
        assert_eq!(bias_clamp(&cascaded, 0, 2048, 4.0), 2f32.powi(-9));
        // None for perspective or warped maps, or a cap of 0.
        let spot = LightSetup {
            projection: MapProjection::Perspective,
            ..ortho(2048.0, None)
        };
        assert_eq!(bias_clamp(&spot, 0, 2048, 4.0), 0.0);
        let warped = LightSetup {
            warp_depth: Some(Vec4::Z),
            ..ortho(2048.0, None)
        };
        assert_eq!(bias_clamp(&warped, 0, 2048, 4.0), 0.0);
        assert_eq!(bias_clamp(&ortho(2048.0, None), 0, 2048, 0.0), 0.0);
    }
}
