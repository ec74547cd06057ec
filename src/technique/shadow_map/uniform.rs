//! The shadow-map family's uniform (`ShadowMap` of shadow_map.wgsl) and
//! its slots: one per face for the depth pass and lookup, two for the blur.

use super::config::{CullFace, ShadowMapConfig};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, UVec4, Vec3, Vec4};

/// The most faces (cube) or cascades one light's maps have.
pub const MAX_FACES: usize = 8;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ShadowMapUniform {
    pub faces: [Mat4; MAX_FACES],
    /// xyz the light's position, w 1 where receivers on solids take no
    /// normal offset (`cull=solids`).
    pub light: Vec4,
    pub kernel: Vec4,
    pub map: Vec4,
    pub soft: Vec4,
    pub depth: Vec4,
    pub face: UVec4,
    pub moments: Vec4,
    /// x cascades (0: not cascaded), y blend fraction, z view depth where
    /// the first cascade starts, w 1 where the maps choose the cascade
    /// (`select=map`), 0 where the view depth does.
    pub cascade: Vec4,
    /// View depth at which each cascade ends.
    pub cascade_far: [Vec4; 2],
    /// Each cascade's world texel size.
    pub cascade_texel: [Vec4; 2],
    /// Row z of the view matrix of the camera the cascades were fitted to:
    /// a point's view depth is −dot(row, (p, 1)).
    pub cascade_view_z: Vec4,
    /// xyz the direction the light travels, w unused (`MapShape::warped`).
    pub warp: Vec4,
    /// Warped faces: the row giving a point's stored (linear) depth.
    pub warp_depth: Vec4,
}

impl ShadowMapUniform {
    /// The fields the parameters, the light's position and the maps' culling
    /// (`CullFace::for_shape`) fix: light, kernel, soft-shadow and moment
    /// terms; the rest zero.
    pub fn with_filter(
        c: &ShadowMapConfig,
        normal_offset: f32,
        light_position: Vec3,
        cull: CullFace,
    ) -> ShadowMapUniform {
        ShadowMapUniform {
            light: light_position.extend((cull == CullFace::Solids) as u32 as f32),
            kernel: Vec4::new(
                c.radius,
                normal_offset,
                c.slope_bias,
                c.normal_offset_slope as u32 as f32,
            ),
            soft: Vec4::new(
                c.light_size,
                c.varwidth_scale,
                c.varwidth_exponent,
                c.blocker_search,
            ),
            moments: Vec4::new(
                c.bleeding_reduction,
                c.exponent,
                c.exponent_negative,
                c.moment_bias,
            ),
            ..ShadowMapUniform::zeroed()
        }
    }
}

/// Uniform slots: per face, the depth pass (and lookup), blur along x, blur along y.
pub const STRIDE: u64 = 768;
pub const SLOTS: u64 = MAX_FACES as u64 * 3;
