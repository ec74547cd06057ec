//! The shadow-map family's uniform (`ShadowMap` of shadow_map.wgsl) and
//! its slots: one per face for the depth pass and lookup, two for the blur.

use crate::scene::Light;
use crate::technique::shadow_map::config::{
    CullFace, DepthFormat, Filter, Select, ShadowMapConfig,
};
use crate::technique::shadow_map::projection::setup::LightSetup;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, UVec4, Vec4};

/// `ShadowMapUniform::moment_depth` where moment filters take the map's
/// whole depth range: offset 0, scale 1.
const WHOLE_MOMENT_DEPTH: Vec4 = Vec4::new(0.0, 1.0, 0.0, 0.0);

/// The most faces (cube) or cascades one light's maps have.
pub const MAX_FACES: usize = 8;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ShadowMapUniform {
    pub faces: [Mat4; MAX_FACES],
    /// xyz the light's position, w which solids' lit faces the maps store
    /// ([`solids_stored`]): receivers on the others take no normal offset.
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
    /// x the stored depth moment filters take as 0, y the scale to 1
    /// (`LightSetup::moment_depth`).
    pub moment_depth: Vec4,
    /// x the widest a shadow edge's ramp may be on screen, in pixels
    /// (`edge_ramp_pixels`), y the reach in texels of the ramp it steepens
    /// (`ShadowMapConfig::ramp_reach`; 0: none), z the tangent of the
    /// receiver plane's crease angle (0 without a receiver plane), w unused.
    pub screen: Vec4,
}

impl ShadowMapUniform {
    /// The fields the parameters, the light and the maps' culling
    /// (`CullFace::for_shape`) fix: light, kernel, soft-shadow and moment
    /// terms (moment depth over the whole range); the rest zero. Under a
    /// light without an area the soft filters get no penumbra unless
    /// `hard_light_penumbra` pretends one.
    pub fn with_filter(
        c: &ShadowMapConfig,
        normal_offset: f32,
        light: &Light,
        cull: CullFace,
    ) -> ShadowMapUniform {
        let penumbra = if light.area.is_some() || c.hard_light_penumbra {
            1.0
        } else {
            0.0
        };
        ShadowMapUniform {
            light: light
                .position
                .extend(solids_stored(cull, c.solid_front_bias)),
            kernel: Vec4::new(c.radius, normal_offset, c.slope_bias, c.normal_offset_power),
            soft: Vec4::new(
                c.light_size * penumbra,
                c.varwidth_scale * penumbra,
                c.varwidth_exponent,
                c.blocker_search,
            ),
            moments: Vec4::new(
                c.bleeding_reduction,
                if c.filter == Filter::Esm {
                    c.esm_exponent
                } else {
                    c.exponent
                },
                c.exponent_negative,
                c.moment_bias,
            ),
            moment_depth: WHOLE_MOMENT_DEPTH,
            screen: Vec4::new(
                c.edge_ramp_pixels,
                c.ramp_reach(light.area.is_some()),
                c.crease_slope(),
                0.0,
            ),
            ..ShadowMapUniform::zeroed()
        }
    }
}

/// `ShadowMapUniform::light.w`: 0 where every caster stores both faces, 1
/// where solids store their back faces alone (`cull=solids`), 2 where
/// concave solids also store their front faces (`solid_front_bias` > 0).
fn solids_stored(cull: CullFace, solid_front_bias: f32) -> f32 {
    match cull {
        CullFace::Solids if solid_front_bias > 0.0 => 2.0,
        CullFace::Solids => 1.0,
        _ => 0.0,
    }
}

/// Uniform slots: per face, the depth pass (and lookup), blur along x, blur along y.
pub const STRIDE: u64 = 1024;
pub const SLOTS: u64 = MAX_FACES as u64 * 3;

/// What one frame's uniforms share beyond the parameters: the maps' side
/// and format, an area light's radius (PCSS), the normal offset of the
/// light's type, the maps' culling, the moment blur's radius and the view
/// of the camera the cascades were fitted to.
pub struct FrameTerms {
    pub size: u32,
    pub format: DepthFormat,
    pub area_radius: f32,
    pub normal_offset: f32,
    pub cull: CullFace,
    pub blur: u32,
    pub fit_view: Mat4,
}

/// The byte offset of slot (s·MAX_FACES + f)·3 + k: sample s (one light, or
/// an area light's samples), face f; k = 0 depth pass and lookup, 1 and 2
/// blur along x and y.
pub fn slot_offset(sample: usize, face: u32, k: u32) -> u64 {
    ((sample as u64 * MAX_FACES as u64 + face as u64) * 3 + k as u64) * STRIDE
}

