//! Shadow techniques. Each family lives in its own folder, implements
//! [`ShadowTechnique`] and is listed once in [`FAMILIES`]; a technique
//! writes, for one light, a screen-space visibility mask (the fraction of the
//! light that reaches the surface seen in each pixel) that the lighting pass
//! composes as `ambient + visibility × (diffuse + specular)`.

pub mod irregular;
pub mod light_space;
pub mod listing;
pub mod none;
pub mod params;
pub mod planar;
pub mod projective;
pub mod raytraced;
pub mod shadow_map;
pub mod shadow_volume;

use crate::frame::{Compose, FrameLayouts, FrameTargets, SceneGpu};
use crate::gpu::GpuContext;
use crate::gpu::work::CountedRenderPass;
use crate::scene::{Light, Scene};
use anyhow::{Context, Result, anyhow};
pub use params::{ParamKind, ParamSpec, ParamValues};

/// Everything a technique may read while writing one light's mask.
pub struct MaskContext<'a> {
    pub gpu: &'a GpuContext,
    pub scene: &'a Scene,
    pub scene_gpu: &'a SceneGpu,
    /// The frame's targets, read only: size, uniform, depth, G-buffer.
    pub frame: &'a FrameTargets,
    pub light_index: usize,
    pub light: &'a Light,
    /// The camera of the frame.
    pub camera: &'a crate::scene::Camera,
    /// The camera light views are fitted to (cascade splits, the view of
    /// the scene a map covers): the frame's, except when measuring how maps
    /// move with the camera over fixed surface points (`compare --path`).
    pub fit_camera: &'a crate::scene::Camera,
    /// The targets whose G-buffer shows what `fit_camera` sees (fits to
    /// the pixels seen): `frame`, except where `fit_camera` is another
    /// camera.
    pub fit_frame: &'a FrameTargets,
    /// The mask layer to write (format [`crate::frame::MASK_FORMAT`]).
    pub target: &'a wgpu::TextureView,
    /// How results the GPU computes for the CPU reach it this frame.
    pub feedback: Feedback,
}

/// How a technique reads back what the GPU computed from this frame for
/// its own CPU-side set-up (SDSM's depth bounds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Feedback {
    /// Wait for this frame's result (one stall per frame; every measurement).
    #[default]
    ThisFrame,
    /// Use the latest result that has arrived, without waiting (the viewer).
    PreviousFrame,
}

impl MaskContext<'_> {
    /// Binds the frame uniform (group 0), the object table (group 1) and
    /// the G-buffer (group 3) of a technique pass; the pass binds group 2.
    pub fn bind_frame_groups(&self, pass: &mut wgpu::RenderPass) {
        pass.set_bind_group(
            crate::frame::FRAME_GROUP,
            self.frame.frame_bind_group(),
            &[],
        );
        pass.set_bind_group(
            crate::frame::OBJECTS_GROUP,
            &self.scene_gpu.object_bind_group,
            &[],
        );
        pass.set_bind_group(
            crate::frame::GBUFFER_GROUP,
            self.frame.gbuffer_bind_group(),
            &[],
        );
    }
}

/// One shadow technique instance, owned per light. Its family's shaders,
/// layouts and pipelines are shared per device (`GpuContext::cache`); the
/// instance owns its light's state (maps, volumes).
pub trait ShadowTechnique: Send {
    /// Parses changed parameter values into the family's typed
    /// configuration (the family's `create` parses the first ones); on an
    /// error the configuration stays as it was.
    fn configure(&mut self, params: &ParamValues) -> Result<()>;

    /// Records (or performs) the work that writes the light's visibility mask
    /// into `ctx.target`. Every pixel of the target must be written.
    fn render_mask(&mut self, ctx: &MaskContext, encoder: &mut wgpu::CommandEncoder) -> Result<()>;

    /// How the lighting pass composes this technique's mask.
    fn compose(&self) -> Compose {
        Compose::Relight
    }

