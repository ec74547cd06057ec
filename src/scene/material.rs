//! Phong materials, their textures and procedural patterns ([004]).

use anyhow::{Context, Result, bail};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Procedural texture patterns of [004].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProceduralKind {
    /// Alternating bands along object-space x.
    Stripes,
    /// 3D checkerboard.
    Checker,
    /// `sin(x·f + turbulence)`, turbulence = Σ |noise(2^o p)| / 2^o... weighted 1/o.
    Marble,
    /// Σ_o |noise(o·p)| / o.
    Turbulence,
}

/// A procedural texture evaluated in the fragment shader from the
/// object-space position.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Procedural {
    pub kind: ProceduralKind,
    pub color_a: Vec3,
    pub color_b: Vec3,
    /// Pattern frequency (cycles per object-space unit).
    pub scale: f32,
    /// Perlin octaves for marble and turbulence.
    pub octaves: u32,
}

/// Most Perlin octaves a procedural texture may sum: each costs one noise
/// evaluation per pixel, and beyond 16 the finest octave is far below a
/// pixel at any scale the scenes use.
pub const MAX_OCTAVES: u32 = 16;

impl Procedural {
    /// Checks colours, scale and octave count.
    pub fn validate(&self) -> Result<()> {
        if !(self.color_a.is_finite() && self.color_b.is_finite()) {
            bail!("procedural texture has a non-finite colour");
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            bail!(
                "procedural texture scale must be a positive finite number, got {}",
                self.scale
            );
        }
        if !(1..=MAX_OCTAVES).contains(&self.octaves) {
            bail!(
                "procedural texture octaves must be in 1..={MAX_OCTAVES}, got {}",
                self.octaves
            );
        }
        Ok(())
    }
}

/// A decoded RGBA8 image used as a diffuse texture or a normal map.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub image: image::RgbaImage,
    /// True for colour textures (sampled as sRGB), false for normal maps.
    pub srgb: bool,
    pub source: Option<PathBuf>,
    /// How coordinates outside [0, 1] read it, along u and along v (the
    /// glTF sampler's `wrapS`, `wrapT`).
    pub wrap: [TextureWrap; 2],
}

/// What a texture coordinate outside [0, 1] reads along one axis (glTF 2.0
/// sampler `wrapS`/`wrapT`, OpenGL's wrap modes), bilinear taps included.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TextureWrap {
    /// The texture tiles (glTF's default, and OBJ/MTL's).
    #[default]
    Repeat,
    /// The border texels extend outwards.
    ClampToEdge,
    /// The texture tiles, every other copy mirrored.
    MirroredRepeat,
}

impl TextureWrap {
    /// The texel a tap at integer coordinate `i` reads on an axis of `n`
    /// texels.
    pub fn texel(self, i: i64, n: i64) -> i64 {
        match self {
            TextureWrap::Repeat => i.rem_euclid(n),
            TextureWrap::ClampToEdge => i.clamp(0, n - 1),
            TextureWrap::MirroredRepeat => {
                let k = i.rem_euclid(2 * n);
                if k < n { k } else { 2 * n - 1 - k }
            }
        }
    }

    /// The glTF sampler enum (OpenGL's constant).
    pub fn gl_constant(self) -> u32 {
        match self {
            TextureWrap::Repeat => 10497,
            TextureWrap::ClampToEdge => 33071,
            TextureWrap::MirroredRepeat => 33648,
        }
    }

    /// The index the shaders decode (`WRAP_*` in common.wgsl).
    pub fn index(self) -> u32 {
        self as u32
    }
}

/// How a material's opacity is used (glTF 2.0 `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AlphaMode {
    /// Opacity ignored: the surface is solid.
    #[default]
    Opaque,
    /// A cut-out: the surface exists where opacity ≥ `alpha_cutoff`.
    Mask,
    /// Translucent: the surface lets `1 − opacity` of the light through.
    Blend,
}

impl AlphaMode {
    /// The glTF spelling (`OPAQUE`, `MASK`, `BLEND`).
    pub fn gltf_name(self) -> &'static str {
        match self {
            AlphaMode::Opaque => "OPAQUE",
            AlphaMode::Mask => "MASK",
            AlphaMode::Blend => "BLEND",
        }
    }
}

