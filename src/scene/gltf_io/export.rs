//! A resolved scene written as glTF 2.0: world-space vertices, Phong
//! parameters and shadow flags in `extras.shadowlab`, KHR_lights_punctual
//! lights and the camera.

use super::extras::{PhongExtras, ShadowFlags};
use crate::scene::{Aabb, AlphaMode, Light, LightType, Material, Object, Scene, TextureWrap};
use anyhow::{Context, Result, anyhow};
use glam::{Quat, Vec3};
use serde_json::{Value, json};
use std::path::Path;

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

/// glTF component types and buffer-view targets.
const FLOAT: u32 = 5126;
const UINT: u32 = 5125;
const ARRAY: u32 = 34962;
const ELEMENTS: u32 = 34963;

/// Material `m` as glTF: base colour and roughness from the Phong terms,
/// which the shadowlab extras keep exactly; alpha mode, cutoff and sides.
fn material_json(m: &Material) -> Value {
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
    if m.alpha_mode != AlphaMode::Opaque {
        v["alphaMode"] = json!(m.alpha_mode.gltf_name());
    }
    if m.alpha_mode == AlphaMode::Mask {
        v["alphaCutoff"] = json!(m.alpha_cutoff);
    }
    if m.double_sided {
        v["doubleSided"] = json!(true);
    }
    if m.alpha_texture.is_some() && m.alpha_texture != m.diffuse_texture {
        log::warn!(
            "material '{}': glTF keeps opacity in the base colour texture's alpha; its separate opacity map is not written",
            m.name
        );
    }
    v
}

/// Object `o`'s mesh in world space (its transform baked in), single-sided
/// where its material is double-sided, its arrays written to `w`.
fn mesh_json(w: &mut BinWriter, scene: &Scene, o: &Object) -> Value {
    // A double-sided material's back faces are the loader's: glTF says
    // `doubleSided` instead.
    let m = &scene.meshes[o.mesh];
    let single;
    let m = if scene.materials[o.material].double_sided && m.sides_doubled {
        single = m.single_sided();
        &single
    } else {
        m
    };
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
    let b = Aabb::from_points(pos.iter().copied());
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
    if m.colors.len() == m.positions.len() {
        attributes["COLOR_0"] = json!(w.accessor(
            bytemuck::cast_slice(&m.colors),
            m.colors.len(),
            "VEC3",
            FLOAT,
            ARRAY,
            None
        ));
    }
    // Normal-mapped materials get their tangent space (xyz unit, w ±1).
    if scene.materials[o.material].normal_map.is_some() && m.tangents.len() == m.positions.len() {
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
    json!({
        "name": m.name,
        "primitives": [{
            "attributes": attributes,
            "indices": ia,
            "material": o.material,
            "mode": 4,
        }],
    })
}

/// Light `l` (number `i`) as a KHR_lights_punctual light.
fn light_json(l: &Light, i: usize) -> Value {
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
    lj
}

/// Writes the scene as `.gltf` JSON plus a `.bin` buffer beside it, or as
/// one binary `.glb` when `out` ends in `.glb`: vertices
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
    let mut images = vec![];
    let mut textures = vec![];
    // One sampler per pair of wrap modes the textures use, trilinear.
    let mut samplers: Vec<[TextureWrap; 2]> = vec![];
    for t in &scene.textures {
        let mut png = std::io::Cursor::new(Vec::new());
        t.image.write_to(&mut png, image::ImageFormat::Png)?;
        let view = w.view(png.get_ref(), None);
        images.push(json!({"bufferView": view, "mimeType": "image/png", "name": t.name}));
        let sampler = samplers
            .iter()
            .position(|&s| s == t.wrap)
            .unwrap_or_else(|| {
                samplers.push(t.wrap);
                samplers.len() - 1
            });
        textures.push(json!({"source": images.len() - 1, "sampler": sampler}));
    }
    let materials: Vec<Value> = scene.materials.iter().map(material_json).collect();
    let mut meshes = vec![];
    let mut nodes = vec![];
    for o in &scene.objects {
        meshes.push(mesh_json(&mut w, scene, o));
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
        lights.push(light_json(l, i));
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
    });
    if !images.is_empty() {
        doc["images"] = json!(images);
        doc["textures"] = json!(textures);
        doc["samplers"] = samplers
            .iter()
            .map(|[s, t]| {
                json!({"magFilter": 9729, "minFilter": 9987,
                    "wrapS": s.gl_constant(), "wrapT": t.gl_constant()})
            })
            .collect();
    }
    if !lights.is_empty() {
        doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        doc["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
    }
    write_files(out, doc, &bin_name, &w.bin)
}

/// Writes `doc` and its buffer `bin`: one binary `.glb` (JSON and BIN
/// chunks, glTF 2.0 §4.4) when `out` ends in `.glb`, else `.gltf` JSON with
/// the buffer beside it as `bin_name`.
fn write_files(out: &Path, mut doc: Value, bin_name: &str, bin: &[u8]) -> Result<()> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let glb = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if !glb {
        doc["buffers"] = json!([{"uri": bin_name, "byteLength": bin.len()}]);
        std::fs::write(out, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", out.display()))?;
        let bin_path = out.with_file_name(bin_name);
        return std::fs::write(&bin_path, bin)
            .with_context(|| format!("writing {}", bin_path.display()));
    }
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    let mut json = serde_json::to_vec(&doc)?;
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let total = u32::try_from(total).map_err(|_| anyhow!("{}: over 4 GiB", out.display()))?;
    let mut file = Vec::with_capacity(total as usize);
    file.extend_from_slice(b"glTF");
    file.extend_from_slice(&2u32.to_le_bytes());
    file.extend_from_slice(&total.to_le_bytes());
    for (chunk, kind) in [(&json, b"JSON"), (&bin, b"BIN\0")] {
        file.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
        file.extend_from_slice(kind);
        file.extend_from_slice(chunk);
    }
    std::fs::write(out, file).with_context(|| format!("writing {}", out.display()))
}