    /// True when the frame must use a projection with the far plane at
    /// infinity ([`crate::scene::Camera::projection_infinite`]).
    fn infinite_far_plane(&self) -> bool {
        false
    }

    /// Called once the GPU has finished this frame's masks: read back
    /// statistics for [`ShadowTechnique::counters`].
    fn after_frame(&mut self, _gpu: &GpuContext) -> Result<()> {
        Ok(())
    }

    /// Technique-specific counters of the last frame (name, value).
    fn counters(&self) -> Vec<(&'static str, f64)> {
        vec![]
    }

    /// Bytes of shadow-specific resources this instance holds (maps,
    /// volumes, acceleration structures).
    fn resource_bytes(&self) -> u64 {
        0
    }

    /// Asks the technique to prepare its debug views in the next frames.
    fn enable_debug(&mut self, _on: bool) {}

    /// The debug views of the last frame: world-space lines (light frusta,
    /// silhouettes, volumes) and small images (a depth map).
    fn debug_views(&self, _gpu: &GpuContext) -> Result<DebugViews> {
        Ok(DebugViews::default())
    }

    /// With debug views on, where each pixel of the last frame looked up
    /// the technique's map; `None` for techniques without a map.
    fn map_lookup(&self, _gpu: &GpuContext) -> Result<Option<MapLookup>> {
        Ok(None)
    }
}

/// Per pixel of a frame (row-major), what a shadow-map lookup saw.
#[derive(Clone, Debug, Default)]
pub struct MapLookup {
    /// Screen pixels one map texel spans (the aliasing measure d of [001] §3;
    /// > 1: a texel covers more than a pixel), 0 where no map is looked up.
    pub footprint: Vec<f32>,
    /// The map partition looked up, counted from 1 (cascade or cube face);
    /// 0 where none is.
    pub partition: Vec<u32>,
}

/// A world-space line segment of a debug view (RGBA colour).
#[derive(Clone, Copy, Debug)]
pub struct DebugLine {
    pub a: glam::Vec3,
    pub b: glam::Vec3,
    pub color: [f32; 4],
}

/// An RGBA8 image of a debug view.
#[derive(Clone, Debug)]
pub struct DebugImage {
    pub label: String,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// What a technique shows in the viewer's debug views.
#[derive(Clone, Debug, Default)]
pub struct DebugViews {
    pub lines: Vec<DebugLine>,
    pub images: Vec<DebugImage>,
}

/// The 12 edges of the frustum of a view-projection matrix ([0,1] depth).
pub fn frustum_lines(view_proj: glam::Mat4, color: [f32; 4]) -> Vec<DebugLine> {
    let inv = view_proj.inverse();
    let corner = |i: usize| {
        let p = inv
            * glam::Vec4::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { 0.0 } else { 1.0 },
                1.0,
            );
        p.truncate() / p.w
    };
    [
        (0, 1),
        (2, 3),
        (0, 2),
        (1, 3),
        (4, 5),
        (6, 7),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ]
    .iter()
    .map(|&(a, b)| DebugLine {
        a: corner(a),
        b: corner(b),
        color,
    })
    .collect()
}

/// A named set of parameter values of a family.
pub struct Preset {
    pub name: &'static str,
    pub summary: &'static str,
    pub values: &'static [(&'static str, &'static str)],
}

/// What a family declares it handles; `shadowlab report` checks each
/// claim against the family's measurements.
#[derive(Clone, Copy, Debug)]
pub struct Capabilities {
    pub point_lights: bool,
    pub spot_lights: bool,
    pub directional_lights: bool,
    /// Penumbrae from lights with an area (some presets).
    pub soft_shadows: bool,
    /// Casters shadow themselves and other casters, not only receivers.
    pub self_shadowing: bool,
    /// Meshes that are not closed (the bunny, the teapot).
    pub open_meshes: bool,
    /// Receivers that are not planes.
    pub curved_receivers: bool,
    /// Casters with holes (alpha-tested cut-outs: leaves, fences): a
    /// shadow volume is extruded from triangles and cannot cut them.
    pub cutout_casters: bool,
}

