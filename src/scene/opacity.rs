//! Opacity of see-through surfaces (glTF `MASK` and `BLEND` materials, MTL
//! `map_d`): the mip chains of their opacity maps, and what a shadow ray
//! crossing a caster triangle at a barycentric point lets through. Both ray
//! tracing kernels use [`CasterOpacity`]; the GPU passes use the same maps
//! ([`OpacityMaps::texels`]) at a level chosen for their texel footprint.

use super::{AlphaMode, Material, Object, Scene, Texture, TextureWrap};
use glam::Vec2;
use std::collections::HashMap;

/// An opacity map and its box-filtered mip chain, one byte per texel.
#[derive(Clone, Debug)]
pub struct OpacityMap {
    pub width: u32,
    pub height: u32,
    /// Level 0 first; each level half the previous one (at least 1).
    pub levels: Vec<Vec<u8>>,
    /// Its texture's wrap modes along u and v.
    pub wrap: [TextureWrap; 2],
}

impl OpacityMap {
    /// The alpha channel of `t` and its mip chain.
    pub fn of(t: &Texture) -> OpacityMap {
        let (width, height) = t.image.dimensions();
        let mut levels = vec![t.image.pixels().map(|p| p[3]).collect::<Vec<u8>>()];
        let (mut w, mut h) = (width, height);
        while w > 1 || h > 1 {
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let prev = levels.last().expect("level 0 exists");
            let at = |x: u32, y: u32| prev[(y.min(h - 1) * w + x.min(w - 1)) as usize] as u32;
            let next = (0..nh)
                .flat_map(|y| (0..nw).map(move |x| (x, y)))
                .map(|(x, y)| {
                    let s = at(2 * x, 2 * y)
                        + at(2 * x + 1, 2 * y)
                        + at(2 * x, 2 * y + 1)
                        + at(2 * x + 1, 2 * y + 1);
                    s.div_ceil(4) as u8
                })
                .collect();
            levels.push(next);
            (w, h) = (nw, nh);
        }
        OpacityMap {
            width,
            height,
            levels,
            wrap: t.wrap,
        }
    }

    /// Bilinear opacity of level 0 at `uv` (wrapped as its texture says),
    /// in 0..=1: the reference's full-resolution lookup (texel centres at
    /// half-integers, as GPU samplers place them).
    pub fn sample(&self, uv: Vec2) -> f32 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return 1.0;
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |dx: i64, dy: i64| {
            let tx = self.wrap[0].texel(x0 as i64 + dx, w);
            let ty = self.wrap[1].texel(y0 as i64 + dy, h);
            self.levels[0][(ty * w + tx) as usize] as f32 / 255.0
        };
        let top = texel(0, 0) * (1.0 - fx) + texel(1, 0) * fx;
        let bottom = texel(0, 1) * (1.0 - fx) + texel(1, 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// The opacity maps of a scene's see-through materials, by texture.
#[derive(Clone, Debug, Default)]
pub struct OpacityMaps {
    pub maps: Vec<OpacityMap>,
    /// Texture index → index in `maps`.
    pub of_texture: HashMap<usize, usize>,
}

impl OpacityMaps {
    /// The maps of every texture a see-through material takes its opacity
    /// from.
    pub fn of(scene: &Scene) -> OpacityMaps {
        let mut out = OpacityMaps::default();
        for m in scene.materials.iter().filter(|m| m.is_see_through()) {
            if let Some(t) = m.alpha_texture
                && !out.of_texture.contains_key(&t)
            {
                out.of_texture.insert(t, out.maps.len());
                out.maps.push(OpacityMap::of(&scene.textures[t]));
            }
        }
        out
    }

    /// The map of `m`'s opacity texture, if it has one.
    pub fn for_material(&self, m: &Material) -> Option<&OpacityMap> {
        m.alpha_texture
            .filter(|_| m.is_see_through())
            .and_then(|t| self.of_texture.get(&t))
            .map(|&i| &self.maps[i])
    }
}

/// What a surface does to a shadow ray that crosses it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Crossing {
    /// Stops it.
    Blocks,
    /// Lets it through untouched (a cut-out's hole).
    Passes,
    /// Lets this fraction of the light through (a translucent surface).
    Transmits(f32),
}

/// One see-through caster triangle: its material and texture coordinates.
#[derive(Clone, Copy, Debug)]
struct SeeThroughFace {
    material: u32,
    uvs: [Vec2; 3],
    /// The caster triangle of the surface it lies on: itself, or for a
    /// back face [`super::Mesh::make_double_sided`] added, its front face.
    surface: u32,
}

/// The see-through triangles among a scene's shadow casters, indexed as
/// [`Scene::world_triangles`] lists the casters, for the ray tracers.
#[derive(Clone, Debug, Default)]
pub struct CasterOpacity {
    maps: OpacityMaps,
    materials: Vec<Material>,
    /// Per caster triangle: 0 for an opaque one, else its face + 1.
    face_of: Vec<u32>,
    faces: Vec<SeeThroughFace>,
}

impl CasterOpacity {
    /// The see-through casters among the objects `filter` selects (the
    /// same filter the triangles were listed with), or `None` when every
    /// caster is opaque.
    pub fn of(scene: &Scene, filter: impl Fn(&Object) -> bool) -> Option<CasterOpacity> {
        let see_through = |o: &Object| scene.materials[o.material].is_see_through();
        if !scene.objects.iter().any(|o| filter(o) && see_through(o)) {
            return None;
        }
        let mut out = CasterOpacity {
            maps: OpacityMaps::of(scene),
            materials: scene.materials.clone(),
            ..Default::default()
        };
        for o in scene.objects.iter().filter(|o| filter(o)) {
            let m = &scene.meshes[o.mesh];
            let first = out.face_of.len();
            let front_faces = if m.sides_doubled {
                m.triangle_count() / 2
            } else {
                m.triangle_count()
            };
            for (i, t) in m.indices.chunks_exact(3).enumerate() {
                if !see_through(o) {
                    out.face_of.push(0);
                    continue;
                }
                let uv = |k: usize| m.uvs.get(t[k] as usize).copied().unwrap_or(Vec2::ZERO);
                out.faces.push(SeeThroughFace {
                    material: o.material as u32,
                    uvs: [uv(0), uv(1), uv(2)],
                    surface: (first + i % front_faces) as u32,
                });
                out.face_of.push(out.faces.len() as u32);
            }
        }
        Some(out)
    }

