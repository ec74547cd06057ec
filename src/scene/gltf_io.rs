//! glTF 2.0 import (meshes, base colour, textures, KHR_lights_punctual,
//! cameras, `extras.shadowlab` flags) and export of a resolved scene in
//! world space.

use super::{
    Camera, Light, LightType, Material, Mesh, Object, Scene, Texture, frame_scene_defaults,
};
use anyhow::{Context, Result, anyhow, bail};
use glam::{Mat4, Quat, Vec2, Vec3};
use serde_json::{Value, json};
use std::path::Path;

/// Per-node flags stored under `extras.shadowlab`.
#[derive(serde::Deserialize, serde::Serialize, Debug, Default)]
struct ShadowFlags {
    casts_shadow: Option<bool>,
    receives_shadow: Option<bool>,
    shadow_plane: Option<bool>,
}

/// Phong parameters stored under a material's `extras.shadowlab`.
#[derive(serde::Deserialize, serde::Serialize, Debug)]
struct PhongExtras {
    ka: [f32; 3],
    kd: [f32; 3],
    ks: [f32; 3],
    shininess: f32,
    uv_scale: f32,
    procedural: Option<super::Procedural>,
}

fn extras_field<T: serde::de::DeserializeOwned>(
    extras: &gltf::json::Extras,
    what: &str,
) -> Result<Option<T>> {
    let Some(raw) = extras else { return Ok(None) };
    let v: Value = serde_json::from_str(raw.get())?;
    match v.get("shadowlab") {
        Some(s) => Ok(Some(
            serde_json::from_value(s.clone())
                .with_context(|| format!("{what}: extras.shadowlab"))?,
        )),
        None => Ok(None),
    }
}

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

/// Checks that the node graph is a forest, as glTF 2.0 requires (§ 3.5.4
/// "Scenes"): no node is its own descendant, no node has two parents, and
/// no scene root is another node's child. Checked here rather than trusted
/// to the importer: a cycle would make the traversal below run forever and
/// shared children would multiply objects.
fn check_node_forest(file: &str, doc: &gltf::Document) -> Result<()> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            if c == node.index() {
                bail!("{file}: node {c} is its own child (a cycle in the node hierarchy)");
            }
            if let Some(p) = parent[c] {
                bail!(
                    "{file}: node {c} is a child of both node {p} and node {} (glTF nodes form trees; shared children are not allowed)",
                    node.index()
                );
            }
            parent[c] = Some(node.index());
        }
    }
    // With one parent each, a cycle is a loop of parent links that never
    // reaches a root: follow them, marking nodes known to reach a root.
    let mut reaches_root = vec![false; n];
    let mut walked_from = vec![usize::MAX; n];
    for start in 0..n {
        let mut path: Vec<usize> = vec![];
        let mut at = start;
        while !reaches_root[at] {
            if walked_from[at] == start {
                let first = path.iter().position(|&i: &usize| i == at).unwrap_or(0);
                let cycle: Vec<String> = path[first..].iter().map(|i| i.to_string()).collect();
                bail!(
                    "{file}: the node hierarchy has a cycle: node {} (each the child of the next)",
                    cycle.join(" -> node ")
                );
            }
            walked_from[at] = start;
            path.push(at);
            match parent[at] {
                Some(p) => at = p,
                None => break,
            }
        }
        for i in path {
            reaches_root[i] = true;
        }
    }
    for scene in doc.scenes() {
        for root in scene.nodes() {
            if let Some(p) = parent[root.index()] {
                bail!(
                    "{file}: scene {} lists node {} as a root, but it is a child of node {p}",
                    scene.index(),
                    root.index()
                );
            }
        }
    }
    Ok(())
}

/// Runs `f`, turning a panic — which the `gltf` crate raises on some
/// malformed documents that its validation lets through (found by fuzzing:
/// an attribute's accessor index out of range, an accessor whose element
/// size is not the attribute's) — into an error naming the file. The panic
/// message is not printed.
fn without_panics<T>(file: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    r.unwrap_or_else(|payload| {
        let why = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("unknown");
        bail!("{file}: malformed glTF (the importer failed: {why})")
    })
}