impl Texture {
    /// Makes the image's alpha channel hold its opacity, for a map that
    /// gives opacity as grey levels (MTL `map_d`): an image whose alpha is
    /// all opaque takes its red channel as alpha.
    pub fn opacity_in_alpha(&mut self) {
        if self.image.pixels().all(|p| p[3] == 255) {
            for p in self.image.pixels_mut() {
                p[3] = p[0];
            }
        }
    }
}

/// Phong material ([004]): `ka`, `kd`, `ks`, shininess `n`, with the
/// opacity and sidedness of glTF 2.0 materials.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub ka: Vec3,
    pub kd: Vec3,
    pub ks: Vec3,
    pub shininess: f32,
    /// Opacity factor in 0..=1 (glTF `baseColorFactor` alpha, MTL `d`),
    /// multiplied by the alpha texture's value.
    pub alpha: f32,
    pub alpha_mode: AlphaMode,
    /// Opacity below which a [`AlphaMode::Mask`] surface is a hole (glTF
    /// default ½).
    pub alpha_cutoff: f32,
    /// The texture whose alpha channel is the opacity (glTF: the base
    /// colour texture; MTL: `map_d`).
    pub alpha_texture: Option<usize>,
    /// Seen and lit from both sides (glTF `doubleSided`): never culled, its
    /// normal faces the viewer.
    pub double_sided: bool,
    pub diffuse_texture: Option<usize>,
    pub normal_map: Option<usize>,
    pub procedural: Option<Procedural>,
    /// Tiling of texture coordinates.
    pub uv_scale: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            ka: Vec3::splat(0.2),
            kd: Vec3::splat(0.8),
            ks: Vec3::splat(0.2),
            shininess: 32.0,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            alpha_texture: None,
            double_sided: false,
            diffuse_texture: None,
            normal_map: None,
            procedural: None,
            uv_scale: 1.0,
        }
    }
}

impl Material {
    /// Checks coefficients, texture references (against `textures`
    /// loaded textures) and the procedural texture.
    pub fn validate(&self, textures: usize) -> Result<()> {
        self.check(textures)
            .with_context(|| format!("material '{}'", self.name))
    }

    fn check(&self, textures: usize) -> Result<()> {
        for (field, c) in [("ka", self.ka), ("kd", self.kd), ("ks", self.ks)] {
            if !(c.is_finite() && c.min_element() >= 0.0) {
                bail!("{field} must be finite and non-negative, got {c}");
            }
        }
        if !(0.0..=1000.0).contains(&self.shininess) {
            bail!("shininess must be in 0..=1000, got {}", self.shininess);
        }
        if !(self.uv_scale.is_finite() && self.uv_scale > 0.0) {
            bail!(
                "uv_scale must be a positive finite number, got {}",
                self.uv_scale
            );
        }
        for (field, v) in [("alpha", self.alpha), ("alpha_cutoff", self.alpha_cutoff)] {
            if !(0.0..=1.0).contains(&v) {
                bail!("{field} must be in 0..=1, got {v}");
            }
        }
        for (field, t) in [
            ("diffuse texture", self.diffuse_texture),
            ("normal map", self.normal_map),
            ("alpha texture", self.alpha_texture),
        ] {
            if let Some(i) = t.filter(|&i| i >= textures) {
                bail!("{field} index {i} out of range ({textures} textures)");
            }
        }
        match &self.procedural {
            Some(p) => p.validate(),
            None => Ok(()),
        }
    }

    /// Whether the surface can have holes or let light through: opacity
    /// matters to it.
    pub fn is_see_through(&self) -> bool {
        self.alpha_mode != AlphaMode::Opaque
    }

    pub fn color(name: &str, kd: Vec3) -> Material {
        Material {
            name: name.into(),
            ka: kd,
            kd,
            ..Default::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::TextureWrap;

    /// Taps past either border of 4 texels: repeat tiles, clamp holds the
    /// border texel, mirror reflects about the border (−1 → 0, 4 → 3, and
    /// the next copy 8 → 0 the right way round).
    #[test]
    fn wrap_modes_read_the_texels_gltf_says() {
        let taps = [-5, -1, 0, 3, 4, 7, 8];
        let read = |w: TextureWrap| taps.map(|i| w.texel(i, 4));
        assert_eq!(read(TextureWrap::Repeat), [3, 3, 0, 3, 0, 3, 0]);
        assert_eq!(read(TextureWrap::ClampToEdge), [0, 0, 0, 3, 3, 3, 3]);
        assert_eq!(read(TextureWrap::MirroredRepeat), [3, 0, 0, 3, 3, 0, 0]);
    }
}
