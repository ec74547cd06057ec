//! The viewer's egui panels, generated from the registry and the parameter
//! tables: technique and parameters, lights, scene and camera, rendering
//! settings, statistics, debug overlays and help.

use super::{Overlay, SceneState, ViewerState};
use crate::frame::MAX_LIGHTS;
use crate::gpu::GpuContext;
use crate::measure::flicker::CameraPath;
use crate::renderer::{LightingModel, MipFilter, Shading};
use crate::scene::{Light, LightArea, LightType, builtin};
use crate::technique::TechniqueInstance;
use crate::technique::{self, ParamKind, ParamSpec, ParamValues};
use glam::Vec3;

/// Requests from the panels that the app carries out after the frame.
#[derive(Default)]
pub struct Actions {
    pub heatmap: bool,
    pub switch_scene: Option<String>,
}

/// One widget per parameter, from its table row; returns true on change.
pub fn param_widget(ui: &mut egui::Ui, spec: &ParamSpec, value: &mut f64) -> bool {
    match spec.kind {
        ParamKind::Float => ui
            .add(
                egui::Slider::new(value, spec.min..=spec.max)
                    .step_by(spec.step)
                    .text(spec.name),
            )
            .changed(),
        ParamKind::Int => {
            let mut v = *value as i64;
            let c = ui
                .add(egui::Slider::new(&mut v, spec.min as i64..=spec.max as i64).text(spec.name))
                .changed();
            *value = v as f64;
            c
        }
        ParamKind::Bool => {
            let mut b = *value != 0.0;
            let c = ui.checkbox(&mut b, spec.name).changed();
            *value = b as u32 as f64;
            c
        }
        ParamKind::Choice(options) => {
            let mut i = *value as usize;
            let before = i;
            egui::ComboBox::from_label(spec.name)
                .selected_text(options.get(i).copied().unwrap_or("?"))
                .show_ui(ui, |ui| {
                    for (k, o) in options.iter().enumerate() {
                        ui.selectable_value(&mut i, k, *o);
                    }
                });
            *value = i as f64;
            i != before
        }
    }
}

/// What a parameter panel did this frame.
pub struct PanelResult {
    pub changed: bool,
    /// The parameters shown, one widget each: those that apply.
    pub shown: Vec<&'static str>,
    /// Parameters hidden because they have no effect here.
    pub hidden: usize,
}

/// The parameter panel of a technique instance for a light of `kind`:
/// the parameters that apply to it with the current values (hover for
/// each doc), and a note of how many are hidden.
pub fn param_panel(
    ui: &mut egui::Ui,
    params: &mut ParamValues,
    kind: Option<LightType>,
) -> PanelResult {
    let mut r = PanelResult {
        changed: false,
        shown: vec![],
        hidden: 0,
    };
    if params.specs.is_empty() {
        ui.label("no parameters");
    }
    for i in 0..params.specs.len() {
        let spec = &params.specs[i];
        if !params.applies(spec, kind) {
            r.hidden += 1;
            continue;
        }
        let w = ui.scope(|ui| param_widget(ui, spec, &mut params.values[i]));
        r.changed |= w.inner;
        r.shown.push(spec.name);
        w.response.on_hover_text(spec.doc);
    }
    if r.hidden > 0 {
        ui.weak(format!(
            "{} parameters that do not apply to this light and these settings are hidden",
            r.hidden
        ));
    }
    r
}

fn vec3_edit(ui: &mut egui::Ui, label: &str, v: &mut Vec3, speed: f32) {
    ui.horizontal(|ui| {
        ui.label(label);
        ui.add(egui::DragValue::new(&mut v.x).speed(speed).prefix("x "));
        ui.add(egui::DragValue::new(&mut v.y).speed(speed).prefix("y "));
        ui.add(egui::DragValue::new(&mut v.z).speed(speed).prefix("z "));
    });
}