/// A technique family: its parameter table, presets and constructor.
pub struct Family {
    pub id: &'static str,
    pub summary: &'static str,
    pub capabilities: Capabilities,
    pub params: &'static [ParamSpec],
    /// The first preset is the family's default (`family` = `family:<first>`).
    pub presets: &'static [Preset],
    /// A technique instance configured with the given values.
    pub create: fn(&GpuContext, &ParamValues) -> Result<Box<dyn ShadowTechnique>>,
}

/// The registry: every technique family.
pub static FAMILIES: &[&Family] = &[
    &none::FAMILY,
    &raytraced::FAMILY,
    &planar::FAMILY,
    &projective::FAMILY,
    &shadow_map::FAMILY,
    &shadow_volume::FAMILY,
    &irregular::FAMILY,
];

/// Pipeline layout of a technique pass: frame uniform (group 0), object
/// table (group 1), the technique's own group 2 and the G-buffer (group 3).
pub fn pipeline_layout(
    gpu: &GpuContext,
    label: &str,
    own: &wgpu::BindGroupLayout,
) -> wgpu::PipelineLayout {
    FrameLayouts::of(gpu).technique_layout(&gpu.device, label, own)
}

/// Depth-stencil state of a pass over the frame's depth: read only,
/// compare Always, with `stencil` (default: untouched).
pub fn frame_depth_read(gpu: &GpuContext, stencil: wgpu::StencilState) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: gpu.depth_format,
        depth_write_enabled: Some(false),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil,
        bias: Default::default(),
    }
}

/// The fragment stage of a full-screen pipeline: an entry point of a
/// module, with values for the pipeline-overridable constants it reads.
#[derive(Clone, Copy)]
pub struct FragmentEntry<'a> {
    pub module: &'a wgpu::ShaderModule,
    pub entry: &'a str,
    pub constants: &'a [(&'a str, f64)],
}

impl<'a> FragmentEntry<'a> {
    /// `entry` of `module`, its constants at their defaults.
    pub fn new(module: &'a wgpu::ShaderModule, entry: &'a str) -> FragmentEntry<'a> {
        FragmentEntry {
            module,
            entry,
            constants: &[],
        }
    }
}

/// A full-screen pipeline (`vs_fullscreen` of common.wgsl, one triangle)
/// running `fragment` into `targets`, from the device's cache (the label
/// names the pass; label, entry point, constants and states are the key).
pub fn fullscreen_pipeline(
    gpu: &GpuContext,
    label: &str,
    layout: &wgpu::PipelineLayout,
    fragment: FragmentEntry,
    targets: &[Option<wgpu::ColorTargetState>],
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    let constant_bits: Vec<_> = fragment
        .constants
        .iter()
        .map(|(k, v)| (*k, v.to_bits()))
        .collect();
    let key = (fragment.entry, targets, &depth_stencil, constant_bits);
    gpu.cache.render_pipeline(label, &key, || {
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: fragment.module,
                    entry_point: Some("vs_fullscreen"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: depth_stencil.clone(),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: fragment.module,
                    entry_point: Some(fragment.entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: fragment.constants,
                        ..Default::default()
                    },
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
    })
}

/// Begins a render pass on the light's mask layer, cleared to 1 (lit), with
/// the frame's depth (read) and a cleared stencil.
pub fn mask_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    ctx: &MaskContext,
    label: &str,
) -> CountedRenderPass<'e> {
    mask_pass_with(encoder, ctx, label, wgpu::LoadOp::Clear(wgpu::Color::WHITE))
}

/// [`mask_pass`] with a chosen load operation for the mask.
pub fn mask_pass_with<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    ctx: &MaskContext,
    label: &str,
    load: wgpu::LoadOp<wgpu::Color>,
) -> CountedRenderPass<'e> {
    pass_over_frame_depth(encoder, ctx, label, ctx.target, load, true)
}

