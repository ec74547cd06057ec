//! Wavefront OBJ + MTL loading through `tobj`, with a line-checking pass
//! first so that malformed files are reported with file and line, and with
//! the [000] §5 conventions: `…NS` objects cast no shadow, `ShadowPlane…`
//! objects are shadow planes, `s off` objects are flat-shaded.

use super::{
    AlphaMode, Material, Mesh, Object, Scene, Texture, TextureWrap, frame_scene_defaults, mtl_map,
};
use anyhow::{Context, Result, anyhow, bail};
use glam::{Mat4, Vec2, Vec3};
use std::collections::HashMap;
use std::io::BufReader;
use std::path::Path;

/// What the checking pass learned: per object name, whether smoothing was
/// off at its first face.
#[derive(Debug, Default)]
pub struct ObjInfo {
    pub flat_objects: Vec<String>,
}

fn parse_floats(words: &[&str], min: usize, max: usize) -> Option<Vec<f32>> {
    if words.len() < min || words.len() > max {
        return None;
    }
    let v: Option<Vec<f32>> = words.iter().map(|w| w.parse::<f32>().ok()).collect();
    v.filter(|v| v.iter().all(|x| x.is_finite()))
}

/// Checks every line of an OBJ text: vertex records must hold finite
/// numbers, faces at least three corners in one of the four index forms
/// (`v`, `v/vt`, `v//vn`, `v/vt/vn`) that reference existing records.
pub fn check_obj(file: &str, text: &str) -> Result<ObjInfo> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    let total = |k: &str| {
        text.lines()
            .filter(|l| l.split_whitespace().next() == Some(k))
            .count() as i64
    };
    let (tv, tt, tn) = (total("v"), total("vt"), total("vn"));
    let mut info = ObjInfo::default();
    let mut object = String::from("unnamed");
    let mut smooth = true;
    let mut seen_face_in: Vec<String> = vec![];
    for (ln, line) in text.lines().enumerate() {
        let err = |msg: String| anyhow!("{file}:{}: {msg}: '{}'", ln + 1, line.trim());
        let line = line.split('#').next().unwrap_or("");
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&key, args)) = words.split_first() else {
            continue;
        };
        match key {
            "v" => {
                parse_floats(args, 3, 7)
                    .ok_or_else(|| err("vertex needs 3 finite numbers".into()))?;
                nv += 1;
            }
            "vt" => {
                parse_floats(args, 1, 3)
                    .ok_or_else(|| err("texture coordinate needs 1-3 finite numbers".into()))?;
                nt += 1;
            }
            "vn" => {
                parse_floats(args, 3, 3)
                    .ok_or_else(|| err("normal needs 3 finite numbers".into()))?;
                nn += 1;
            }
            "f" => {
                if args.len() < 3 {
                    return Err(err("face needs at least 3 corners".into()));
                }
                let mut form = None;
                for corner in args {
                    let parts: Vec<&str> = corner.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(err(format!("bad face corner '{corner}'")));
                    }
                    let shape = (parts.len(), parts.get(1).is_some_and(|s| !s.is_empty()));
                    if form.is_some_and(|f| f != shape) {
                        return Err(err("face mixes index forms".into()));
                    }
                    form = Some(shape);
                    for (k, p) in parts.iter().enumerate() {
                        if p.is_empty() {
                            continue;
                        }
                        let i: i64 = p.parse().map_err(|_| err(format!("bad index '{p}'")))?;
                        let (so_far, all, what) = [
                            (nv, tv, "vertex"),
                            (nt, tt, "texture coordinate"),
                            (nn, tn, "normal"),
                        ][k];
                        let ok = if i > 0 {
                            i <= all
                        } else {
                            i < 0 && -i <= so_far
                        };
                        if !ok {
                            return Err(err(format!("{what} index {i} out of range")));
                        }
                    }
                }
                if !seen_face_in.contains(&object) {
                    seen_face_in.push(object.clone());
                    if !smooth {
                        info.flat_objects.push(object.clone());
                    }
                }
            }
            "o" | "g" => object = args.join(" "),
            "s" => smooth = !matches!(args.first(), Some(&"off") | Some(&"0")),
            _ => {}
        }
    }
    Ok(info)
}

/// Checks an MTL text: colours need three finite numbers, `Ns` a number in
/// 0–1000, `d` in 0–1.
pub fn check_mtl(file: &str, text: &str) -> Result<()> {
    for (ln, line) in text.lines().enumerate() {
        let err = |msg: &str| anyhow!("{file}:{}: {msg}: '{}'", ln + 1, line.trim());
        let words: Vec<&str> = line
            .split('#')
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect();
        let Some((&key, args)) = words.split_first() else {
            continue;
        };
        match key {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                parse_floats(args, 3, 3).ok_or_else(|| err("colour needs 3 finite numbers"))?;
            }
            "Ns" => {
                let v = parse_floats(args, 1, 1).ok_or_else(|| err("Ns needs one number"))?;
                if !(0.0..=1000.0).contains(&v[0]) {
                    return Err(err("Ns must be within 0-1000"));
                }
            }
            "d" => {
                let v = parse_floats(args, 1, 1).ok_or_else(|| err("d needs one number"))?;
                if !(0.0..=1.0).contains(&v[0]) {
                    return Err(err("d must be within 0-1"));
                }
            }
            _ => {}
        }
    }
    Ok(())
}

