//! glTF 2.0 import (meshes, materials (`materials`), textures, KHR_lights_punctual,
//! KHR_mesh_quantization, cameras, `extras.shadowlab` flags) and export of a resolved scene in
//! world space (`export`).

mod attributes;
mod checks;
mod export;
mod extras;
mod materials;

pub use export::export;

use super::{
    Camera, Light, Material, Mesh, Object, Scene, Texture, TextureWrap, frame_scene_defaults,
};
use anyhow::{Context, Result, anyhow, bail};
use attributes::MESH_QUANTIZATION;
use checks::{
    check_accessors, check_attribute_indices, check_external_files, check_glb_layout,
    check_node_forest, check_primitive_accessors, scene_roots, validated, without_panics,
};
use extras::{ShadowFlags, extras_field};
use glam::{Mat4, Vec2, Vec3};
use materials::{appearance_extensions_left, base_colour_texture, material_of, uv_transform};
use std::path::Path;

fn to_rgba(img: &gltf::image::Data) -> Result<image::RgbaImage> {
    use gltf::image::Format::*;
    let px = &img.pixels;
    let rgba: Vec<u8> = match img.format {
        R8G8B8A8 => px.clone(),
        R8G8B8 => px
            .chunks_exact(3)
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect(),
        R8G8 => px
            .chunks_exact(2)
            .flat_map(|c| [c[0], c[0], c[0], c[1]])
            .collect(),
        R8 => px.iter().flat_map(|&c| [c, c, c, 255]).collect(),
        f => bail!("unsupported texture format {f:?}"),
    };
    image::RgbaImage::from_raw(img.width, img.height, rgba).ok_or_else(|| anyhow!("bad image size"))
}

/// Loads a `.gltf` or `.glb` file. Node transforms are baked into each
/// object's transform; lights come from KHR_lights_punctual, the camera from
/// the first camera node.
pub fn load_scene(path: &Path) -> Result<Scene> {
    let file = path.display().to_string();
    without_panics(&file, || load_checked(&file, path))
}

/// The document's images, decoded; `None` for one that is missing or
/// cannot be decoded (warned about).
fn read_images(
    file: &str,
    doc: &gltf::Document,
    base: &Path,
    buffers: &[gltf::buffer::Data],
) -> Vec<Option<gltf::image::Data>> {
    // An image that is missing or cannot be decoded leaves its materials
    // their flat colour, with a warning (as the OBJ loader does).
    doc.images()
        .map(|im| {
            gltf::image::Data::from_source(im.source(), Some(base), buffers)
                .map_err(|e| {
                    let name = match im.source() {
                        gltf::image::Source::Uri { uri, .. } => format!(" '{uri}'"),
                        gltf::image::Source::View { .. } => String::new(),
                    };
                    log::warn!(
                        "{file}: image {}{name}: {e}; using the flat material colour",
                        im.index()
                    )
                })
                .ok()
        })
        .collect()
}

/// A KHR_lights_punctual light at `pos`, shining along `forward`.
fn light_of(l: &gltf::khr_lights_punctual::Light, pos: Vec3, forward: Vec3) -> Result<Light> {
    use gltf::khr_lights_punctual::Kind;
    let mut light = match l.kind() {
        Kind::Directional => Light::directional(forward, l.intensity()),
        Kind::Point => Light::point(pos, l.intensity()),
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => Light::spot(
            pos,
            pos + forward,
            l.intensity(),
            inner_cone_angle.to_degrees(),
            outer_cone_angle.to_degrees(),
        ),
    };
    light.color = l.color().into();
    light.range = l.range().unwrap_or(0.0);
    if let Some(area) = extras_field::<super::LightArea>(l.extras(), "light")? {
        light.area = Some(area);
    }
    Ok(light)
}

/// What a primitive's attributes are read from: the buffers, each
/// material's KHR_texture_transform, and whether the file uses
/// KHR_mesh_quantization (integer attributes).
struct AttributeSources<'a> {
    buffers: &'a [gltf::buffer::Data],
    uv_transforms: &'a [Option<glam::Mat3>],
    quantized: bool,
}