fn light_panel(ui: &mut egui::Ui, state: &mut ViewerState, scene: &mut SceneState) {
    ui.horizontal(|ui| {
        for i in 0..scene.lights.len() {
            ui.selectable_value(&mut state.selected_light, i, format!("light {i}"));
        }
        if scene.lights.len() < MAX_LIGHTS && ui.button("+").on_hover_text("add a light").clicked()
        {
            let c = scene.scene_gpu.bounds.center();
            let r = scene.scene_gpu.bounds.size().length() * 0.5;
            scene
                .lights
                .push(Light::point(c + Vec3::new(0.3, 1.0, 0.4) * r, 0.6));
            state.selected_light = scene.lights.len() - 1;
        }
        if scene.lights.len() > 1
            && ui
                .button("−")
                .on_hover_text("remove the selected light")
                .clicked()
        {
            scene.lights.remove(state.selected_light);
            state.selected_light = state.selected_light.min(scene.lights.len() - 1);
        }
    });
    let Some(l) = scene.lights.get_mut(state.selected_light) else {
        ui.label("no light");
        return;
    };
    egui::ComboBox::from_label("type")
        .selected_text(format!("{:?}", l.kind).to_lowercase())
        .show_ui(ui, |ui| {
            for k in [LightType::Point, LightType::Spot, LightType::Directional] {
                ui.selectable_value(&mut l.kind, k, format!("{k:?}").to_lowercase());
            }
        });
    let speed = (scene.scene_gpu.bounds.size().length() * 0.005).max(0.001);
    if l.kind != LightType::Directional {
        vec3_edit(ui, "position", &mut l.position, speed);
    }
    if l.kind != LightType::Point {
        let mut d = l.direction;
        vec3_edit(ui, "direction", &mut d, 0.01);
        if d.length_squared() > 1e-6 {
            l.direction = d.normalize();
        }
    }
    let mut c = l.color.to_array();
    ui.horizontal(|ui| {
        ui.label("colour");
        ui.color_edit_button_rgb(&mut c);
    });
    l.color = Vec3::from(c);
    ui.add(egui::Slider::new(&mut l.intensity, 0.0..=4.0).text("intensity"));
    // A directional light has no position, so no range to fall off over.
    if l.kind != LightType::Directional {
        ui.add(egui::Slider::new(&mut l.range, 0.0..=100.0).text("range (0 = none)"));
    }
    if l.kind == LightType::Spot {
        ui.add(egui::Slider::new(&mut l.outer_cone_deg, 1.0..=89.0).text("outer cone°"));
        ui.add(
            egui::Slider::new(&mut l.inner_cone_deg, 0.0..=l.outer_cone_deg).text("inner cone°"),
        );
    }
    let mut area = match l.area {
        None => 0.0,
        Some(LightArea::Sphere { radius }) => radius,
        Some(LightArea::Rect { width, .. }) => width,
    };
    ui.add(egui::Slider::new(&mut area, 0.0..=2.0).text("area size (0 = hard)"))
        .on_hover_text("sphere radius (point, spot) or tangent of the half-angle (directional): soft shadows where the technique supports them");
    l.area = (area > 0.0).then_some(LightArea::Sphere { radius: area });
}