/// A render pass into `view` over the frame's depth (loaded and kept),
/// its stencil cleared to 0 when `clear_stencil`, else not attached.
pub fn pass_over_frame_depth<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    ctx: &MaskContext,
    label: &str,
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
    clear_stencil: bool,
) -> CountedRenderPass<'e> {
    ctx.gpu.render_pass(
        encoder,
        &wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: ctx.frame.depth_view(),
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: clear_stencil.then_some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            ..Default::default()
        },
    )
}

/// A technique for one light with its parameter values.
pub struct TechniqueInstance {
    pub choice: TechniqueChoice,
    pub technique: Box<dyn ShadowTechnique>,
}

impl TechniqueInstance {
    pub fn new(gpu: &GpuContext, choice: TechniqueChoice) -> Result<TechniqueInstance> {
        let technique = (choice.family.create)(gpu, &choice.params)?;
        Ok(TechniqueInstance { choice, technique })
    }

    /// One instance of `choice` for each of `lights` lights (at least one,
    /// for a frame without lights).
    pub fn per_light(
        gpu: &GpuContext,
        choice: &TechniqueChoice,
        lights: usize,
    ) -> Result<Vec<TechniqueInstance>> {
        (0..lights.max(1))
            .map(|_| TechniqueInstance::new(gpu, choice.clone()))
            .collect()
    }

    /// Changes the parameter values (the viewer's sliders); on an error
    /// the previous values stay.
    pub fn set_params(&mut self, params: ParamValues) -> Result<()> {
        self.technique.configure(&params)?;
        self.choice.params = params;
        Ok(())
    }
}

/// What the lights' techniques ask of the frame.
#[derive(Clone, Debug, Default)]
pub struct TechniqueNeeds {
    /// Per light: how its mask is composed.
    pub compose: Vec<Compose>,
    /// Some technique needs the far plane at infinity (shadow volumes).
    pub infinite_far_plane: bool,
}

impl TechniqueNeeds {
    pub fn of(techniques: &[TechniqueInstance]) -> TechniqueNeeds {
        TechniqueNeeds {
            compose: techniques.iter().map(|t| t.technique.compose()).collect(),
            infinite_far_plane: techniques.iter().any(|t| t.technique.infinite_far_plane()),
        }
    }
}

/// A resolved technique id: family, preset name and parameter values.
#[derive(Clone)]
pub struct TechniqueChoice {
    pub family: &'static Family,
    pub preset: &'static str,
    pub params: ParamValues,
}

impl TechniqueChoice {
    /// `family:preset` as written on the command line.
    pub fn id(&self) -> String {
        format!("{}:{}", self.family.id, self.preset)
    }
}

/// Every registered preset as `family:preset`, in registry order.
pub fn preset_ids() -> Vec<String> {
    FAMILIES
        .iter()
        .flat_map(|f| {
            f.presets
                .iter()
                .map(move |p| format!("{}:{}", f.id, p.name))
        })
        .collect()
}