/// Checks that the accessors a primitive is read through have the types
/// glTF 2.0 requires (§ 3.7.2.1): POSITION and NORMAL `VEC3` of `FLOAT`,
/// TEXCOORD_0 `VEC2` of `FLOAT` or normalised `UNSIGNED_BYTE`/`SHORT`,
/// indices `SCALAR` of unsigned integers.
fn check_primitive_accessors(
    file: &str,
    mesh: &str,
    index: usize,
    prim: &gltf::Primitive,
) -> Result<()> {
    use gltf::Semantic;
    use gltf::accessor::{DataType as T, Dimensions as D};
    let float = [T::F32].as_slice();
    let uv = [T::F32, T::U8, T::U16].as_slice();
    let unsigned = [T::U8, T::U16, T::U32].as_slice();
    let rules: [(&str, Option<gltf::Accessor>, D, &[T]); 4] = [
        ("POSITION", prim.get(&Semantic::Positions), D::Vec3, float),
        ("NORMAL", prim.get(&Semantic::Normals), D::Vec3, float),
        ("TEXCOORD_0", prim.get(&Semantic::TexCoords(0)), D::Vec2, uv),
        ("indices", prim.indices(), D::Scalar, unsigned),
    ];
    for (what, accessor, dims, types) in rules {
        let Some(a) = accessor else { continue };
        if a.dimensions() != dims || !types.contains(&a.data_type()) {
            bail!(
                "{file}: mesh '{mesh}' primitive {index}: {what} accessor {} is {:?} of {:?}; glTF requires {dims:?} of {}",
                a.index(),
                a.dimensions(),
                a.data_type(),
                types
                    .iter()
                    .map(|t| format!("{t:?}"))
                    .collect::<Vec<_>>()
                    .join(" or ")
            );
        }
    }
    Ok(())
}

/// Checks that every mesh attribute names an existing accessor, which the
/// `gltf` crate's own validation assumes for `POSITION` (and panics on).
fn check_attribute_indices(file: &str, root: &gltf::json::Root) -> Result<()> {
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets = primitive.targets.iter().flatten().flat_map(|t| {
                [&t.positions, &t.normals, &t.tangents]
                    .into_iter()
                    .flatten()
                    .map(|i| ("targets", i.value()))
            });
            let attributes = primitive
                .attributes
                .values()
                .map(|i| ("attributes", i.value()))
                .chain(primitive.indices.iter().map(|i| ("indices", i.value())));
            for (what, index) in attributes.chain(targets) {
                if index >= accessors {
                    bail!(
                        "{file}: meshes[{m}].primitives[{p}].{what}: accessor {index} out of range ({accessors} accessors)"
                    );
                }
            }
        }
    }
    Ok(())
}

/// Checks, before the importer reads them, that every buffer and image a
/// glTF file names by URI (other than `data:` URIs) is a regular file: the
/// importer reads whatever a URI names, and `/dev/zero` or a FIFO would never
/// end.
fn check_external_files(file: &str, dir: &Path, root: &gltf::json::Root) -> Result<()> {
    let buffers = root
        .buffers
        .iter()
        .enumerate()
        .map(|(i, b)| ("buffer", i, &b.uri));
    let images = root
        .images
        .iter()
        .enumerate()
        .map(|(i, im)| ("image", i, &im.uri));
    for (what, index, uri) in buffers.chain(images) {
        let Some(uri) = uri.as_deref().filter(|u| !u.starts_with("data:")) else {
            continue;
        };
        let target = dir.join(uri);
        if !target.exists() {
            bail!("{file}: {what} {index}: '{uri}' not found");
        }
        if !target.is_file() {
            bail!("{file}: {what} {index}: '{uri}' is not a regular file");
        }
    }
    Ok(())
}