fn technique_panel(
    ui: &mut egui::Ui,
    state: &mut ViewerState,
    scene: &mut SceneState,
    gpu: &GpuContext,
) {
    ui.checkbox(
        &mut state.same_technique_for_all,
        "same technique for every light",
    );
    let li = state.selected_light.min(MAX_LIGHTS - 1);
    let current = scene.techniques[li].choice.id();
    let mut chosen = current.clone();
    egui::ComboBox::from_label("technique")
        .selected_text(&chosen)
        .show_ui(ui, |ui| {
            for id in technique::preset_ids() {
                let summary = technique::resolve(&id)
                    .map(|c| c.family.summary)
                    .unwrap_or("");
                ui.selectable_value(&mut chosen, id.clone(), id)
                    .on_hover_text(summary);
            }
        });
    if chosen != current {
        match technique::resolve(&chosen).and_then(|c| TechniqueInstance::new(gpu, c)) {
            Ok(_) => {
                let range = if state.same_technique_for_all {
                    0..MAX_LIGHTS
                } else {
                    li..li + 1
                };
                for i in range {
                    if let Ok(inst) =
                        technique::resolve(&chosen).and_then(|c| TechniqueInstance::new(gpu, c))
                    {
                        scene.techniques[i] = inst;
                    }
                }
            }
            Err(e) => state.error = Some(format!("{e:#}")),
        }
    }
    ui.label(scene.techniques[li].choice.family.summary);
    let mut params = scene.techniques[li].choice.params.clone();
    let kind = scene.lights.get(li).map(|l| l.kind);
    if param_panel(ui, &mut params, kind).changed {
        let range = if state.same_technique_for_all {
            0..MAX_LIGHTS
        } else {
            li..li + 1
        };
        for i in range {
            if scene.techniques[i].choice.family.id == scene.techniques[li].choice.family.id
                && let Err(e) = scene.techniques[i].set_params(params.clone())
            {
                state.error = Some(format!("{e:#}"));
            }
        }
    }
}

fn scene_panel(
    ui: &mut egui::Ui,
    state: &mut ViewerState,
    scene: &mut SceneState,
    actions: &mut Actions,
) {
    let mut name = state.scene_name.clone();
    egui::ComboBox::from_label("scene")
        .selected_text(&name)
        .show_ui(ui, |ui| {
            for n in builtin::NAMES {
                ui.selectable_value(&mut name, n.to_string(), *n);
            }
        });
    if name != state.scene_name {
        actions.switch_scene = Some(name);
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("camera:");
        for (n, c) in &scene.scene.camera_presets {
            if ui.button(n).clicked() {
                scene.camera = *c;
            }
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("lights:");
        for (n, l) in &scene.scene.light_presets {
            if ui.button(n).clicked() {
                scene.lights = l.clone();
                state.selected_light = 0;
            }
        }
    });
    ui.add(egui::Slider::new(&mut scene.camera.fov_y_deg, 10.0..=120.0).text("fov°"));
    ui.horizontal(|ui| {
        ui.label("camera path")
            .on_hover_text("move the camera one small step per frame (the steps of `compare --path`) to watch shadows shimmer or stay put");
        let label = |p: Option<CameraPath>| p.map_or("off".to_string(), |p| format!("{p:?}").to_lowercase());
        egui::ComboBox::from_id_salt("camera path")
            .selected_text(label(state.camera_path))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut state.camera_path, None, "off");
                for p in [CameraPath::Dolly, CameraPath::Strafe, CameraPath::Turn, CameraPath::Orbit] {
                    ui.selectable_value(&mut state.camera_path, Some(p), label(Some(p)));
                }
            });
    });
    let mut bg = state
        .settings
        .background
        .unwrap_or(scene.scene.background)
        .to_array();
    ui.horizontal(|ui| {
        ui.label("background");
        ui.color_edit_button_rgb(&mut bg);
    });
    state.settings.background = Some(Vec3::from(bg));
}

