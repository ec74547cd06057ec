//! Scene model: indexed triangle meshes, Phong materials, objects with shadow
//! flags, lights and cameras, plus the loaders (OBJ/MTL, glTF, TOML) and the
//! built-in scenes.

pub mod area;
pub mod builtin;
pub mod bvh;
pub mod clusters;
pub mod embree;
pub mod gltf_io;
pub mod landscape;
pub mod obj;
pub mod planes;
pub mod shapes;
pub mod toml_scene;
pub mod topology;

use anyhow::{Context, Result, bail};
use glam::{Mat4, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// An indexed triangle mesh in object space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    /// xyz tangent, w handedness (±1), derived from the uvs.
    pub tangents: Vec<Vec4>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends `other` transformed by `m` (normals by its inverse transpose).
    pub fn append(&mut self, other: &Mesh, m: Mat4) {
        let base = self.positions.len() as u32;
        let nm = m.inverse().transpose();
        self.positions
            .extend(other.positions.iter().map(|&p| m.transform_point3(p)));
        self.normals.extend(
            other
                .normals
                .iter()
                .map(|&n| nm.transform_vector3(n).normalize_or_zero()),
        );
        self.uvs.extend_from_slice(&other.uvs);
        self.tangents.extend(other.tangents.iter().map(|t| {
            m.transform_vector3(t.truncate())
                .normalize_or_zero()
                .extend(t.w)
        }));
        self.indices.extend(other.indices.iter().map(|&i| i + base));
    }

    /// Validates the mesh and fills in what is missing: an error on NaN or
    /// infinite positions or out-of-range indices; degenerate triangles are
    /// dropped (the count is returned); missing normals become smooth
    /// area-weighted normals, missing uvs zero, tangents are derived from uvs.
    pub fn finalize(&mut self) -> Result<usize> {
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            bail!(
                "mesh '{}': vertex {} has a non-finite position {:?}",
                self.name,
                i,
                self.positions[i]
            );
        }
        if !self.indices.len().is_multiple_of(3) {
            bail!(
                "mesh '{}': index count {} is not a multiple of 3",
                self.name,
                self.indices.len()
            );
        }
        let n = self.positions.len() as u32;
        if let Some(&bad) = self.indices.iter().find(|&&i| i >= n) {
            bail!(
                "mesh '{}': index {} out of range ({} vertices)",
                self.name,
                bad,
                n
            );
        }
        let before = self.indices.len() / 3;
        let pos = &self.positions;
        let kept: Vec<u32> = self
            .indices
            .chunks_exact(3)
            .filter(|t| {
                let (a, b, c) = (pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
                t[0] != t[1]
                    && t[1] != t[2]
                    && t[0] != t[2]
                    && (b - a).cross(c - a).length_squared() > 0.0
            })
            .flatten()
            .copied()
            .collect();
        let degenerate = before - kept.len() / 3;
        self.indices = kept;
        if self.normals.len() != self.positions.len() || self.normals.iter().any(|n| !n.is_finite())
        {
            self.normals = smooth_normals(&self.positions, &self.indices);
        }
        if self.uvs.len() != self.positions.len() {
            self.uvs = vec![Vec2::ZERO; self.positions.len()];
        }
        self.tangents = compute_tangents(&self.positions, &self.normals, &self.uvs, &self.indices);
        Ok(degenerate)
    }

    /// Splits every triangle into its own three vertices with the face normal
    /// (OBJ `s off`, flat-shaded geometry).
    pub fn unweld_flat(&mut self) {
        let mut out = Mesh {
            name: self.name.clone(),
            ..Default::default()
        };
        for t in self.indices.chunks_exact(3) {
            let p: Vec<Vec3> = t.iter().map(|&i| self.positions[i as usize]).collect();
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            for (k, &i) in t.iter().enumerate() {
                out.positions.push(p[k]);
                out.normals.push(n);
                out.uvs
                    .push(self.uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
                out.indices.push(out.indices.len() as u32);
            }
        }
        *self = out;
    }

    /// Adds a copy of every triangle with the opposite winding and normal,
    /// so that a thin open surface is visible and lit from both sides.
    pub fn make_double_sided(&mut self) {
        let n = self.positions.len() as u32;
        self.positions.extend_from_within(..);
        let flipped: Vec<Vec3> = self.normals.iter().map(|&v| -v).collect();
        self.normals.extend(flipped);
        self.uvs.extend_from_within(..);
        // The back copy's normal is flipped; flipping the handedness keeps
        // its bitangent `cross(n, t)·w` and so its normal map the same.
        let back_tangents: Vec<Vec4> = self
            .tangents
            .iter()
            .map(|t| t.truncate().extend(-t.w))
            .collect();
        self.tangents.extend(back_tangents);
        let back: Vec<u32> = self
            .indices
            .chunks_exact(3)
            .flat_map(|t| [t[0] + n, t[2] + n, t[1] + n])
            .collect();
        self.indices.extend(back);
    }

    /// The same surface with every triangle's winding reversed (normals and
    /// tangents kept). Placed by a mirroring transform (negative
    /// determinant), it is wound counter-clockwise seen from outside again,
    /// as culling and shadow-volume counting assume; the scene shader flips
    /// the tangent handedness by the sign of the determinant.
    pub fn with_reversed_winding(&self) -> Mesh {
        let mut m = self.clone();
        for t in m.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        m.name = format!("{} (mirrored)", self.name);
        m
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }
}

/// Area-weighted vertex normals, accumulated over vertices welded by
/// position so that seams (duplicated vertices) shade smoothly.
pub fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut weld: std::collections::HashMap<[u32; 3], usize> = Default::default();
    let slot: Vec<usize> = positions
        .iter()
        .map(|p| {
            let next = weld.len();
            *weld.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    let mut n = vec![Vec3::ZERO; weld.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        let fnrm = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for v in [a, b, c] {
            n[slot[v]] += fnrm;
        }
    }
    slot.iter()
        .map(|&s| n[s].try_normalize().unwrap_or(Vec3::Y))
        .collect()
}

/// Per-vertex tangents from uv derivatives (Lengyel's method), Gram-Schmidt
/// orthogonalised against the normal, handedness in w.
pub fn compute_tangents(p: &[Vec3], n: &[Vec3], uv: &[Vec2], indices: &[u32]) -> Vec<Vec4> {
    let mut tan = vec![Vec3::ZERO; p.len()];
    let mut bit = vec![Vec3::ZERO; p.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        let (e1, e2) = (p[b] - p[a], p[c] - p[a]);
        let (d1, d2) = (uv[b] - uv[a], uv[c] - uv[a]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-12 {
            continue;
        }
        let r = 1.0 / det;
        let sdir = (e1 * d2.y - e2 * d1.y) * r;
        let tdir = (e2 * d1.x - e1 * d2.x) * r;
        for &v in &[a, b, c] {
            tan[v] += sdir;
            bit[v] += tdir;
        }
    }
    (0..p.len())
        .map(|i| {
            let nn = n[i];
            let t = (tan[i] - nn * nn.dot(tan[i]))
                .try_normalize()
                .unwrap_or_else(|| nn.any_orthonormal_vector());
            let w = if nn.cross(t).dot(bit[i]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            t.extend(w)
        })
        .collect()
}

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

/// Procedural texture patterns of SEEDS §1 (lecture 004).
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
}

/// Phong material (SEEDS §1): `ka`, `kd`, `ks`, shininess `n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub ka: Vec3,
    pub kd: Vec3,
    pub ks: Vec3,
    pub shininess: f32,
    /// Opacity (`d` in MTL); kept for export, rendering is opaque.
    pub alpha: f32,
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
        for (field, t) in [
            ("diffuse texture", self.diffuse_texture),
            ("normal map", self.normal_map),
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

    pub fn color(name: &str, kd: Vec3) -> Material {
        Material {
            name: name.into(),
            ka: kd,
            kd,
            ..Default::default()
        }
    }
}

/// One placed mesh with its shadow flags.
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub mesh: usize,
    pub material: usize,
    pub transform: Mat4,
    pub casts_shadow: bool,
    pub receives_shadow: bool,
    /// Defines a receiving plane for planar shadows (from its first
    /// triangle); such objects are not drawn.
    pub shadow_plane: bool,
    /// True once [`Scene::finalize`] has pointed a mirroring object (negative
    /// determinant) at a winding-reversed copy of its mesh.
    pub winding_reversed: bool,
}

impl Object {
    /// Applies the naming conventions of SEEDS §1: a name ending in upper-case
    /// `NS` casts no shadow; a name containing `ShadowPlane` is a shadow plane.
    pub fn from_name(name: &str, mesh: usize, material: usize, transform: Mat4) -> Object {
        let shadow_plane = name.contains("ShadowPlane");
        Object {
            name: name.to_string(),
            mesh,
            material,
            transform,
            casts_shadow: !name.ends_with("NS") && !shadow_plane,
            receives_shadow: true,
            shadow_plane,
            winding_reversed: false,
        }
    }
}

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
        if n.dot(to_light) <= 0.0 {
            return false;
        }
        if self.kind == LightType::Directional {
            return true;
        }
        let d = to_light.length();
        let in_cone = self.kind != LightType::Spot
            || (-to_light / d).dot(self.direction.normalize())
                > self.outer_cone_deg.to_radians().cos();
        in_cone && (self.range <= 0.0 || d < self.range)
    }

    pub fn validate(&self) -> Result<()> {
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

/// How far below 1 points at infinity land with
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
    /// Right-handed look-at view matrix.
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }
    /// Perspective projection onto wgpu's [0,1] depth range:
    /// `z_ndc = far/(near−far) · z_view/(−z_view) + near·far/(near−far)/(−z_view)`.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective(
            self.fov_y_deg.to_radians(),
            aspect,
            self.near,
            self.far,
        )
    }
    /// [`Camera::projection`] with the far plane at infinity, re-derived for
    /// [0,1] depth: with clip z = a·z_e + b and w = −z_e (z_e < 0 in front),
    /// z_ndc = −a − b/z_e; z_ndc(−near) = 0 gives b = a·near, and z_ndc → −a
    /// as z_e → −∞. Taking −a = 1 − [`INFINITE_FAR_EPSILON`] keeps points at
    /// infinity (w = 0 in, e.g. shadow-volume extrusions) inside the clip
    /// volume and in front of the cleared depth 1 despite rounding.
    pub fn projection_infinite(&self, aspect: f32) -> Mat4 {
        let mut m = self.projection(aspect);
        let a = -(1.0 - INFINITE_FAR_EPSILON);
        m.z_axis.z = a;
        m.w_axis.z = a * self.near;
        m
    }

    pub fn validate(&self) -> Result<()> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            bail!("camera has a non-finite vector");
        }
        if (self.target - self.eye).length_squared() < 1e-12 {
            bail!("camera eye and target coincide");
        }
        if (self.target - self.eye).cross(self.up).length_squared() < 1e-12 {
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

/// A complete scene with named presets.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub objects: Vec<Object>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub camera_presets: Vec<(String, Camera)>,
    pub light_presets: Vec<(String, Vec<Light>)>,
    /// Linear RGB.
    pub background: Vec3,
    /// Global ambient intensity multiplied by each material's `ka`.
    pub ambient: Vec3,
    /// Where the scene came from (a built-in name or a file).
    pub source: String,
    /// Hash of every mesh's positions and indices, taken by
    /// [`Scene::finalize`] (call it again after changing meshes).
    pub geometry_hash: u64,
}