/// Resolves `family` or `family:preset` to a family and its preset values.
pub fn resolve(id: &str) -> Result<TechniqueChoice> {
    let (fid, pid) = id.split_once(':').map_or((id, None), |(f, p)| (f, Some(p)));
    let family = FAMILIES.iter().find(|f| f.id == fid).ok_or_else(|| {
        anyhow!(
            "unknown technique '{id}' (valid: {})",
            preset_ids().join(", ")
        )
    })?;
    let preset = match pid {
        None => &family.presets[0],
        Some(p) => family.presets.iter().find(|x| x.name == p).ok_or_else(|| {
            anyhow!(
                "technique family '{fid}' has no preset '{p}' (valid: {})",
                family
                    .presets
                    .iter()
                    .map(|x| format!("{fid}:{}", x.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })?,
    };
    let mut params = ParamValues::defaults(family.params);
    for (k, v) in preset.values {
        params.set(k, v)?;
    }
    Ok(TechniqueChoice {
        family,
        preset: preset.name,
        params,
    })
}

/// Parses one technique with optional parameter values in brackets,
/// `family[:preset][key=value,...]`, e.g. `raytraced:reference[samples=64]`.
pub fn parse_choice(spec: &str) -> Result<TechniqueChoice> {
    let item = spec.trim();
    let (id, params) = match item.split_once('[') {
        Some((id, rest)) => (
            id,
            rest.strip_suffix(']')
                .ok_or_else(|| anyhow!("unbalanced '[' in '{item}' (expected ']' at the end)"))?,
        ),
        None => (item, ""),
    };
    if params.contains(['[', ']']) {
        anyhow::bail!("unbalanced brackets in '{item}'");
    }
    let mut c = resolve(id)?;
    let sets: Vec<String> = params
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(String::from)
        .collect();
    apply_settings(&mut c.params, &sets).with_context(|| format!("in '{item}'"))?;
    Ok(c)
}

/// Warns of `--set` parameters that do nothing for some of `lights` with
/// the chosen values (a cascade count under a point light, a blur under
/// the grid filter).
pub fn warn_without_effect(
    choice: &TechniqueChoice,
    set: &[String],
    lights: &[crate::scene::Light],
) {
    for (i, l) in lights.iter().enumerate() {
        for p in choice.params.without_effect(set, l.kind) {
            log::warn!(
                "--set {p}: it has no effect on light {i} ({:?}) with {}:{}",
                l.kind,
                choice.family.id,
                choice.preset
            );
        }
    }
}

/// Parses `key=value` settings and applies them to `params`.
pub fn apply_settings(params: &mut ParamValues, settings: &[String]) -> Result<()> {
    for s in settings {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| anyhow!("--set expects key=value, got '{s}'"))?;
        params.set(k.trim(), v.trim())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_accepts_family_and_preset_ids() {
        let c = resolve("none").unwrap();
        assert_eq!(c.id(), "none:default");
        assert_eq!(resolve("none:default").unwrap().family.id, "none");
        let e = resolve("bogus").err().unwrap().to_string();
        assert!(e.contains("none:default"), "{e}");
        let e = resolve("none:bogus").err().unwrap().to_string();
        assert!(e.contains("valid: none:default"), "{e}");
    }

    #[test]
    fn every_preset_is_valid_for_its_table() {
        for f in FAMILIES {
            assert!(!f.presets.is_empty(), "{} has no preset", f.id);
            for p in f.presets {
                resolve(&format!("{}:{}", f.id, p.name)).unwrap();
            }
            for s in f.params {
                assert!(
                    s.min <= s.default && s.default <= s.max,
                    "{}.{}",
                    f.id,
                    s.name
                );
                assert!(!s.doc.is_empty());
            }
        }
    }

    #[test]
    fn technique_specs_parse_with_bracketed_values() {
        let c = parse_choice("raytraced:reference[samples=64]").unwrap();
        assert_eq!(c.id(), "raytraced:reference");
        assert_eq!(c.params.get("samples").unwrap(), 64.0);
        let e = format!("{:#}", parse_choice("raytraced[nope=1]").err().unwrap());
        assert!(e.contains("unknown parameter 'nope'"), "{e}");
        assert!(parse_choice("raytraced[samples=2]]").is_err());
        assert!(parse_choice("raytraced[[samples=2]").is_err());
    }

    #[test]
    fn settings_must_be_key_value() {
        let mut p = ParamValues::defaults(none::FAMILY.params);
        assert!(apply_settings(&mut p, &["x".into()]).is_err());
        assert!(
            apply_settings(&mut p, &["x=1".into()])
                .unwrap_err()
                .to_string()
                .contains("unknown parameter")
        );
    }
}