const LOAD_OPTIONS: tobj::LoadOptions = tobj::LoadOptions {
    single_index: true,
    triangulate: true,
    ignore_points: true,
    ignore_lines: true,
};

fn to_mesh(name: &str, m: &tobj::Mesh) -> Mesh {
    let v3 = |v: &[f32]| {
        v.chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect::<Vec<_>>()
    };
    Mesh {
        name: name.into(),
        positions: v3(&m.positions),
        normals: v3(&m.normals),
        // `v x y z r g b`, as MeshLab and photogrammetry tools write them.
        colors: v3(&m.vertex_color),
        uvs: m
            .texcoords
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], c[1]))
            .collect(),
        indices: m.indices.clone(),
        ..Default::default()
    }
}

/// Parses an OBJ text (no materials) into a single mesh: used for the
/// meshes shipped in `assets/`.
pub fn parse_single_mesh(name: &str, text: &str) -> Result<Mesh> {
    check_obj(name, text)?;
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &LOAD_OPTIONS, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| anyhow!("{name}: {e}"))?;
    let mut out = Mesh {
        name: name.into(),
        ..Default::default()
    };
    for m in &models {
        out.append(&to_mesh(&m.name, &m.mesh), Mat4::IDENTITY);
    }
    Ok(out)
}

/// Loads a texture named by an MTL statement (options, then the file). A
/// statement that cannot be parsed, or a file that is missing or cannot be
/// decoded (corrupt, truncated, larger than the image decoder's 512 MiB
/// limit) falls back to the flat material colour with a warning naming it.
fn load_texture(
    dir: &Path,
    statement: &str,
    srgb: bool,
    scene: &mut Scene,
) -> Result<Option<usize>> {
    let map = match mtl_map::parse(statement) {
        Ok(map) => map,
        Err(e) => {
            log::warn!("texture '{statement}': {e}; using the flat material colour");
            return Ok(None);
        }
    };
    let file = map.file;
    if !map.ignored.is_empty() {
        log::warn!(
            "texture {file}: MTL option(s) {} not applied (read as without them)",
            map.ignored.join(", ")
        );
    }
    let path = dir.join(file.replace('\\', "/"));
    if !path.is_file() {
        log::warn!(
            "texture {}: not found; using the flat material colour",
            path.display()
        );
        return Ok(None);
    }
    let decoded = image::ImageReader::open(&path)
        .and_then(|r| r.with_guessed_format())
        .map_err(anyhow::Error::from)
        .and_then(|r| r.decode().map_err(anyhow::Error::from));
    let img = match decoded {
        Ok(img) => img,
        Err(e) => {
            log::warn!(
                "texture {}: cannot decode ({e}); using the flat material colour",
                path.display()
            );
            return Ok(None);
        }
    };
    scene.textures.push(Texture {
        name: file.to_string(),
        image: img.to_rgba8(),
        srgb,
        source: Some(path),
        wrap: [if map.clamp {
            TextureWrap::ClampToEdge
        } else {
            TextureWrap::Repeat
        }; 2],
    });
    Ok(Some(scene.textures.len() - 1))
}

fn to_material(dir: &Path, m: &tobj::Material, scene: &mut Scene) -> Result<Material> {
    let v = |c: Option<[f32; 3]>, d: Vec3| c.map(Vec3::from).unwrap_or(d);
    let base = Material::default();
    let kd = v(m.diffuse, base.kd);
    let texture = |f: &Option<String>, srgb, scene: &mut Scene| match f.as_deref() {
        Some(f) => load_texture(dir, f, srgb, scene),
        None => Ok(None),
    };
    let alpha = m.dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
    let alpha_texture = texture(&m.dissolve_texture, false, scene)?;
    if let Some(t) = alpha_texture {
        scene.textures[t].opacity_in_alpha();
    }
    // MTL has no alpha mode: a `map_d` is a cut-out (foliage, fences), a
    // bare `d` below 1 a translucent surface.
    let alpha_mode = match (alpha_texture, alpha < 1.0) {
        (Some(_), _) => AlphaMode::Mask,
        (None, true) => AlphaMode::Blend,
        (None, false) => AlphaMode::Opaque,
    };
    Ok(Material {
        name: m.name.clone(),
        ka: v(m.ambient, kd),
        kd,
        ks: v(m.specular, base.ks),
        shininess: m.shininess.unwrap_or(base.shininess).clamp(0.0, 1000.0),
        alpha,
        alpha_mode,
        alpha_texture,
        diffuse_texture: texture(&m.diffuse_texture, true, scene)?,
        normal_map: texture(&m.normal_texture, false, scene)?,
        ..base
    })
}