fn render_panel(ui: &mut egui::Ui, state: &mut ViewerState) {
    egui::ComboBox::from_label("shading")
        .selected_text(format!("{:?}", state.settings.shading).to_lowercase())
        .show_ui(ui, |ui| {
            for s in [Shading::Flat, Shading::Gouraud, Shading::Pixel] {
                ui.selectable_value(
                    &mut state.settings.shading,
                    s,
                    format!("{s:?}").to_lowercase(),
                );
            }
        });
    egui::ComboBox::from_label("specular")
        .selected_text(format!("{:?}", state.settings.lighting))
        .show_ui(ui, |ui| {
            for s in [LightingModel::Phong, LightingModel::BlinnPhong] {
                ui.selectable_value(&mut state.settings.lighting, s, format!("{s:?}"));
            }
        });
    // Texture filtering: the device's default until the slider moves.
    let mut anisotropy = state
        .settings
        .anisotropy
        .unwrap_or(state.default_anisotropy);
    if ui
        .add(egui::Slider::new(&mut anisotropy, 1..=16).text("texture anisotropy"))
        .on_hover_text(
            "anisotropic filtering of material textures (1 = trilinear); costly on CPU adapters",
        )
        .changed()
    {
        state.settings.anisotropy = Some(anisotropy);
    }
    // Anisotropic filtering needs linear mip blending: the choice applies at 1.
    let mut mip_filter = state
        .settings
        .mip_filter
        .unwrap_or(state.default_mip_filter);
    ui.add_enabled_ui(anisotropy == 1, |ui| {
        egui::ComboBox::from_label("mip filter")
            .selected_text(format!("{mip_filter:?}"))
            .show_ui(ui, |ui| {
                for m in [MipFilter::Nearest, MipFilter::Linear] {
                    if ui
                        .selectable_value(&mut mip_filter, m, format!("{m:?}"))
                        .changed()
                    {
                        state.settings.mip_filter = Some(mip_filter);
                    }
                }
            })
            .response
            .on_hover_text("blending between mip levels of material textures (linear = trilinear)");
    });
    ui.checkbox(&mut state.settings.cull_back_faces, "back-face culling");
    ui.checkbox(&mut state.settings.show_light_icons, "light icons");
    ui.checkbox(&mut state.vsync, "vsync");
    ui.horizontal(|ui| {
        ui.label("antialiasing");
        ui.selectable_value(&mut state.supersampling, 1, "off");
        ui.selectable_value(&mut state.supersampling, 2, "2×2 SSAA");
    })
    .response
    .on_hover_text("supersampling: the frame is rendered at twice the window size and filtered down (the mask architecture works per pixel, so this replaces MSAA)");
}

/// How often the statistics' text changes: readable, and the panels stay
/// the same between changes (their layer is then not drawn again).
const STATS_REFRESH: std::time::Duration = std::time::Duration::from_millis(250);

fn stats_panel(ui: &mut egui::Ui, state: &mut ViewerState, scene: &SceneState) {
    if state
        .stats_at
        .is_none_or(|at| at.elapsed() >= STATS_REFRESH)
    {
        state.stats_lines = stats_lines(state, scene);
        state.stats_at = Some(std::time::Instant::now());
    }
    for line in &state.stats_lines {
        ui.label(line);
    }
}

fn stats_lines(state: &ViewerState, scene: &SceneState) -> Vec<String> {
    let n = state.frame_times.len().max(1) as f64;
    let mean = state.frame_times.iter().sum::<f64>() / n;
    let mut lines = vec![format!(
        "{:.1} FPS, frame {:.1} ms (mean of {} frames)",
        1000.0 / mean.max(1e-3),
        mean,
        state.frame_times.len()
    )];
    if let Some(t) = &state.last_timings {
        lines.push(format!(
            "wall: prepass {:.1}, masks {:.1}, lighting {:.1} ms",
            t.prepass_ms, t.masks_ms, t.lighting_ms
        ));
        if let Some(g) = &t.gpu {
            lines.push(format!(
                "GPU: prepass {:.2}, masks {:.2}, lighting {:.2} ms",
                g.prepass_ms, g.masks_ms, g.lighting_ms
            ));
        }
    }
    lines.push(format!(
        "triangles: {} drawn, {} casters",
        scene.scene_gpu.triangle_count, scene.scene_gpu.caster_triangle_count
    ));
    for (i, t) in scene.techniques.iter().take(scene.lights.len()).enumerate() {
        let c: Vec<String> = t
            .technique
            .counters()
            .iter()
            .map(|(k, v)| format!("{k} {v:.0}"))
            .collect();
        if !c.is_empty() {
            lines.push(format!("light {i}: {}", c.join(", ")));
        }
    }
    lines
}