impl Scene {
    pub fn new(name: &str) -> Scene {
        Scene {
            name: name.into(),
            meshes: vec![],
            materials: vec![],
            textures: vec![],
            objects: vec![],
            lights: vec![],
            camera: Camera::new(Vec3::new(0.0, 5.0, 10.0), Vec3::ZERO),
            camera_presets: vec![],
            light_presets: vec![],
            background: Vec3::new(0.05, 0.06, 0.08),
            ambient: Vec3::splat(0.15),
            source: name.into(),
            geometry_hash: 0,
        }
    }

    pub fn add_mesh(&mut self, mesh: Mesh) -> usize {
        self.meshes.push(mesh);
        self.meshes.len() - 1
    }
    pub fn add_material(&mut self, m: Material) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }
    pub fn add_object(&mut self, name: &str, mesh: usize, material: usize, t: Mat4) -> usize {
        self.objects
            .push(Object::from_name(name, mesh, material, t));
        self.objects.len() - 1
    }

    /// Finalises every mesh (see [`Mesh::finalize`]) and checks lights and
    /// camera; logs the number of degenerate triangles dropped.
    pub fn finalize(&mut self) -> Result<()> {
        for m in &mut self.meshes {
            let dropped = m.finalize()?;
            if dropped > 0 {
                log::warn!(
                    "mesh '{}': skipped {} degenerate triangle(s)",
                    m.name,
                    dropped
                );
            }
        }
        for m in &self.materials {
            m.validate(self.textures.len())?;
        }
        let mut reversed: std::collections::HashMap<usize, usize> = Default::default();
        for i in 0..self.objects.len() {
            let o = &self.objects[i];
            if !o.transform.is_finite() {
                bail!("object '{}' has a non-finite transform", o.name);
            }
            if o.mesh >= self.meshes.len() || o.material >= self.materials.len() {
                bail!("object '{}' references a missing mesh or material", o.name);
            }
            let det = glam::Mat3::from_mat4(o.transform).determinant();
            if det == 0.0 || !det.is_finite() || !o.transform.inverse().is_finite() {
                bail!(
                    "object '{}' has a singular transform (determinant {det}: a zero scale flattens it, so its normals and shadow volumes are undefined)",
                    o.name
                );
            }
            // A mirroring transform turns counter-clockwise triangles
            // clockwise: draw a winding-reversed copy instead (once).
            if (det < 0.0) != o.winding_reversed {
                let mesh = o.mesh;
                let copy = match reversed.get(&mesh) {
                    Some(&c) => c,
                    None => {
                        let c = self.add_mesh(self.meshes[mesh].with_reversed_winding());
                        reversed.insert(mesh, c);
                        c
                    }
                };
                let o = &mut self.objects[i];
                o.mesh = copy;
                o.winding_reversed = !o.winding_reversed;
                log::debug!("object '{}': mirrored transform, winding reversed", o.name);
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            l.validate().with_context(|| format!("light {i}"))?;
        }
        for (name, lights) in &self.light_presets {
            for (i, l) in lights.iter().enumerate() {
                l.validate()
                    .with_context(|| format!("light preset '{name}', light {i}"))?;
            }
        }
        self.camera.validate()?;
        self.geometry_hash = {
            use std::hash::Hasher;
            let mut h = std::collections::hash_map::DefaultHasher::new();
            for m in &self.meshes {
                h.write_usize(m.positions.len());
                h.write(bytemuck::cast_slice(&m.positions));
                h.write(bytemuck::cast_slice(&m.indices));
            }
            h.finish()
        };
        if self.camera_presets.is_empty() {
            self.camera_presets.push(("default".into(), self.camera));
        }
        if self.light_presets.is_empty() {
            self.light_presets
                .push(("default".into(), self.lights.clone()));
        }
        Ok(())
    }

    /// Triangles drawn (shadow planes excluded).
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .filter(|o| !o.shadow_plane)
            .map(|o| self.meshes[o.mesh].triangle_count())
            .sum()
    }
    /// Triangles of shadow-casting objects.
    pub fn caster_triangle_count(&self) -> usize {
        self.objects
            .iter()
            .filter(|o| o.casts_shadow && !o.shadow_plane)
            .map(|o| self.meshes[o.mesh].triangle_count())
            .sum()
    }
    pub fn bounds(&self) -> Aabb {
        self.objects
            .iter()
            .filter(|o| !o.shadow_plane)
            .fold(Aabb::EMPTY, |b, o| {
                b.union(self.meshes[o.mesh].bounds().transformed(o.transform))
            })
    }

    /// World-space triangles of the objects selected by `filter`.
    pub fn world_triangles(&self, filter: impl Fn(&Object) -> bool) -> Vec<[Vec3; 3]> {
        let mut out = vec![];
        for o in self.objects.iter().filter(|o| filter(o)) {
            let m = &self.meshes[o.mesh];
            let wp: Vec<Vec3> = m
                .positions
                .iter()
                .map(|&p| o.transform.transform_point3(p))
                .collect();
            out.extend(
                m.indices
                    .chunks_exact(3)
                    .map(|t| [wp[t[0] as usize], wp[t[1] as usize], wp[t[2] as usize]]),
            );
        }
        out
    }

    pub fn camera_preset(&self, name: &str) -> Result<Camera> {
        self.camera_presets
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, c)| *c)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "scene '{}' has no camera preset '{}' (valid: {})",
                    self.name,
                    name,
                    self.camera_presets
                        .iter()
                        .map(|p| p.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }
    pub fn light_preset(&self, name: &str) -> Result<Vec<Light>> {
        self.light_presets
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, l)| l.clone())
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "scene '{}' has no light preset '{}' (valid: {})",
                    self.name,
                    name,
                    self.light_presets
                        .iter()
                        .map(|p| p.0.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }
}

