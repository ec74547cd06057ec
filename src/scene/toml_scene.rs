//! TOML scene files: models (OBJ/glTF files or built-in shapes) placed with
//! a transform and per-object shadow flags, lights and a camera.
//!
//! ```toml
//! name = "demo"
//! background = [0.05, 0.06, 0.08]
//! [[model]]
//! shape = "plane"          # plane | box | sphere | torus, or path = "x.obj"
//! size = [10.0, 10.0]
//! receives_shadow = true
//! [[model]]
//! shape = "plane"
//! alpha_mode = "blend"     # opaque | mask | blend (glTF alphaMode)
//! alpha = 0.3              # opacity factor; alpha_cutoff for mask
//! double_sided = true
//! [[model]]
//! path = "chair.obj"
//! translate = [0.0, 0.0, -1.0]
//! rotate_deg = [0.0, 30.0, 0.0]
//! scale = 0.5
//! [[light]]
//! type = "spot"
//! position = [3.0, 5.0, 3.0]
//! direction = [-0.5, -1.0, -0.5]
//! [camera]
//! eye = [0.0, 4.0, 10.0]
//! target = [0.0, 1.0, 0.0]
//! ```

use super::{AlphaMode, Camera, Light, LightArea, LightType, Material, Mesh, Scene, shapes};
use anyhow::{Context, Result, anyhow, bail};
use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    background: Option<[f32; 3]>,
    ambient: Option<[f32; 3]>,
    #[serde(default)]
    model: Vec<ModelEntry>,
    #[serde(default)]
    light: Vec<LightEntry>,
    camera: Option<CameraEntry>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Scale {
    Uniform(f32),
    Axes([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelEntry {
    path: Option<String>,
    shape: Option<String>,
    size: Option<Vec<f32>>,
    name: Option<String>,
    color: Option<[f32; 3]>,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default)]
    rotate_deg: [f32; 3],
    scale: Option<Scale>,
    casts_shadow: Option<bool>,
    receives_shadow: Option<bool>,
    shadow_plane: Option<bool>,
    /// Material overrides for every material of the model.
    alpha: Option<f32>,
    alpha_mode: Option<AlphaMode>,
    alpha_cutoff: Option<f32>,
    double_sided: Option<bool>,
}

impl ModelEntry {
    /// Applies the entry's material overrides to `m`.
    fn override_material(&self, m: &mut Material) {
        m.alpha = self.alpha.unwrap_or(m.alpha);
        m.alpha_mode = self.alpha_mode.unwrap_or(m.alpha_mode);
        m.alpha_cutoff = self.alpha_cutoff.unwrap_or(m.alpha_cutoff);
        m.double_sided = self.double_sided.unwrap_or(m.double_sided);
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightEntry {
    #[serde(rename = "type")]
    kind: LightType,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
    color: Option<[f32; 3]>,
    intensity: Option<f32>,
    range: Option<f32>,
    inner_cone_deg: Option<f32>,
    outer_cone_deg: Option<f32>,
    area_radius: Option<f32>,
    area_size: Option<[f32; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraEntry {
    eye: [f32; 3],
    target: [f32; 3],
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    near: Option<f32>,
    far: Option<f32>,
}

fn shape_mesh(shape: &str, size: &[f32]) -> Result<Mesh> {
    if let Some(bad) = size.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        bail!("`size` values must be positive finite numbers, got {bad}");
    }
    let s = |i: usize, d: f32| size.get(i).copied().unwrap_or(d);
    Ok(match shape {
        "plane" => shapes::plane(s(0, 10.0), s(1, s(0, 10.0)), 8),
        "box" => shapes::cuboid(Vec3::new(s(0, 1.0), s(1, s(0, 1.0)), s(2, s(0, 1.0)))),
        "sphere" => shapes::sphere(s(0, 0.5), 48, 24),
        "torus" => shapes::torus(s(0, 0.7), s(1, 0.2), 48, 16),
        _ => bail!("unknown shape '{shape}' (valid: plane, box, sphere, torus)"),
    })
}

/// Adds model `m` of a scene file (`at` names it in errors): a loaded file
/// placed and overridden, or a shape.
fn add_model(
    scene: &mut Scene,
    m: &ModelEntry,
    at: &str,
    dir: &Path,
    includes: &[PathBuf],
) -> Result<()> {
    let ctx = |what: &str| format!("{at}: {what}");
    let scale = match m.scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(s),
        Some(Scale::Axes(a)) => a.into(),
    };
    if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
        bail!(
            "{}",
            ctx(&format!(
                "`scale` must be finite and non-zero on every axis, got {scale} (a zero scale flattens the model)"
            ))
        );
    }
    if !(Vec3::from(m.translate).is_finite() && Vec3::from(m.rotate_deg).is_finite()) {
        bail!("{}", ctx("`translate` and `rotate_deg` must be finite"));
    }
    let r = m.rotate_deg.map(f32::to_radians);
    let placement = Mat4::from_scale_rotation_translation(
        scale,
        Quat::from_euler(EulerRot::XYZ, r[0], r[1], r[2]),
        m.translate.into(),
    );
    let first_object = scene.objects.len();
    match (&m.path, &m.shape) {
        (Some(p), None) => {
            let sub = super::load_file_included(&dir.join(p), includes)
                .with_context(|| ctx("loading model"))?;
            let (mesh_off, mat_off, tex_off) = (
                scene.meshes.len(),
                scene.materials.len(),
                scene.textures.len(),
            );
            scene.textures.extend(sub.textures);
            scene.meshes.extend(sub.meshes);
            for mut mat in sub.materials {
                mat.diffuse_texture = mat.diffuse_texture.map(|t| t + tex_off);
                mat.normal_map = mat.normal_map.map(|t| t + tex_off);
                mat.alpha_texture = mat.alpha_texture.map(|t| t + tex_off);
                m.override_material(&mut mat);
                scene.materials.push(mat);
            }
            for mut o in sub.objects {
                o.mesh += mesh_off;
                o.material += mat_off;
                o.transform = placement * o.transform;
                scene.objects.push(o);
            }
        }
        (None, Some(shape)) => {
            let mesh = shape_mesh(shape, m.size.as_deref().unwrap_or(&[]))
                .with_context(|| ctx("shape"))?;
            let mesh = scene.add_mesh(mesh);
            let colour = m.color.map(Vec3::from).unwrap_or(Vec3::splat(0.8));
            let mut mat = Material::color(shape, colour);
            m.override_material(&mut mat);
            let mat = scene.add_material(mat);
            scene.add_object(m.name.as_deref().unwrap_or(shape), mesh, mat, placement);
        }
        _ => bail!("{}", ctx("needs exactly one of `path` or `shape`")),
    }
    for o in &mut scene.objects[first_object..] {
        if let (Some(n), None) = (&m.name, &m.path) {
            o.name = n.clone();
        }
        o.casts_shadow = m.casts_shadow.unwrap_or(o.casts_shadow);
        o.receives_shadow = m.receives_shadow.unwrap_or(o.receives_shadow);
        o.shadow_plane = m.shadow_plane.unwrap_or(o.shadow_plane);
    }
    Ok(())
}

/// Light `l` of a scene file (`at` names it in errors).
fn light_of(l: &LightEntry, at: &str) -> Result<Light> {
    let need = |v: Option<[f32; 3]>, what: &str| {
        v.map(Vec3::from)
            .ok_or_else(|| anyhow!("{at}: {:?} light needs `{what}`", l.kind))
    };
    let mut light = match l.kind {
        LightType::Point => Light::point(need(l.position, "position")?, 1.0),
        LightType::Spot => {
            let p = need(l.position, "position")?;
            Light::spot(p, p + need(l.direction, "direction")?, 1.0, 25.0, 35.0)
        }
        LightType::Directional => Light::directional(need(l.direction, "direction")?, 1.0),
    };
    light.color = l.color.map(Vec3::from).unwrap_or(light.color);
    light.intensity = l.intensity.unwrap_or(light.intensity);
    light.range = l.range.unwrap_or(0.0);
    light.inner_cone_deg = l.inner_cone_deg.unwrap_or(light.inner_cone_deg);
    light.outer_cone_deg = l.outer_cone_deg.unwrap_or(light.outer_cone_deg);
    light.area = match (l.area_radius, l.area_size) {
        (Some(r), None) => Some(LightArea::Sphere { radius: r }),
        (None, Some([w, h])) => Some(LightArea::Rect {
            width: w,
            height: h,
        }),
        (None, None) => None,
        _ => bail!("{at}: give `area_radius` or `area_size`, not both"),
    };
    light.validate().with_context(|| at.to_string())?;
    Ok(light)
}

/// Loads a TOML scene file; errors name the file and the line/field.
/// `includes` are the scene files that include this one, outermost first
/// (see [`super::load_file_included`]), so that include cycles are errors.
pub fn load(path: &Path, includes: &[PathBuf]) -> Result<Scene> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {file}"))?;
    let f: SceneFile = toml::from_str(&text).map_err(|e| anyhow!("{file}: {e}"))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut scene = Scene::new(
        f.name
            .as_deref()
            .unwrap_or_else(|| path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene")),
    );
    scene.source = file.clone();
    for (field, c) in [("background", f.background), ("ambient", f.ambient)] {
        if c.map(Vec3::from)
            .is_some_and(|c| !c.is_finite() || c.min_element() < 0.0)
        {
            bail!("{file}: `{field}` must be three finite non-negative numbers");
        }
    }
    if let Some(b) = f.background {
        scene.background = b.into();
    }
    if let Some(a) = f.ambient {
        scene.ambient = a.into();
    }
    for (i, m) in f.model.iter().enumerate() {
        add_model(&mut scene, m, &format!("{file}: model[{i}]"), dir, includes)?;
    }
    if scene.objects.is_empty() {
        bail!("{file}: no [[model]] entries");
    }
    for (i, l) in f.light.iter().enumerate() {
        scene
            .lights
            .push(light_of(l, &format!("{file}: light[{i}]"))?);
    }
    let had_lights = !scene.lights.is_empty();
    super::frame_scene_defaults(&mut scene);
    if !had_lights {
        log::info!("{file}: no [[light]]; placed a default point light");
    }
    if let Some(c) = f.camera {
        let camera = Camera {
            eye: c.eye.into(),
            target: c.target.into(),
            up: c.up.map(Vec3::from).unwrap_or(Vec3::Y),
            fov_y_deg: c.fov.unwrap_or(50.0),
            near: c.near.unwrap_or(scene.camera.near),
            far: c.far.unwrap_or(scene.camera.far),
        };
        scene.camera = match c.up {
            Some(_) => camera,
            None => camera.with_usable_up(),
        };
    }
    Ok(scene)
}