fn debug_panel(
    ui: &mut egui::Ui,
    state: &mut ViewerState,
    scene: &SceneState,
    actions: &mut Actions,
) {
    ui.horizontal(|ui| {
        ui.selectable_value(&mut state.overlay, Overlay::Image, "image");
        for i in 0..scene.lights.len() {
            ui.selectable_value(&mut state.overlay, Overlay::Mask(i), format!("mask {i}"));
        }
    });
    ui.checkbox(&mut state.show_debug, "technique debug views")
        .on_hover_text("what the selected light's technique offers: light frusta as lines, its depth map, volumes and silhouettes");
    if state.heatmap_job.is_some() {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label("ray tracing the reference…");
        });
    } else if ui.button("error heatmap vs raytraced (H)").clicked() {
        actions.heatmap = true;
    }
}

/// Builds every panel for this frame.
pub fn build(
    root: &mut egui::Ui,
    state: &mut ViewerState,
    scene: &mut SceneState,
    gpu: &GpuContext,
    actions: &mut Actions,
) {
    state.view_left = 0;
    // The side panel keeps the width it is given (content scrolls inside
    // it) and never takes more than 45 % of the window.
    let width = root.ctx().content_rect().width();
    let widest = (width * 0.45).max(200.0);
    if !std::mem::replace(&mut state.layout_fitted, true) && width < super::dock::SMALL_WINDOW {
        state.show_panel = false;
    }
    if !state.show_panel {
        egui::Area::new(egui::Id::unique("panel toggle"))
            .anchor(egui::Align2::LEFT_TOP, [8.0, 8.0])
            .show(root.ctx(), |ui| {
                if ui.button("▶ controls (Tab)").clicked() {
                    state.show_panel = true;
                }
            });
    }
    if state.show_panel {
        let panel = egui::Panel::left("controls")
            .resizable(true)
            .default_size(320.0f32.min(widest))
            .size_range(200.0f32.min(widest)..=widest)
            .show(root, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading("shadowlab");
                    if let Some(e) = &state.error {
                        ui.colored_label(egui::Color32::LIGHT_RED, e);
                    }
                    if let Some(m) = &state.message {
                        ui.label(m);
                    }
                    egui::CollapsingHeader::new("Technique")
                        .default_open(true)
                        .show(ui, |ui| technique_panel(ui, state, scene, gpu));
                    egui::CollapsingHeader::new("Lights")
                        .default_open(true)
                        .show(ui, |ui| light_panel(ui, state, scene));
                    egui::CollapsingHeader::new("Scene and camera")
                        .default_open(false)
                        .show(ui, |ui| scene_panel(ui, state, scene, actions));
                    egui::CollapsingHeader::new("Rendering")
                        .default_open(false)
                        .show(ui, |ui| render_panel(ui, state));
                    egui::CollapsingHeader::new("Statistics")
                        .default_open(true)
                        .show(ui, |ui| stats_panel(ui, state, scene));
                    egui::CollapsingHeader::new("Debug views")
                        .default_open(false)
                        .show(ui, |ui| debug_panel(ui, state, scene, actions));
                    if ui.button("help (F1)").clicked() {
                        state.show_help = !state.show_help;
                    }
                });
            });
        state.view_left =
            (panel.response.rect.right() * root.ctx().pixels_per_point()).round() as u32;
    }
    super::dock::show(root, state);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::FAMILIES;

    /// Every registered technique's parameter panel builds, with one widget
    /// per parameter that applies and the rest counted as hidden, and leaves
    /// valid values.
    #[test]
    fn parameter_panels_exist_for_every_technique() {
        let ctx = egui::Context::default();
        for f in FAMILIES {
            for p in f.presets {
                let mut choice = technique::resolve(&format!("{}:{}", f.id, p.name)).unwrap();
                let before = choice.params.values.clone();
                let mut panel = None;
                ctx.run_ui(Default::default(), |ui| {
                    panel = Some(param_panel(ui, &mut choice.params, None));
                })
                .drop_without_applying_deltas();
                let panel = panel.unwrap();
                assert_eq!(
                    panel.shown.len() + panel.hidden,
                    f.params.len(),
                    "{}: every parameter shown or hidden",
                    f.id
                );
                // Sliders snap to their step, so allow rounding noise only.
                for (a, b) in choice.params.values.iter().zip(&before) {
                    assert!(
                        (a - b).abs() < 1e-9,
                        "{}: building the panel changed {b} to {a}",
                        f.id
                    );
                }
                for (s, v) in choice.params.specs.iter().zip(&choice.params.values) {
                    assert!(s.min <= *v && *v <= s.max);
                }
            }
        }
    }

    /// The shadow-map panel shows, per light type, the parameters that act
    /// on it: a point light its cube or paraboloid choice and local normal
    /// offset, a spot light its field of view and fit, a sun its cascades and
    /// warps; the grid filter hides the moment filters' and PCSS's rows, and
    /// choosing a moment filter shows its blur and hides the taps.
    #[test]
    fn the_panel_lists_the_parameters_of_each_light_type() {
        let ctx = egui::Context::default();
        let shown = |id: &str, kind: LightType| {
            let mut choice = crate::measure::parse_technique_list(id).unwrap().remove(0);
            let mut names = vec![];
            ctx.run_ui(Default::default(), |ui| {
                names = param_panel(ui, &mut choice.params, Some(kind)).shown;
            })
            .drop_without_applying_deltas();
            names
        };
        let point = shown("shadow-map:pcf", LightType::Point);
        let spot = shown("shadow-map:pcf", LightType::Spot);
        let sun = shown("shadow-map:pcf", LightType::Directional);
        for (list, has, lacks) in [
            (
                &point,
                &["omni", "normal_offset_local", "samples", "radius"][..],
                &[
                    "fov",
                    "cascades",
                    "warp",
                    "normal_offset_directional",
                    "fit",
                    "blur",
                ][..],
            ),
            (
                &spot,
                &[
                    "fov",
                    "fit",
                    "roll",
                    "normal_offset_local",
                    "slope_bias_clamp_local",
                ][..],
                &[
                    "omni",
                    "cascades",
                    "normal_offset_directional",
                    "slope_bias_clamp",
                ][..],
            ),
            (
                &sun,
                &[
                    "cascades",
                    "warp",
                    "fit",
                    "normal_offset_directional",
                    "slope_bias_clamp",
                ][..],
                &[
                    "omni",
                    "fov",
                    "normal_offset_local",
                    "slope_bias_clamp_local",
                    "split_lambda",
                    "lispsm_n",
                ][..],
            ),
        ] {
            for n in has {
                assert!(list.contains(n), "{n} missing from {list:?}");
            }
            for n in lacks {
                assert!(!list.contains(n), "{n} shown in {list:?}");
            }
        }
        let vsm = shown("shadow-map:vsm", LightType::Directional);
        assert!(vsm.contains(&"blur") && vsm.contains(&"bleeding_reduction"));
        assert!(!vsm.contains(&"samples") && !vsm.contains(&"exponent_negative"));
        let csm = shown("shadow-map:csm", LightType::Directional);
        assert!(csm.contains(&"split_lambda") && csm.contains(&"select"));
        // Shadow volumes: the scissor needs a light's range, the far-plane
        // choice volumes extruded to infinity; projective shadows' alpha
        // bias the depth-in-alpha comparison.
        let volumes_sun = shown("shadow-volume:auto", LightType::Directional);
        let volumes_point = shown("shadow-volume:auto", LightType::Point);
        let finite = shown("shadow-volume:auto[length=50]", LightType::Point);
        assert!(!volumes_sun.contains(&"scissor") && volumes_point.contains(&"scissor"));
        assert!(volumes_point.contains(&"far_plane") && !finite.contains(&"far_plane"));
        assert!(!shown("projective:default", LightType::Spot).contains(&"alpha_bias"));
        let virtual_point = shown("shadow-map:virtual", LightType::Point);
        assert!(
            virtual_point.contains(&"texels_per_pixel")
                && !virtual_point.contains(&"clipmap_levels")
        );
    }
}
