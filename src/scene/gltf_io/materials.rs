//! A glTF material as the lab reads it: Phong terms, base colour and its
//! texture, alpha mode, cutoff and sidedness — from metallic-roughness, or
//! from KHR_materials_pbrSpecularGlossiness's diffuse where a file uses
//! that instead — and the appearance-only extensions a file may require
//! that the lab does not read.

use super::extras::{PhongExtras, extras_field};
use crate::scene::{AlphaMode, Material};
use anyhow::Result;
use glam::{Vec2, Vec3};

/// Material extensions that change how a surface is shaded, not where it
/// is or what light it stops: a file that requires one is read with the
/// core material (its base colour and alpha mode) and a warning, not
/// refused. KHR_materials_pbrSpecularGlossiness is read (its diffuse is the
/// base colour); KHR_materials_transmission is not: such a surface casts
/// the shadow its alpha mode says.
const APPEARANCE_EXTENSION_PREFIX: &str = "KHR_materials_";
const SPECULAR_GLOSSINESS: &str = "KHR_materials_pbrSpecularGlossiness";

/// Takes the required material extensions off the list the importer
/// validates, warning about each one the lab does not read.
pub fn appearance_extensions_left(file: &str, root: &mut gltf::json::Root) {
    root.extensions_required.retain(|e| {
        let appearance = e.starts_with(APPEARANCE_EXTENSION_PREFIX);
        if appearance && e != SPECULAR_GLOSSINESS {
            log::warn!(
                "{file}: requires {e}, which shadowlab does not read; its materials are drawn and cast shadows as their core glTF material (base colour, alphaMode)"
            );
        }
        !appearance
    });
}

/// The base colour factor (RGBA): KHR_materials_pbrSpecularGlossiness's
/// diffuse where the material has it, else metallic-roughness's.
fn base_colour_factor(m: &gltf::Material) -> [f32; 4] {
    match m.pbr_specular_glossiness() {
        Some(sg) => sg.diffuse_factor(),
        None => m.pbr_metallic_roughness().base_color_factor(),
    }
}

/// The base colour texture, from the same source as [`base_colour_factor`].
pub fn base_colour_texture<'a>(m: &gltf::Material<'a>) -> Option<gltf::texture::Info<'a>> {
    match m.pbr_specular_glossiness() {
        Some(sg) => sg.diffuse_texture(),
        None => m.pbr_metallic_roughness().base_color_texture(),
    }
}

/// Material `m`'s KHR_texture_transform of its base colour texture.
pub fn uv_transform(m: &gltf::Material) -> Option<glam::Mat3> {
    base_colour_texture(m)
        .and_then(|t| t.texture_transform())
        .map(|t| {
            glam::Mat3::from_scale_angle_translation(
                Vec2::from(t.scale()),
                t.rotation(),
                Vec2::from(t.offset()),
            )
        })
}

/// Material `m` without its textures: Phong terms from the shadowlab
/// extras or from metallic-roughness, the colour and alpha factor from
/// [`base_colour_factor`], and the alpha mode and cutoff.
pub fn material_of(m: &gltf::Material) -> Result<Material> {
    let pbr = m.pbr_metallic_roughness();
    let base = base_colour_factor(m);
    let mut mat = match extras_field::<PhongExtras>(m.extras(), "material")? {
        Some(p) => Material {
            ka: p.ka.into(),
            kd: p.kd.into(),
            ks: p.ks.into(),
            shininess: p.shininess,
            uv_scale: p.uv_scale,
            procedural: p.procedural,
            ..Material::default()
        },
        None => {
            // Phong from metallic-roughness: n = 2/r² − 2.
            let r = pbr.roughness_factor().max(0.05);
            Material {
                ks: Vec3::splat(0.04 + 0.5 * pbr.metallic_factor()),
                shininess: (2.0 / (r * r) - 2.0).clamp(1.0, 1000.0),
                ..Material::color("", Vec3::from_slice(&base[..3]))
            }
        }
    };
    mat.name = m.name().unwrap_or("material").into();
    mat.alpha = base[3].clamp(0.0, 1.0);
    mat.alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask,
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    };
    mat.alpha_cutoff = m.alpha_cutoff().unwrap_or(0.5).clamp(0.0, 1.0);
    mat.double_sided = m.double_sided();
    Ok(mat)
}