    /// Whether caster triangle `prim` is see-through at all.
    pub fn is_see_through(&self, prim: usize) -> bool {
        self.face_of.get(prim).is_some_and(|&f| f != 0)
    }

    /// What caster triangle `prim` does to a ray crossing it at barycentric
    /// `(u, v)` (the point `(1 − u − v)·v0 + u·v1 + v·v2`): opacity is
    /// the material's factor times its map's bilinear value there. The
    /// crossing names the surface crossed (front and back face of a
    /// double-sided one are one surface).
    pub fn crossing(&self, prim: usize, u: f32, v: f32) -> (usize, Crossing) {
        let Some(face) = self.face_of.get(prim).filter(|&&f| f != 0) else {
            return (prim, Crossing::Blocks);
        };
        let face = &self.faces[*face as usize - 1];
        (face.surface as usize, self.surface_crossing(face, u, v))
    }

    fn surface_crossing(&self, face: &SeeThroughFace, u: f32, v: f32) -> Crossing {
        let m = &self.materials[face.material as usize];
        let [a, b, c] = face.uvs;
        let uv = (a * (1.0 - u - v) + b * u + c * v) * m.uv_scale;
        let alpha = m.alpha * self.maps.for_material(m).map_or(1.0, |map| map.sample(uv));
        match m.alpha_mode {
            AlphaMode::Opaque => Crossing::Blocks,
            AlphaMode::Mask if alpha >= m.alpha_cutoff => Crossing::Blocks,
            AlphaMode::Mask => Crossing::Passes,
            AlphaMode::Blend => Crossing::Transmits(1.0 - alpha),
        }
    }
}

/// Light a shadow ray carries past the see-through surfaces it crosses:
/// the product of their transmittances, each surface counted once (a
/// kernel may report a triangle twice when its BVH splits it, and a
/// double-sided surface has two triangles).
#[derive(Clone, Debug)]
pub struct Transmittance {
    pub value: f32,
    crossed: Vec<usize>,
}

/// Below this, a ray carries no light worth tracing on (1/65536: under the
/// precision of the visibility masks).
const OPAQUE_ENOUGH: f32 = 1.0 / 65536.0;

impl Default for Transmittance {
    fn default() -> Self {
        Transmittance {
            value: 1.0,
            crossed: vec![],
        }
    }
}

impl Transmittance {
    /// Accounts for crossing surface `surface` as `crossing` says; true
    /// when the ray is now blocked (the kernel may stop).
    pub fn cross(&mut self, (surface, crossing): (usize, Crossing)) -> bool {
        match crossing {
            Crossing::Blocks => {
                self.value = 0.0;
                true
            }
            Crossing::Passes => false,
            Crossing::Transmits(t) => {
                if !self.crossed.contains(&surface) {
                    self.crossed.push(surface);
                    self.value *= t;
                }
                if self.value <= OPAQUE_ENOUGH {
                    self.value = 0.0;
                }
                self.value == 0.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, h: u32, alpha: impl Fn(u32, u32) -> u8) -> Texture {
        Texture {
            name: "t".into(),
            image: image::RgbaImage::from_fn(w, h, |x, y| {
                image::Rgba([255, 255, 255, alpha(x, y)])
            }),
            srgb: true,
            source: None,
            wrap: Default::default(),
        }
    }

    #[test]
    fn mip_chains_halve_down_to_one_texel_and_average() {
        let map = OpacityMap::of(&texture(4, 2, |x, _| if x < 2 { 255 } else { 0 }));
        let sizes: Vec<usize> = map.levels.iter().map(Vec::len).collect();
        assert_eq!(sizes, [8, 2, 1]);
        assert_eq!(map.levels[1], [255, 0]);
        assert_eq!(map.levels[2], [128]);
    }

    #[test]
    fn bilinear_lookup_hits_texel_centres_and_repeats() {
        let map = OpacityMap::of(&texture(2, 1, |x, _| if x == 0 { 255 } else { 0 }));
        assert_eq!(map.sample(Vec2::new(0.25, 0.5)), 1.0);
        assert_eq!(map.sample(Vec2::new(0.75, 0.5)), 0.0);
        assert!((map.sample(Vec2::new(0.5, 0.5)) - 0.5).abs() < 1e-6);
        // Repeats: u = 1.25 is u = 0.25; u = 0 lies between texel 1 and 0.
        assert_eq!(map.sample(Vec2::new(1.25, 0.5)), 1.0);
        assert!((map.sample(Vec2::new(0.0, 0.5)) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn two_half_transparent_panes_pass_a_quarter_and_count_once() {
        let mut t = Transmittance::default();
        assert!(!t.cross((3, Crossing::Transmits(0.5))));
        assert!(
            !t.cross((3, Crossing::Transmits(0.5))),
            "the same pane again"
        );
        assert!(!t.cross((7, Crossing::Passes)));
        assert!(!t.cross((9, Crossing::Transmits(0.5))));
        assert_eq!(t.value, 0.25);
        assert!(t.cross((1, Crossing::Blocks)));
        assert_eq!(t.value, 0.0);
    }
}
