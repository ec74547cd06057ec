//! Scene model: indexed triangle meshes, Phong materials, objects with shadow
//! flags, lights and cameras, plus the loaders (OBJ/MTL, glTF, TOML) and the
//! built-in scenes.

pub mod aabb;
pub mod area;
pub mod builtin;
pub mod bvh;
pub mod camera;
pub mod clusters;
pub mod embree;
pub mod extent;
pub mod gltf_io;
pub mod hull;
pub mod landscape;
pub mod light;
pub mod material;
pub mod mesh;
pub mod mtl_map;
pub mod obj;
pub mod opacity;
pub mod orbit;
pub mod planes;
pub mod shapes;
pub mod toml_scene;
pub mod topology;

pub use aabb::Aabb;
pub use camera::{Camera, INFINITE_FAR_EPSILON, NEAR_PLANE_DEPTH};
pub use light::{Light, LightArea, LightType};
pub use material::{
    AlphaMode, MAX_OCTAVES, Material, Procedural, ProceduralKind, Texture, TextureWrap,
};
pub use mesh::{Mesh, compute_tangents, smooth_normals};

use anyhow::{Context, Result, bail};
use glam::{Mat4, Vec3};
use std::path::{Path, PathBuf};

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
    /// Whether the object's mesh must carry back faces: its material is
    /// double-sided and its mesh does not have them yet.
    fn needs_back_faces(&self, scene: &Scene) -> bool {
        scene.materials[self.material].double_sided && !scene.meshes[self.mesh].sides_doubled
    }

    /// Applies the naming conventions of [000] §5: a name ending in upper-case
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
    /// The file had no light and the loader placed a default one: said
    /// ([`Scene::warn_default_light`]) only where the run uses the scene's
    /// lights, not where they are replaced.
    pub default_light: bool,
}

impl Scene {
    /// Warns that the scene's light is the loader's default, when it is.
    pub fn warn_default_light(&self) {
        if self.default_light {
            log::warn!(
                "{}: the file has no light; placed a default point light",
                self.source
            );
        }
    }

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
            default_light: false,
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
        let mut doubled: std::collections::HashMap<usize, usize> = Default::default();
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
            // A double-sided material draws a copy of its mesh with back
            // faces (reversed winding, flipped normals): every pass then
            // sees both sides whatever its culling, and the normal faces the
            // viewer on each side.
            if o.needs_back_faces(self) {
                self.objects[i].mesh = self.mesh_copy(&mut doubled, o.mesh, |m| {
                    let mut m = m.clone();
                    m.make_double_sided();
                    m
                });
            }
            let o = &self.objects[i];
            // A mirroring transform turns counter-clockwise triangles
            // clockwise: draw a winding-reversed copy instead (once).
            if (det < 0.0) != o.winding_reversed {
                let copy = self.mesh_copy(&mut reversed, o.mesh, Mesh::with_reversed_winding);
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

    /// The copy of mesh `mesh` that `make` derives from it, made once per
    /// mesh: `copies` remembers each one made.
    fn mesh_copy(
        &mut self,
        copies: &mut std::collections::HashMap<usize, usize>,
        mesh: usize,
        make: impl FnOnce(&Mesh) -> Mesh,
    ) -> usize {
        if let Some(&c) = copies.get(&mesh) {
            return c;
        }
        let c = self.add_mesh(make(&self.meshes[mesh]));
        copies.insert(mesh, c);
        c
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
    let scene = match ext.as_str() {
        "obj" => obj::load_scene(path)?,
        "gltf" | "glb" => gltf_io::load_scene(path)?,
        "toml" => toml_scene::load(path, includes)?,
        _ => bail!(
            "{}: unknown scene format '.{}' (valid: .obj, .gltf, .glb, .toml)",
            path.display(),
            ext
        ),
    };
    finished(scene, &path.display().to_string())
}

/// Loads a scene file's `bytes` by the extension of its `name` (a glTF,
/// GLB or OBJ file opened in the browser page, which has no file system:
/// what it refers to outside itself is missing, with the loaders' own
/// errors and fallbacks).
pub fn load_bytes(name: &str, bytes: &[u8]) -> Result<Scene> {
    let ext = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let stem = Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("file");
    let scene = match ext.as_str() {
        "obj" => {
            let text = std::str::from_utf8(bytes).map_err(|_| {
                anyhow::anyhow!("{name}: an OBJ file is text, and this is not UTF-8")
            })?;
            obj::load_text(name, text, Path::new(""), stem)?
        }
        "gltf" | "glb" => gltf_io::load_scene_bytes(name, bytes, Path::new(""))?,
        _ => bail!("{name}: unknown scene format '.{ext}' (valid: .obj, .gltf, .glb)"),
    };
    finished(scene, name)
}

/// `scene` finalized, or an error when it has nothing to draw.
fn finished(mut scene: Scene, file: &str) -> Result<Scene> {
    scene.finalize().with_context(|| file.to_string())?;
    if scene.triangle_count() == 0 {
        bail!(
            "{file}: no triangles to draw (every triangle is degenerate, or every object is a shadow plane)"
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
        // What a shadow ray sees of the surface.
        let m = &scene.materials[o.material];
        (m.alpha_mode, m.alpha.to_bits(), m.alpha_cutoff.to_bits()).hash(&mut h);
        (m.alpha_texture, m.uv_scale.to_bits()).hash(&mut h);
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