/// Primitive `pi` of `gmesh` (on node `name`) as a mesh, its texture
/// coordinates through its material's KHR_texture_transform.
fn read_mesh(
    file: &str,
    gmesh: &gltf::Mesh,
    name: &str,
    pi: usize,
    prim: &gltf::Primitive,
    sources: &AttributeSources,
) -> Result<Mesh> {
    use attributes::read_floats;
    use gltf::Semantic;
    let uv_set = base_colour_uv_set(prim);
    let mesh_name = gmesh.name().unwrap_or(name);
    check_primitive_accessors(file, mesh_name, pi, prim, uv_set, sources.quantized)?;
    let buffers = sources.buffers;
    let mut positions: Vec<Vec3> = prim
        .get(&Semantic::Positions)
        .and_then(|a| read_floats::<3>(a, buffers, false))
        .ok_or_else(|| anyhow!("{file}: mesh '{mesh_name}' has no POSITION"))?
        .into_iter()
        .map(Vec3::from)
        .collect();
    let reader = prim.reader(|b| Some(&buffers[b.index()]));
    let vertices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    let indices = triangle_list(prim.mode(), &vertices).expect("triangle modes only");
    // Quantised normals are unit only up to their rounding.
    let mut normals: Vec<Vec3> = prim
        .get(&Semantic::Normals)
        .and_then(|a| read_floats::<3>(a, buffers, false))
        .map(|n| {
            n.into_iter()
                .map(|n| Vec3::from(n).normalize_or_zero())
                .collect()
        })
        .unwrap_or_default();
    attributes::add_default_morph(file, gmesh, prim, buffers, &mut positions, &mut normals);
    let transform = prim
        .material()
        .index()
        .and_then(|i| sources.uv_transforms[i])
        .unwrap_or(glam::Mat3::IDENTITY);
    let uvs = prim
        .get(&Semantic::TexCoords(uv_set))
        .and_then(|a| read_floats::<2>(a, buffers, !sources.quantized))
        .map(|t| {
            t.into_iter()
                .map(|uv| transform.transform_point2(Vec2::from(uv)))
                .collect()
        })
        .unwrap_or_default();
    Ok(Mesh {
        name: mesh_name.to_string(),
        normals,
        uvs,
        colors: vertex_colours(file, mesh_name, pi, prim, buffers),
        positions,
        indices,
        ..Default::default()
    })
}

/// The primitive's `COLOR_0` as linear RGB, which multiplies its material's
/// colour; empty where it has none, or one of a type glTF does not allow
/// (warned about). Its alpha is not read: on a cut-out or translucent
/// material a warning says so where it is below 1.
fn vertex_colours(
    file: &str,
    mesh: &str,
    pi: usize,
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Vec<Vec3> {
    use gltf::accessor::{DataType as T, Dimensions as D};
    let Some(a) = prim.get(&gltf::Semantic::Colors(0)) else {
        return vec![];
    };
    let allowed = matches!(a.data_type(), T::U8 | T::U16 | T::F32)
        && matches!(a.dimensions(), D::Vec3 | D::Vec4);
    if !allowed {
        log::warn!(
            "{file}: mesh '{mesh}' primitive {pi}: COLOR_0 is {:?} of {:?}, not VEC3 or VEC4 of FLOAT or normalised UNSIGNED_BYTE or UNSIGNED_SHORT; ignored",
            a.dimensions(),
            a.data_type()
        );
        return vec![];
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(colours) = reader.read_colors(0) else {
        return vec![];
    };
    let rgba: Vec<[f32; 4]> = colours.into_rgba_f32().collect();
    if prim.material().alpha_mode() != gltf::material::AlphaMode::Opaque
        && rgba.iter().any(|c| c[3] < 1.0)
    {
        log::warn!(
            "{file}: mesh '{mesh}' primitive {pi}: COLOR_0's alpha is not applied (the material's opacity alone is)"
        );
    }
    rgba.iter()
        .map(|&[r, g, b, _]| Vec3::new(r, g, b))
        .collect()
}

/// The texture coordinate set (`TEXCOORD_n`) the primitive's base colour
/// texture reads (its KHR_texture_transform may name another), whose alpha
/// is also its opacity: the one set a mesh keeps.
fn base_colour_uv_set(prim: &gltf::Primitive) -> u32 {
    prim.material()
        .pbr_metallic_roughness()
        .base_color_texture()
        .map_or(0, |info| {
            let transform = info.texture_transform().and_then(|t| t.tex_coord());
            transform.unwrap_or(info.tex_coord())
        })
}

/// The triangle list of a primitive's `vertices` drawn in `mode` (glTF 2.0
/// §3.7.2.1): strip triangle i is (v_i, v_{i+1+i%2}, v_{i+2−i%2}), which
/// keeps every triangle's winding; fan triangle i is (v_{i+1}, v_{i+2},
/// v_0). Triangles a strip's repeated vertices make degenerate (its
/// restarts) are left out. `None` for points and lines.
fn triangle_list(mode: gltf::mesh::Mode, vertices: &[u32]) -> Option<Vec<u32>> {
    use gltf::mesh::Mode;
    let triangles: Vec<[u32; 3]> = match mode {
        Mode::Triangles => return Some(vertices.to_vec()),
        Mode::TriangleStrip => (0..vertices.len().saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [vertices[i], vertices[i + 1 + odd], vertices[i + 2 - odd]]
            })
            .collect(),
        Mode::TriangleFan => (1..vertices.len().saturating_sub(1))
            .map(|i| [vertices[i], vertices[i + 1], vertices[0]])
            .collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => return None,
    };
    let proper = |t: &[u32; 3]| t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
    Some(triangles.into_iter().filter(proper).flatten().collect())
}

/// A perspective camera node at `pos`, turned by `rot`, looking along
/// `forward`.
fn camera_of(c: &gltf::Camera, pos: Vec3, rot: glam::Quat, forward: Vec3) -> Option<Camera> {
    let gltf::camera::Projection::Perspective(p) = c.projection() else {
        return None;
    };
    Some(Camera {
        eye: pos,
        target: pos + forward,
        up: rot * Vec3::Y,
        fov_y_deg: p.yfov().to_degrees(),
        near: p.znear(),
        far: p.zfar().unwrap_or(p.znear() * 1e4),
    })
}

/// The scene's textures made from the document's images, once per image
/// and colour space.
struct TextureCache<'a> {
    file: &'a str,
    images: &'a [Option<gltf::image::Data>],
    /// Scene textures by image, colour space and wrap modes: two glTF
    /// textures of one image and sampler are one texture.
    made: std::collections::HashMap<(usize, bool, [TextureWrap; 2]), usize>,
}