/// Checks a binary glTF's header and chunk lengths against the file, so
/// that a truncated or inconsistent file gets a message that says which.
fn check_glb_layout(file: &str, bytes: &[u8]) -> Result<()> {
    let word = |at: usize| -> Option<usize> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        bail!("{file}: GLB header truncated ({} bytes)", bytes.len());
    };
    if version != 2 {
        bail!("{file}: GLB version {version} (only 2 is supported)");
    }
    if length != bytes.len() {
        bail!(
            "{file}: GLB header declares {length} bytes but the file has {}",
            bytes.len()
        );
    }
    let mut at = 12;
    let mut chunk = 0;
    while at < bytes.len() {
        let Some(len) = word(at) else {
            bail!("{file}: GLB chunk {chunk} header truncated at byte {at}");
        };
        if at + 8 + len > bytes.len() {
            bail!(
                "{file}: GLB chunk {chunk} declares {len} bytes at byte {at}, past the end of the file ({} bytes)",
                bytes.len()
            );
        }
        at += 8 + len;
        chunk += 1;
    }
    Ok(())
}

/// Checks that every accessor's elements lie inside its buffer view and
/// every view inside its buffer (the importer's reader would otherwise
/// return nothing, and the message would blame a missing attribute).
fn check_accessors(file: &str, doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<()> {
    for view in doc.views() {
        let have = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
        if view.offset() + view.length() > have {
            bail!(
                "{file}: buffer view {}: bytes {}..{} past the end of buffer {} ({have} bytes)",
                view.index(),
                view.offset(),
                view.offset() + view.length(),
                view.buffer().index()
            );
        }
    }
    for a in doc.accessors() {
        let Some(view) = a.view() else { continue };
        let stride = view.stride().unwrap_or(a.size());
        let need = match a.count() {
            0 => 0,
            n => a.offset() + stride * (n - 1) + a.size(),
        };
        if need > view.length() {
            bail!(
                "{file}: accessor {}: {} elements of {} bytes (stride {stride}, offset {}) need {need} bytes, buffer view {} has {}",
                a.index(),
                a.count(),
                a.size(),
                a.offset(),
                view.index(),
                view.length()
            );
        }
    }
    Ok(())
}

/// Loads a `.gltf` or `.glb` file. Node transforms are baked into each
/// object's transform; lights come from KHR_lights_punctual, the camera from
/// the first camera node.
pub fn load_scene(path: &Path) -> Result<Scene> {
    let file = path.display().to_string();
    without_panics(&file, || load_checked(&file, path))
}

fn load_checked(file: &str, path: &Path) -> Result<Scene> {
    let file = file.to_string();
    let bytes = std::fs::read(path).with_context(|| format!("reading {file}"))?;
    if bytes.starts_with(b"glTF") {
        check_glb_layout(&file, &bytes)?;
    }
    // One parse without the importer's validation serves both checks that
    // must come before it.
    let root = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| anyhow!("{file}: {e}"))?
        .document
        .into_json();
    check_attribute_indices(&file, &root)?;
    check_external_files(&file, path.parent().unwrap_or(Path::new(".")), &root)?;
    let (doc, buffers, images) = gltf::import(path).map_err(|e| anyhow!("{file}: {e}"))?;
    check_node_forest(&file, &doc)?;
    check_accessors(&file, &doc, &buffers)?;
    let mut scene = Scene::new(path.file_stem().and_then(|s| s.to_str()).unwrap_or("gltf"));
    scene.source = file.clone();
    let mut tex_map = std::collections::HashMap::new();
    let mut texture = |scene: &mut Scene, t: gltf::Texture, srgb: bool| -> Option<usize> {
        let idx = t.source().index();
        if let Some(&i) = tex_map.get(&(idx, srgb)) {
            return Some(i);
        }
        match images.get(idx).map(to_rgba) {
            Some(Ok(image)) => {
                scene.textures.push(Texture {
                    name: t.source().name().unwrap_or("texture").into(),
                    image,
                    srgb,
                    source: None,
                });
                tex_map.insert((idx, srgb), scene.textures.len() - 1);
                Some(scene.textures.len() - 1)
            }
            _ => {
                log::warn!("{file}: image {idx} unusable; using the flat material colour");
                None
            }
        }
    };
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let bc = Vec3::from_slice(&pbr.base_color_factor()[..3]);
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
                    ..Material::color("", bc)
                }
            }
        };
        mat.name = m.name().unwrap_or("material").into();
        mat.alpha = pbr.base_color_factor()[3];
        mat.diffuse_texture = pbr
            .base_color_texture()
            .and_then(|t| texture(&mut scene, t.texture(), true));
        mat.normal_map = m
            .normal_texture()
            .and_then(|t| texture(&mut scene, t.texture(), false));
        scene.add_material(mat);
    }
    let default_mat = scene.add_material(Material::default());
    let mut mesh_ids = std::collections::HashMap::new();
    let mut camera = None;
    let gscene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| anyhow!("{file}: no scene"))?;
    // Breadth-first in document order, so objects keep the node order.
    let mut queue: std::collections::VecDeque<(gltf::Node, Mat4)> =
        gscene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = queue.pop_front() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let name = node.name().unwrap_or("node").to_string();
        for c in node.children() {
            queue.push_back((c, world));
        }
        let (_, rot, pos) = world.to_scale_rotation_translation();
        let forward = (rot * Vec3::NEG_Z).normalize();
        if let Some(l) = node.light() {
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
            scene.lights.push(light);
        }
        if let (Some(c), None) = (node.camera(), camera)
            && let gltf::camera::Projection::Perspective(p) = c.projection()
        {
            camera = Some(Camera {
                eye: pos,
                target: pos + forward,
                up: rot * Vec3::Y,
                fov_y_deg: p.yfov().to_degrees(),
                near: p.znear(),
                far: p.zfar().unwrap_or(p.znear() * 1e4),
            });
        }
        let Some(gmesh) = node.mesh() else { continue };
        let flags: ShadowFlags =
            extras_field(node.extras(), &format!("{file}: node '{name}'"))?.unwrap_or_default();
        for (pi, prim) in gmesh.primitives().enumerate() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                log::warn!(
                    "{file}: mesh '{}' primitive {pi} is not triangles; skipped",
                    gmesh.name().unwrap_or("")
                );
                continue;
            }
            let key = (gmesh.index(), pi);
            let mesh_id = match mesh_ids.get(&key) {
                Some(&id) => id,
                None => {
                    check_primitive_accessors(&file, gmesh.name().unwrap_or(&name), pi, &prim)?;
                    let reader = prim.reader(|b| Some(&buffers[b.index()]));
                    let positions: Vec<Vec3> = reader
                        .read_positions()
                        .ok_or_else(|| {
                            anyhow!(
                                "{file}: mesh '{}' has no POSITION",
                                gmesh.name().unwrap_or("")
                            )
                        })?
                        .map(Vec3::from)
                        .collect();
                    let indices: Vec<u32> = match reader.read_indices() {
                        Some(i) => i.into_u32().collect(),
                        None => (0..positions.len() as u32).collect(),
                    };
                    let mesh = Mesh {
                        name: gmesh.name().unwrap_or(&name).to_string(),
                        normals: reader
                            .read_normals()
                            .map(|n| n.map(Vec3::from).collect())
                            .unwrap_or_default(),
                        uvs: reader
                            .read_tex_coords(0)
                            .map(|t| t.into_f32().map(Vec2::from).collect())
                            .unwrap_or_default(),
                        positions,
                        tangents: vec![],
                        indices,
                    };
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
    if !had_lights {
        log::warn!("{file}: no KHR_lights_punctual light; placed a default point light");
    }
    Ok(scene)
}

/// Rotation taking −Z to `dir` (glTF lights and cameras look down −Z).
fn rotation_towards(dir: Vec3, up: Vec3) -> Quat {
    let view = glam::camera::rh::view::look_to_mat4(Vec3::ZERO, dir, up);
    let (_, r, _) = view.inverse().to_scale_rotation_translation();
    r.normalize()
}

fn safe_up(dir: Vec3) -> Vec3 {
    if dir.normalize().dot(Vec3::Y).abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// Binary buffer under construction; every view is 4-byte aligned.
struct BinWriter {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl BinWriter {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        ty: &str,
        comp: u32,
        target: u32,
        minmax: Option<(Vec3, Vec3)>,
    ) -> usize {
        let view = self.view(bytes, Some(target));
        let mut a = json!({"bufferView": view, "componentType": comp, "count": count, "type": ty});
        if let Some((mn, mx)) = minmax {
            a["min"] = json!(mn.to_array());
            a["max"] = json!(mx.to_array());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }
}

/// Writes the scene as `.gltf` JSON plus a `.bin` buffer beside it: vertices
/// in world space (identity node transforms), Phong parameters and shadow
/// flags in `extras.shadowlab`, lights via KHR_lights_punctual and the
/// camera as a perspective camera node.
pub fn export(scene: &Scene, out: &Path) -> Result<()> {
    let bin_name = format!(
        "{}.bin",
        out.file_stem()
            .and_then(|s| s.to_str())
            .ok_or_else(|| anyhow!("bad output name"))?
    );
    let mut w = BinWriter {
        bin: vec![],
        views: vec![],
        accessors: vec![],
    };
    const FLOAT: u32 = 5126;
    const UINT: u32 = 5125;
    const ARRAY: u32 = 34962;
    const ELEMENTS: u32 = 34963;
    let mut images = vec![];
    let mut textures = vec![];
    for t in &scene.textures {
        let mut png = std::io::Cursor::new(Vec::new());
        t.image.write_to(&mut png, image::ImageFormat::Png)?;
        let view = w.view(png.get_ref(), None);
        images.push(json!({"bufferView": view, "mimeType": "image/png", "name": t.name}));
        textures.push(json!({"source": images.len() - 1, "sampler": 0}));
    }
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| {
            let r = (2.0 / (m.shininess + 2.0)).sqrt();
            let mut pbr = json!({
                "baseColorFactor": [m.kd.x.clamp(0.0, 1.0), m.kd.y.clamp(0.0, 1.0), m.kd.z.clamp(0.0, 1.0), m.alpha.clamp(0.0, 1.0)],
                "metallicFactor": 0.0,
                "roughnessFactor": r.clamp(0.0, 1.0),
            });
            if let Some(t) = m.diffuse_texture {
                pbr["baseColorTexture"] = json!({"index": t});
            }
            let mut v = json!({
                "name": m.name,
                "pbrMetallicRoughness": pbr,
                "extras": {"shadowlab": PhongExtras {
                    ka: m.ka.into(), kd: m.kd.into(), ks: m.ks.into(),
                    shininess: m.shininess, uv_scale: m.uv_scale, procedural: m.procedural,
                }},
            });
            if let Some(t) = m.normal_map {
                v["normalTexture"] = json!({"index": t});
            }
            v
        })
        .collect();
    let mut meshes = vec![];
    let mut nodes = vec![];
    for o in &scene.objects {
        let m = &scene.meshes[o.mesh];
        let nm = o.transform.inverse().transpose();
        let pos: Vec<Vec3> = m
            .positions
            .iter()
            .map(|&p| o.transform.transform_point3(p))
            .collect();
        let nrm: Vec<Vec3> = m
            .normals
            .iter()
            .map(|&n| nm.transform_vector3(n).try_normalize().unwrap_or(Vec3::Y))
            .collect();
        let b = super::Aabb::from_points(pos.iter().copied());
        let pa = w.accessor(
            bytemuck::cast_slice(&pos),
            pos.len(),
            "VEC3",
            FLOAT,
            ARRAY,
            Some((b.min, b.max)),
        );
        let na = w.accessor(
            bytemuck::cast_slice(&nrm),
            nrm.len(),
            "VEC3",
            FLOAT,
            ARRAY,
            None,
        );
        let ta = w.accessor(
            bytemuck::cast_slice(&m.uvs),
            m.uvs.len(),
            "VEC2",
            FLOAT,
            ARRAY,
            None,
        );
        let ia = w.accessor(
            bytemuck::cast_slice(&m.indices),
            m.indices.len(),
            "SCALAR",
            UINT,
            ELEMENTS,
            None,
        );
        let mut attributes = json!({"POSITION": pa, "NORMAL": na, "TEXCOORD_0": ta});
        // Normal-mapped materials get their tangent space (xyz unit, w ±1).
        if scene.materials[o.material].normal_map.is_some() && m.tangents.len() == m.positions.len()
        {
            let tangents: Vec<glam::Vec4> = m
                .tangents
                .iter()
                .map(|t| {
                    let v = o
                        .transform
                        .transform_vector3(t.truncate())
                        .try_normalize()
                        .unwrap_or(Vec3::X);
                    v.extend(if t.w < 0.0 { -1.0 } else { 1.0 })
                })
                .collect();
            attributes["TANGENT"] = json!(w.accessor(
                bytemuck::cast_slice(&tangents),
                tangents.len(),
                "VEC4",
                FLOAT,
                ARRAY,
                None
            ));
        }
        meshes.push(json!({
            "name": m.name,
            "primitives": [{
                "attributes": attributes,
                "indices": ia,
                "material": o.material,
                "mode": 4,
            }],
        }));
        nodes.push(json!({
            "name": o.name,
            "mesh": meshes.len() - 1,
            "extras": {"shadowlab": ShadowFlags {
                casts_shadow: Some(o.casts_shadow),
                receives_shadow: Some(o.receives_shadow),
                shadow_plane: Some(o.shadow_plane),
            }},
        }));
    }
    let mut lights = vec![];
    for (i, l) in scene.lights.iter().enumerate() {
        let mut lj = json!({
            "name": format!("light{i}"),
            "type": match l.kind { LightType::Point => "point", LightType::Spot => "spot", LightType::Directional => "directional" },
            "color": l.color.to_array(),
            "intensity": l.intensity,
        });
        if l.range > 0.0 && l.kind != LightType::Directional {
            lj["range"] = json!(l.range);
        }
        if l.kind == LightType::Spot {
            lj["spot"] = json!({
                "innerConeAngle": l.inner_cone_deg.to_radians(),
                "outerConeAngle": l.outer_cone_deg.to_radians(),
            });
        }
        if let Some(a) = l.area {
            lj["extras"] = json!({"shadowlab": a});
        }
        lights.push(lj);
        let rot = rotation_towards(l.direction, safe_up(l.direction));
        nodes.push(json!({
            "name": format!("Light{i}"),
            "translation": l.position.to_array(),
            "rotation": rot.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": i}},
        }));
    }
    let c = &scene.camera;
    let (_, crot, _) = c.view().inverse().to_scale_rotation_translation();
    nodes.push(json!({
        "name": "Camera",
        "translation": c.eye.to_array(),
        "rotation": crot.normalize().to_array(),
        "camera": 0,
    }));
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("shadowlab ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": c.fov_y_deg.to_radians(), "znear": c.near, "zfar": c.far}}],
        "accessors": w.accessors,
        "bufferViews": w.views,
        "buffers": [{"uri": bin_name, "byteLength": w.bin.len()}],
    });
    if !images.is_empty() {
        doc["images"] = json!(images);
        doc["textures"] = json!(textures);
        doc["samplers"] =
            json!([{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}]);
    }
    if !lights.is_empty() {
        doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        doc["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(out, serde_json::to_string_pretty(&doc)?)
        .with_context(|| format!("writing {}", out.display()))?;
    let bin_path = out.with_file_name(&bin_name);
    std::fs::write(&bin_path, &w.bin).with_context(|| format!("writing {}", bin_path.display()))?;
    Ok(())
}