/// Loads a scene by built-in name or from a file (`.obj`, `.gltf`, `.glb`,
/// `.toml`).
pub fn load(name_or_path: &str) -> Result<Scene> {
    if let Some(s) = builtin::by_name(name_or_path)? {
        return Ok(s);
    }
    let path = Path::new(name_or_path);
    if !path.exists() {
        bail!(
            "'{}' is neither a built-in scene ({}) nor an existing file",
            name_or_path,
            builtin::NAMES.join(", ")
        );
    }
    load_file(path)
}

/// Loads a scene file by extension.
pub fn load_file(path: &Path) -> Result<Scene> {
    load_file_included(path, &[])
}

/// [`load_file`] for a file that scene files `includes` (outermost first)
/// include: an error names the chain when `path` is already on it.
pub fn load_file_included(path: &Path, includes: &[PathBuf]) -> Result<Scene> {
    if path.exists() && !path.is_file() {
        // A directory, FIFO or device: reading it fails or never ends.
        bail!("{}: not a regular file", path.display());
    }
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    if includes.contains(&canonical) {
        let chain: Vec<String> = includes
            .iter()
            .chain([&canonical])
            .map(|p| p.display().to_string())
            .collect();
        bail!(
            "scene files include each other in a cycle: {}",
            chain.join(" -> ")
        );
    }
    let includes: Vec<PathBuf> = includes.iter().cloned().chain([canonical]).collect();
    let includes = includes.as_slice();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut scene = match ext.as_str() {
        "obj" => obj::load_scene(path)?,
        "gltf" | "glb" => gltf_io::load_scene(path)?,
        "toml" => toml_scene::load(path, includes)?,
        _ => bail!(
            "{}: unknown scene format '.{}' (valid: .obj, .gltf, .glb, .toml)",
            path.display(),
            ext
        ),
    };
    scene
        .finalize()
        .with_context(|| path.display().to_string())?;
    if scene.triangle_count() == 0 {
        bail!(
            "{}: no triangles to draw (every triangle is degenerate, or every object is a shadow plane)",
            path.display()
        );
    }
    Ok(scene)
}