/// The extension whose textures are KTX2 (Basis Universal) images.
const TEXTURE_BASISU: &str = "KHR_texture_basisu";

/// A texture that names its image only through KHR_texture_basisu (a file
/// that requires the extension) is pointed at that image, and the
/// extension leaves the required ones: the `image` crate cannot decode
/// KTX2, so each such image is warned about and its materials fall back to
/// their flat colour, as for a missing image, instead of refusing the file.
/// A texture that also names a PNG or JPEG keeps it.
fn ktx2_textures_named(root: &mut gltf::json::Root) {
    let empty = gltf::json::Index::<gltf::json::Image>::new(u32::MAX);
    for t in &mut root.textures {
        let basisu_source = t
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(TEXTURE_BASISU))
            .and_then(|b| b["source"].as_u64())
            .and_then(|i| u32::try_from(i).ok());
        if let (true, Some(i)) = (t.source == empty, basisu_source) {
            t.source = gltf::json::Index::new(i);
        }
    }
    root.extensions_required.retain(|e| e != TEXTURE_BASISU);
}

/// A glTF sampler's wrap mode.
fn wrap_of(mode: gltf::texture::WrappingMode) -> TextureWrap {
    use gltf::texture::WrappingMode;
    match mode {
        WrappingMode::Repeat => TextureWrap::Repeat,
        WrappingMode::ClampToEdge => TextureWrap::ClampToEdge,
        WrappingMode::MirroredRepeat => TextureWrap::MirroredRepeat,
    }
}

impl TextureCache<'_> {
    /// The scene texture of `t` (sRGB or linear), added on first use;
    /// `None` for an image that is missing or unusable (warned about).
    fn get(&mut self, scene: &mut Scene, t: gltf::Texture, srgb: bool) -> Option<usize> {
        let idx = t.source().index();
        let wrap = [t.sampler().wrap_s(), t.sampler().wrap_t()].map(wrap_of);
        if let Some(&i) = self.made.get(&(idx, srgb, wrap)) {
            return Some(i);
        }
        // A missing image was reported when it was read.
        let image = self.images.get(idx)?.as_ref()?;
        match to_rgba(image) {
            Ok(image) => {
                scene.textures.push(Texture {
                    name: t.source().name().unwrap_or("texture").into(),
                    image,
                    srgb,
                    source: None,
                    wrap,
                });
                self.made
                    .insert((idx, srgb, wrap), scene.textures.len() - 1);
                Some(scene.textures.len() - 1)
            }
            Err(e) => {
                let file = self.file;
                log::warn!("{file}: image {idx} unusable ({e}); using the flat material colour");
                None
            }
        }
    }
}