/// The uniform buffer's contents for `lights` (one, or an area light's
/// samples) and their `setups`, at [`slot_offset`]s.
pub fn slot_data(
    c: &ShadowMapConfig,
    lights: &[Light],
    setups: &[LightSetup],
    t: &FrameTerms,
) -> Vec<u8> {
    let size = t.size as f32;
    let mut data = vec![0u8; (lights.len() as u64 * SLOTS * STRIDE) as usize];
    for (si, (light, setup)) in lights.iter().zip(setups).enumerate() {
        let mut faces = [Mat4::IDENTITY; MAX_FACES];
        faces[..setup.faces.len()].copy_from_slice(&setup.faces);
        let mut cascade_far = [0.0f32; MAX_FACES];
        let mut cascade_texel = [0.0f32; MAX_FACES];
        if let Some(split) = &setup.cascades {
            cascade_far[..split.far.len()].copy_from_slice(&split.far);
            for (texel, scale) in cascade_texel.iter_mut().zip(&split.texel_scales) {
                *texel = scale / size;
            }
        }
        let pack = |v: [f32; MAX_FACES]| [Vec4::from_slice(&v[..4]), Vec4::from_slice(&v[4..])];
        let base = ShadowMapUniform {
            faces,
            map: Vec4::new(size, 1.0 / size, setup.texel_scale / size, c.kernel_reach()),
            depth: Vec4::new(
                setup.near,
                setup.far,
                t.area_radius,
                c.depth_bias as f32 * t.format.depth_step(),
            ),
            face: UVec4::ZERO,
            cascade: Vec4::new(
                setup.cascades.as_ref().map_or(0, |s| s.far.len()) as f32,
                c.cascades.blend,
                setup.cascades.as_ref().map_or(0.0, |s| s.near),
                (c.cascades.select == Select::Map) as u32 as f32,
            ),
            cascade_far: pack(cascade_far),
            cascade_texel: pack(cascade_texel),
            cascade_view_z: t.fit_view.row(2),
            warp: light.direction.normalize_or_zero().extend(0.0),
            warp_depth: setup.warp_depth.unwrap_or(Vec4::ZERO),
            moment_depth: setup.moment_depth.map_or(WHOLE_MOMENT_DEPTH, |w| {
                Vec4::new(w.x, 1.0 / (w.y - w.x).max(1e-6), 0.0, 0.0)
            }),
            ..ShadowMapUniform::with_filter(c, t.normal_offset, light, t.cull)
        };
        for f in 0..MAX_FACES as u32 {
            for k in 0..3u32 {
                let u = ShadowMapUniform {
                    face: UVec4::new(f, k.saturating_sub(1), t.blur, 0),
                    ..base
                };
                let at = slot_offset(si, f, k) as usize;
                data[at..at + std::mem::size_of::<ShadowMapUniform>()]
                    .copy_from_slice(bytemuck::bytes_of(&u));
            }
        }
    }
    data
}

#[cfg(test)]
mod wgsl_tests {
    use super::*;

    /// The family's shader as the device gets it, after the frame's shared
    /// declarations.
    fn shadow_map_wgsl() -> String {
        crate::frame::technique_source(&[&super::super::pipelines::module_source()])
    }

    /// `ShadowMap` of shadow_map.wgsl is laid out as `ShadowMapUniform`
    /// (every member's offset, the face count, the size).
    #[test]
    fn the_uniform_matches_its_wgsl_struct() {
        let source = shadow_map_wgsl();
        crate::gpu::wgsl_layout::assert_struct_matches(
            &source,
            "ShadowMap",
            crate::field_offsets!(ShadowMapUniform; faces, light, kernel, map, soft, depth, face,
                moments, cascade, cascade_far, cascade_texel, cascade_view_z, warp, warp_depth,
                moment_depth, screen),
            std::mem::size_of::<ShadowMapUniform>(),
        );
    }

    /// Every group-2 variable of the module is bound where
    /// [`super::super::binding`] says, and every binding declared is used.
    #[test]
    fn the_bindings_match_their_wgsl_variables() {
        let source = shadow_map_wgsl();
        let mut wgsl = crate::gpu::wgsl_layout::wgsl_bindings(&source, 2);
        let mut rust: Vec<(String, u32)> = super::super::binding::NAMED
            .iter()
            .map(|(n, b)| (n.to_string(), *b))
            .collect();
        wgsl.sort();
        rust.sort();
        assert_eq!(
            wgsl, rust,
            "group 2: WGSL (left) against gpu::binding (right)"
        );
    }
}