/// Loads an OBJ file (and its MTL libraries) as a scene: one object per OBJ
/// object/group and material, named after the OBJ object so the naming
/// conventions apply. A default camera and point light frame the model.
pub fn load_scene(path: &Path) -> Result<Scene> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {file}"))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("obj");
    load_text(&file, &text, dir, stem)
}

/// Loads an OBJ file's `text` (a file opened in the browser page), its
/// MTL libraries and textures looked for under `dir`.
pub fn load_text(file: &str, text: &str, dir: &Path, stem: &str) -> Result<Scene> {
    let file = file.to_string();
    let info = check_obj(&file, text)?;
    let dir = dir.to_path_buf();
    let (models, materials) =
        tobj::load_obj_buf(&mut BufReader::new(text.as_bytes()), &LOAD_OPTIONS, |p| {
            let mtl_path = dir.join(p);
            // Not a FIFO or a device, which would never end.
            if !mtl_path.is_file() {
                return Err(tobj::LoadError::OpenFileFailed);
            }
            let mtl_text =
                std::fs::read_to_string(&mtl_path).map_err(|_| tobj::LoadError::OpenFileFailed)?;
            if let Err(e) = check_mtl(&mtl_path.display().to_string(), &mtl_text) {
                log::error!("{e}");
                return Err(tobj::LoadError::MaterialParseError);
            }
            tobj::load_mtl_buf(&mut mtl_text.as_bytes())
        })
        .map_err(|e| anyhow!("{file}: {e}"))?;
    let mut scene = Scene::new(stem);
    scene.source = file.clone();
    let materials = match materials {
        Ok(mats) => mats,
        Err(e) => {
            // A malformed MTL is an error; a missing one falls back to grey.
            if e == tobj::LoadError::MaterialParseError {
                let mtl_names: Vec<&str> = text
                    .lines()
                    .filter_map(|l| l.trim().strip_prefix("mtllib "))
                    .collect();
                for name in mtl_names {
                    let p = dir.join(name.trim());
                    if let Ok(t) = std::fs::read_to_string(&p) {
                        check_mtl(&p.display().to_string(), &t)?;
                    }
                }
                bail!("{file}: malformed material library");
            }
            log::warn!("{file}: material library not loaded ({e}); using a grey default");
            vec![]
        }
    };
    let mut mat_index: HashMap<usize, usize> = HashMap::new();
    for (i, m) in materials.iter().enumerate() {
        let mat = to_material(&dir, m, &mut scene).with_context(|| file.clone())?;
        mat_index.insert(i, scene.add_material(mat));
    }
    let default_mat = scene.add_material(Material::default());
    for model in &models {
        let mut mesh = to_mesh(&model.name, &model.mesh);
        if mesh.indices.is_empty() {
            continue;
        }
        if info.flat_objects.contains(&model.name) && model.mesh.normals.is_empty() {
            mesh.unweld_flat();
        }
        let mat = model
            .mesh
            .material_id
            .and_then(|id| mat_index.get(&id).copied())
            .unwrap_or(default_mat);
        let mesh_id = scene.add_mesh(mesh);
        scene
            .objects
            .push(Object::from_name(&model.name, mesh_id, mat, Mat4::IDENTITY));
    }
    if scene.objects.is_empty() {
        bail!("{file}: no faces");
    }
    frame_scene_defaults(&mut scene);
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_four_face_index_forms_are_accepted() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                    f 1 2 3\nf 1/1 2/2 3/3\nf 1//1 2//1 3//1\nf 1/1/1 2/2/1 3/3/1\nf -3 -2 -1\n";
        check_obj("t.obj", text).unwrap();
        let m = parse_single_mesh("t", text).unwrap();
        assert_eq!(m.triangle_count(), 5);
    }

    #[test]
    fn malformed_lines_name_file_and_line() {
        let e = check_obj("bad.obj", "v 0 0 0\nv 1 0 nan_x\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("bad.obj:2:"), "{e}");
        let e = check_obj("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.obj:4:") && e.contains("vertex index 4"),
            "{e}"
        );
        let e = check_obj("bad.obj", "v 0 0 0\nf 1 1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains(":2:"), "{e}");
        let e = check_obj("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("mixes"), "{e}");
        let e = check_mtl("m.mtl", "newmtl a\nKd 1 0\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("m.mtl:2:"), "{e}");
        let e = check_mtl("m.mtl", "newmtl a\nNs 5000\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("0-1000"), "{e}");
    }

    #[test]
    fn smoothing_off_is_recorded_per_object() {
        let info = check_obj(
            "s.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\no A\ns off\nf 1 2 3\no B\ns 1\nf 1 2 3\n",
        )
        .unwrap();
        assert_eq!(info.flat_objects, vec!["A".to_string()]);
    }
}