/// Loads a `.gltf` or `.glb` file's `bytes` (a file opened in the browser
/// page): external buffers and images are looked for under `base`.
pub fn load_scene_bytes(name: &str, bytes: &[u8], base: &Path) -> Result<Scene> {
    let stem = Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("gltf");
    without_panics(name, || load_bytes(name, bytes, base, stem))
}

fn load_checked(file: &str, path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {file}"))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("gltf");
    load_bytes(file, &bytes, base, stem)
}

/// The file parsed without the importer's validation. One whose
/// animations the `gltf` crate cannot parse (KHR_animation_pointer's
/// channels target no node) is read without them, with a warning: the lab
/// draws the rest pose and reads no animation. Any other error stands.
fn parsed(file: &str, bytes: &[u8]) -> Result<gltf::Gltf> {
    let error = match gltf::Gltf::from_slice_without_validation(bytes) {
        Ok(parsed) => return Ok(parsed),
        Err(e) => anyhow!("{file}: {e}"),
    };
    let parsed = without_animations(bytes).ok_or(error)?;
    log::warn!("{file}: its animations cannot be read; drawing the rest pose without them");
    Ok(parsed)
}

/// The file parsed with its `animations` left out, where it has some and
/// parses without them.
fn without_animations(bytes: &[u8]) -> Option<gltf::Gltf> {
    let (json, blob) = if bytes.starts_with(b"glTF") {
        let glb = gltf::Glb::from_slice(bytes).ok()?;
        (
            glb.json.into_owned(),
            glb.bin.map(std::borrow::Cow::into_owned),
        )
    } else {
        (bytes.to_vec(), None)
    };
    let mut value: serde_json::Value = serde_json::from_slice(&json).ok()?;
    value.as_object_mut()?.remove("animations")?;
    let root = serde_json::from_value(value).ok()?;
    Some(gltf::Gltf {
        document: gltf::Document::from_json_without_validation(root),
        blob,
    })
}

/// The nodes the traversal starts from: the default scene's roots (else
/// the first scene's), or, in a file without scenes, every node without a
/// parent (as Blender imports such a file), with a warning.
fn drawn_roots(file: &str, doc: &gltf::Document, parents: &[Option<usize>]) -> Vec<usize> {
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(gscene) => scene_roots(file, &gscene, parents),
        None => {
            log::warn!(
                "{file}: no scene; drawing every node without a parent (as Blender imports such a file)"
            );
            (0..parents.len())
                .filter(|&i| parents[i].is_none())
                .collect()
        }
    }
}