/// Identifies a scene's geometry and flags (object transforms and flags,
/// and the hash of every mesh's positions and indices that
/// [`Scene::finalize`] takes), so that per-scene data — adjacency, BVHs,
/// receiver planes — is rebuilt exactly when it changes.
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (&scene.source, scene.geometry_hash).hash(&mut h);
    for o in &scene.objects {
        (o.casts_shadow, o.receives_shadow, o.shadow_plane, o.mesh).hash(&mut h);
        for f in o.transform.to_cols_array() {
            f.to_bits().hash(&mut h);
        }
    }
    h.finish()
}

/// Places a default camera and light for a scene loaded from a model file
/// that brings neither.
pub fn frame_scene_defaults(scene: &mut Scene) {
    let b = scene.bounds();
    if b.is_empty() {
        return;
    }
    let c = b.center();
    let r = b.size().length().max(1e-3) * 0.5;
    let eye = c + Vec3::new(0.6, 0.5, 1.0).normalize() * r * 2.4;
    scene.camera = Camera {
        near: (r * 0.01).max(1e-3),
        far: r * 10.0,
        ..Camera::new(eye, c)
    };
    if scene.lights.is_empty() {
        scene
            .lights
            .push(Light::point(c + Vec3::new(-0.5, 1.5, 0.7) * r, 1.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fingerprint_changes_when_vertices_do() {
        let mut s = builtin::by_name("floating").unwrap().unwrap();
        let before = scene_fingerprint(&s);
        assert_eq!(scene_fingerprint(&s), before);
        // Same source, objects, transforms and vertex counts: only a vertex moves.
        s.meshes[0].positions[0].y += 0.5;
        s.finalize().unwrap();
        assert_ne!(scene_fingerprint(&s), before);
    }

    fn one_box() -> Scene {
        let mut s = Scene::new("t");
        let m = s.add_material(Material::default());
        let mesh = s.add_mesh(shapes::cuboid(Vec3::ONE));
        s.add_object("Box", mesh, m, Mat4::IDENTITY);
        s.lights = vec![Light::point(Vec3::new(0.0, 3.0, 0.0), 1.0)];
        s
    }

    #[test]
    fn double_sided_meshes_keep_a_tangent_per_vertex() {
        let mut m = shapes::plane(2.0, 2.0, 2);
        m.finalize().unwrap();
        let n = m.positions.len();
        m.make_double_sided();
        assert_eq!(m.tangents.len(), 2 * n);
        assert_eq!(m.normals.len(), 2 * n);
        // Same tangent, opposite handedness on the back copy.
        assert_eq!(m.tangents[n].truncate(), m.tangents[0].truncate());
        assert_eq!(m.tangents[n].w, -m.tangents[0].w);
    }

    #[test]
    fn materials_are_validated() {
        let mut s = one_box();
        s.materials[0].diffuse_texture = Some(3);
        let e = format!("{:#}", s.finalize().unwrap_err());
        assert!(
            e.contains("diffuse texture index 3 out of range (0 textures)"),
            "{e}"
        );
        let mut s = one_box();
        s.materials[0].procedural = Some(Procedural {
            kind: ProceduralKind::Marble,
            color_a: Vec3::ONE,
            color_b: Vec3::ZERO,
            scale: 1.0,
            octaves: 1000,
        });
        let e = format!("{:#}", s.finalize().unwrap_err());
        assert!(e.contains("octaves must be in 1..=16, got 1000"), "{e}");
        let mut s = one_box();
        s.materials[0].kd = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(s.finalize().is_err());
    }

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

    #[test]
    fn geometry_hash_follows_the_vertices() {
        let mut s = one_box();
        s.finalize().unwrap();
        let before = s.geometry_hash;
        s.finalize().unwrap();
        assert_eq!(s.geometry_hash, before, "same geometry, same hash");
        // Same counts, one vertex moved.
        s.meshes[0].positions[0].x += 0.25;
        s.finalize().unwrap();
        assert_ne!(s.geometry_hash, before);
    }
}