fn load_bytes(file: &str, bytes: &[u8], base: &Path, stem: &str) -> Result<Scene> {
    let file = file.to_string();
    if bytes.starts_with(b"glTF") {
        check_glb_layout(&file, bytes)?;
    }
    // One parse without the importer's validation serves the checks that
    // must come before it. KHR_mesh_quantization, which the `gltf` crate
    // does not know, is read here (`attributes`), so it leaves the required
    // extensions before the crate validates the rest.
    let gltf::Gltf { document, blob } = parsed(&file, bytes)?;
    let mut root = document.into_json();
    check_attribute_indices(&file, &root)?;
    check_external_files(&file, base, &root)?;
    let quantized = root.extensions_used.iter().any(|e| e == MESH_QUANTIZATION);
    root.extensions_required.retain(|e| e != MESH_QUANTIZATION);
    ktx2_textures_named(&mut root);
    appearance_extensions_left(&file, &mut root);
    let doc = validated(&file, root)?;
    let buffers =
        gltf::import_buffers(&doc, Some(base), blob).map_err(|e| anyhow!("{file}: {e}"))?;
    let images = read_images(&file, &doc, base, &buffers);
    let parents = check_node_forest(&file, &doc)?;
    check_accessors(&file, &doc, &buffers)?;
    let mut scene = Scene::new(stem);
    scene.source = file.clone();
    let mut textures = TextureCache {
        file: &file,
        images: &images,
        made: Default::default(),
    };
    // Per material, the base colour texture's KHR_texture_transform, baked
    // into the texture coordinates of the primitives that use it.
    let mut uv_transforms: Vec<Option<glam::Mat3>> = vec![];
    for m in doc.materials() {
        uv_transforms.push(uv_transform(&m));
        let mut mat = material_of(&m)?;
        mat.diffuse_texture =
            base_colour_texture(&m).and_then(|t| textures.get(&mut scene, t.texture(), true));
        mat.alpha_texture = mat.diffuse_texture.filter(|_| mat.is_see_through());
        mat.normal_map = m
            .normal_texture()
            .and_then(|t| textures.get(&mut scene, t.texture(), false));
        scene.add_material(mat);
    }
    let default_mat = scene.add_material(Material::default());
    let sources = AttributeSources {
        buffers: &buffers,
        uv_transforms: &uv_transforms,
        quantized,
    };
    let mut mesh_ids = std::collections::HashMap::new();
    let mut camera = None;
    let roots = drawn_roots(&file, &doc, &parents);
    // Breadth-first in document order, so objects keep the node order.
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut queue: std::collections::VecDeque<(gltf::Node, Mat4)> = roots
        .into_iter()
        .map(|i| (nodes[i].clone(), Mat4::IDENTITY))
        .collect();
    while let Some((node, parent)) = queue.pop_front() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let name = node.name().unwrap_or("node").to_string();
        for c in node.children() {
            queue.push_back((c, world));
        }
        let (_, rot, pos) = world.to_scale_rotation_translation();
        let forward = (rot * Vec3::NEG_Z).normalize();
        if let Some(l) = node.light() {
            scene.lights.push(light_of(&l, pos, forward)?);
        }
        if camera.is_none() {
            camera = node.camera().and_then(|c| camera_of(&c, pos, rot, forward));
        }
        let Some(gmesh) = node.mesh() else { continue };
        let flags: ShadowFlags =
            extras_field(node.extras(), &format!("{file}: node '{name}'"))?.unwrap_or_default();
        for (pi, prim) in gmesh.primitives().enumerate() {
            if triangle_list(prim.mode(), &[]).is_none() {
                log::warn!(
                    "{file}: mesh '{}' primitive {pi} is {:?}, not triangles (points and lines cast no shadow); skipped",
                    gmesh.name().unwrap_or(""),
                    prim.mode()
                );
                continue;
            }
            let key = (gmesh.index(), pi);
            let mesh_id = match mesh_ids.get(&key) {
                Some(&id) => id,
                None => {
                    let mesh = read_mesh(&file, &gmesh, &name, pi, &prim, &sources)?;
                    let id = scene.add_mesh(mesh);
                    mesh_ids.insert(key, id);
                    id
                }
            };
            let mat = prim.material().index().unwrap_or(default_mat);
            let mut obj = Object::from_name(&name, mesh_id, mat, world);
            obj.casts_shadow = flags.casts_shadow.unwrap_or(obj.casts_shadow);
            obj.receives_shadow = flags.receives_shadow.unwrap_or(obj.receives_shadow);
            obj.shadow_plane = flags.shadow_plane.unwrap_or(obj.shadow_plane);
            scene.objects.push(obj);
        }
    }
    if scene.objects.is_empty() {
        bail!("{file}: no triangle meshes");
    }
    let had_lights = !scene.lights.is_empty();
    frame_scene_defaults(&mut scene);
    if let Some(c) = camera {
        scene.camera = c;
    }
    scene.default_light = !had_lights;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gltf::mesh::Mode;

    /// Strips alternate their second and third vertices, so every triangle
    /// keeps the first one's winding; fans turn about vertex 0; a strip's
    /// restart (repeated vertices) leaves no degenerate triangle; points
    /// and lines have none.
    #[test]
    fn strips_and_fans_become_triangle_lists_wound_as_drawn() {
        let strip = triangle_list(Mode::TriangleStrip, &[0, 1, 2, 3, 4]).unwrap();
        assert_eq!(strip, [0, 1, 2, 1, 3, 2, 2, 3, 4]);
        let fan = triangle_list(Mode::TriangleFan, &[0, 1, 2, 3]).unwrap();
        assert_eq!(fan, [1, 2, 0, 2, 3, 0]);
        // Triangles 1 to 4 repeat a vertex; 5 is odd, so its last two swap.
        let restarted = triangle_list(Mode::TriangleStrip, &[0, 1, 2, 2, 5, 5, 6, 7, 8]).unwrap();
        assert_eq!(restarted, [0, 1, 2, 5, 7, 6, 6, 7, 8]);
        assert!(
            triangle_list(Mode::TriangleStrip, &[0, 1])
                .unwrap()
                .is_empty()
        );
        assert_eq!(
            triangle_list(Mode::Triangles, &[3, 4, 5]).unwrap(),
            [3, 4, 5]
        );
        for mode in [Mode::Points, Mode::Lines, Mode::LineLoop, Mode::LineStrip] {
            assert!(triangle_list(mode, &[0, 1, 2]).is_none());
        }
    }
}
