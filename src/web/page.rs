//! The lab in a page: the link's view rendered on WebGPU into the canvas,
//! its technique and parameters switched from the same table as the native
//! viewer and `--set`, and the frame compared with the reference, which
//! runs on the page's one thread.

use super::present::{PendingDraw, PresentMode, Presenter};
use super::query::{self, PageArgs};
use super::readback::read_texture;
use crate::gpu::GpuContext;
use crate::headless::{HeadlessFrame, decode_mask, mask_to_u8};
use crate::measure::quality::{self, MaskMetrics};
use crate::renderer::RenderSettings;
use crate::scene::{Camera, Light, Scene};
use crate::technique::raytraced::ReferenceSettings;
use crate::technique::{Feedback, TechniqueChoice, TechniqueInstance};
use anyhow::{Context, Result, anyhow, bail};
use wasm_bindgen::prelude::*;

/// Frames rendered before a comparison, so that the techniques that feed a
/// frame's result to the next (SDSM's depth bounds, a virtual map's pages)
/// have settled: the page cannot wait inside a frame as `compare` does.
const SETTLING_FRAMES: usize = 4;

/// Why a technique does not run in the page, or `None` when it does.
pub fn unavailable(family: &str) -> Option<&'static str> {
    (family == "raytraced").then_some(
        "the reference reads the G-buffer back inside a frame, which a page cannot wait for; the page runs it itself (compare=1, or Compare)",
    )
}

/// An error naming why `choice` does not run in the page ([`unavailable`]).
fn check_runs_in_page(choice: &TechniqueChoice) -> Result<()> {
    match unavailable(choice.family.id) {
        Some(why) => bail!("{} does not run in the page: {why}", choice.id()),
        None => Ok(()),
    }
}

/// The `log` crate's records in the browser's console (warnings such as a
/// texture that could not be decoded, and the adapter's description).
struct ConsoleLog;

impl log::Log for ConsoleLog {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Info
    }

    fn log(&self, r: &log::Record) {
        if !self.enabled(r.metadata()) {
            return;
        }
        let text = JsValue::from_str(&format!("{}: {}", r.level(), r.args()));
        match r.level() {
            log::Level::Error => web_sys::console::error_1(&text),
            log::Level::Warn => web_sys::console::warn_1(&text),
            _ => web_sys::console::log_1(&text),
        }
    }

    fn flush(&self) {}
}

/// What the canvas shows.
pub(super) enum Shown {
    Image,
    /// The last comparison's heatmap, in the frame's colour format.
    Heatmap(wgpu::Texture),
    /// A light's visibility mask in grey.
    Mask(usize),
}

/// What presenting a frame leaves to await.
pub(super) enum Presented {
    Drawn,
    /// The frame's colour on its way to a 2D canvas.
    Draw(PendingDraw),
    /// The mask shown, being read back ([`Page::present_mask`] shows it).
    Mask(crate::gpu::TextureCopy),
}

/// Everything the page holds: the device, the scene and view, the
/// technique's instances and frame, and what the canvas shows.
pub(super) struct Page {
    pub(super) gpu: GpuContext,
    presenter: Presenter,
    scene: Scene,
    pub(super) camera: Camera,
    pub(super) lights: Vec<Light>,
    args: PageArgs,
    hf: HeadlessFrame,
    settings: RenderSettings,
    pub(super) shown: Shown,
    /// The name of a file opened in the page, which no link can name.
    opened_file: Option<String>,
    /// Per light, the technique's mask of the last comparison.
    pub(super) compared_masks: Vec<Vec<f32>>,
    /// Whether a light was changed in the page: no link names it then.
    lights_edited: bool,
}

/// Runs `f` inside validation and out-of-memory error scopes and awaits
/// them: a shader the browser rejects is an error naming `what`.
async fn checked<T>(gpu: &GpuContext, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    let oom = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let r = f();
    let (v, o) = (validation.pop().await, oom.pop().await);
    if let Some(e) = o {
        bail!("{what}: the GPU is out of memory ({e})");
    }
    if let Some(e) = v {
        bail!("{what}: {e}");
    }
    r
}

impl Page {
    pub(super) async fn create(
        canvas: web_sys::HtmlCanvasElement,
        pairs: &str,
        present: PresentMode,
    ) -> Result<Page> {
        static LOGGER: ConsoleLog = ConsoleLog;
        if log::set_logger(&LOGGER).is_ok() {
            log::set_max_level(log::LevelFilter::Info);
        }
        let pairs: Vec<(String, String)> =
            serde_json::from_str(pairs).context("the page's URL parameters")?;
        let args = PageArgs::from_pairs(&pairs)?;
        let choice = args.choice()?;
        check_runs_in_page(&choice)?;
        let (scene, camera, lights) = args.view.resolve()?;
        let (w, h) = args.view.size;
        canvas.set_width(w);
        canvas.set_height(h);
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let presenter = match present {
            PresentMode::Readback => Presenter::readback(&canvas)?,
            PresentMode::WebGpu => Presenter::WebGpu(
                instance
                    .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
                    .map_err(|e| anyhow!("the canvas cannot show WebGPU: {e}"))?,
            ),
        };
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                compatible_surface: presenter.surface(),
                ..Default::default()
            })
            .await
            .map_err(|e| anyhow!("no WebGPU adapter in this browser: {e}"))?;
        let gpu = GpuContext::from_adapter(instance, adapter).await?;
        let color_format = presenter.configure(&gpu, w, h)?;
        let choices = vec![choice; lights.len().max(1)];
        let hf = checked(&gpu, "creating the renderer", || {
            HeadlessFrame::with_color_format(&gpu, &scene, &choices, (w, h), color_format)
        })
        .await?;
        let settings = RenderSettings {
            feedback: Feedback::PreviousFrame,
            ..args.view.settings()
        };
        let mut page = Page {
            gpu,
            presenter,
            scene,
            camera,
            lights,
            args,
            hf,
            settings,
            shown: Shown::Image,
            opened_file: None,
            compared_masks: vec![],
            lights_edited: false,
        };
        let gpu = &page.gpu;
        checked(gpu, "the first frame", || {
            page.hf
                .render(gpu, &page.scene, &page.camera, &page.lights, &page.settings)
                .map(|_| ())
        })
        .await?;
        Ok(page)
    }

    pub(super) fn render(&mut self) -> Result<f64> {
        let t = self.hf.render(
            &self.gpu,
            &self.scene,
            &self.camera,
            &self.lights,
            &self.settings,
        )?;
        Ok(t.total_ms)
    }

    /// Puts what the canvas shows on it (see [`Presenter::present`]), or
    /// starts reading back the mask it shows.
    pub(super) fn present(&self) -> Result<Presented> {
        let source = match &self.shown {
            Shown::Image => self.hf.frame.color(),
            Shown::Heatmap(t) => t,
            Shown::Mask(i) => {
                let masks = self.hf.frame.masks();
                return Ok(Presented::Mask(
                    self.gpu.copy_texture(masks, *i as u32, 0, 2),
                ));
            }
        };
        Ok(match self.presenter.present(&self.gpu, source)? {
            Some(d) => Presented::Draw(d),
            None => Presented::Drawn,
        })
    }

    /// Shows a mask layer as read back (half floats) in grey, white = lit.
    pub(super) fn present_mask(&self, raw: &[u8]) -> Result<Option<PendingDraw>> {
        let rgba: Vec<u8> = mask_to_u8(&decode_mask(raw))
            .into_iter()
            .flat_map(|g| [g, g, g, 255])
            .collect();
        self.presenter.present(&self.gpu, &self.upload(&rgba))
    }

    /// Light `light`'s technique (the first light's for a frame without
    /// lights).
    pub(super) fn choice(&self, light: usize) -> &TechniqueChoice {
        &self.hf.techniques[light.min(self.hf.techniques.len() - 1)].choice
    }

    /// The technique of every light, or `None` when they differ.
    fn common_choice(&self) -> Option<&TechniqueChoice> {
        let first = self.choice(0);
        let same =
            |c: &TechniqueChoice| c.id() == first.id() && c.params.values == first.params.values;
        self.hf
            .techniques
            .iter()
            .all(|t| same(&t.choice))
            .then_some(first)
    }

    /// The techniques' ids: one, or one per light where they differ.
    pub(super) fn technique_label(&self) -> String {
        match self.common_choice() {
            Some(c) => c.id(),
            None => self
                .hf
                .techniques
                .iter()
                .map(|t| t.choice.id())
                .collect::<Vec<_>>()
                .join("|"),
        }
    }

    /// Replaces the technique of `light`, or of every light (`None`).
    pub(super) async fn set_choice(
        &mut self,
        choice: TechniqueChoice,
        light: Option<usize>,
    ) -> Result<()> {
        check_runs_in_page(&choice)?;
        let count = self.lights.len();
        if let Some(i) = light.filter(|&i| i >= count.max(1)) {
            bail!("light {i}: the scene has {count} lights (they count from 0)");
        }
        let gpu = &self.gpu;
        let instances = checked(gpu, "creating the technique", || match light {
            None => TechniqueInstance::per_light(gpu, &choice, count),
            Some(_) => Ok(vec![TechniqueInstance::new(gpu, choice.clone())?]),
        })
        .await?;
        match light {
            None => self.hf.techniques = instances,
            Some(i) => self.hf.techniques.splice(i..=i, instances).for_each(drop),
        }
        self.shown = Shown::Image;
        Ok(())
    }

    /// Replaces light `index` (checked as a scene file's lights are).
    pub(super) fn set_light(&mut self, index: usize, mut light: Light) -> Result<()> {
        self.check_light(index)?;
        light.direction = light.direction.normalize_or_zero();
        light.validate()?;
        self.lights[index] = light;
        self.lights_edited = true;
        self.shown = Shown::Image;
        Ok(())
    }

    /// An error unless light `index` exists.
    pub(super) fn check_light(&self, index: usize) -> Result<()> {
        if index >= self.lights.len() {
            bail!(
                "light {index}: the scene has {} lights (they count from 0)",
                self.lights.len()
            );
        }
        Ok(())
    }

    /// The frame against the reference, per light, and the heatmap of the
    /// first light shown on the canvas.
    pub(super) async fn compare(&mut self) -> Result<serde_json::Value> {
        let mut frame_ms = 0.0;
        for _ in 0..SETTLING_FRAMES {
            frame_ms = self.render()?;
        }
        let (gpu, frame) = (&self.gpu, &self.hf.frame);
        let (w, h) = (frame.width(), frame.height());
        let pos = read_texture(gpu, frame.gbuffer_position(), 0, 16).await?;
        let nrm = read_texture(gpu, frame.gbuffer_normal(), 0, 8).await?;
        let mut color = read_texture(gpu, frame.color(), 0, 4).await?;
        frame.swap_rgba_order(&mut color);
        let considered = quality::considered_from_gbuffer(
            bytemuck::cast_slice(&pos),
            bytemuck::cast_slice(&nrm),
            &self.lights,
        );
        let reference = ReferenceSettings::defaults();
        let bvh = reference.casters(&self.scene, None)?;
        let start = crate::clock::Instant::now();
        let truths: Vec<Vec<f32>> = self
            .lights
            .iter()
            .map(|l| reference.mask_from_gbuffer_bytes(&bvh, l, (&pos, &nrm), frame.uniform()))
            .collect();
        let reference_ms = start.elapsed().as_secs_f64() * 1e3;
        let mut rows: Vec<MaskMetrics> = vec![];
        let mut masks = vec![];
        for (i, truth) in truths.iter().enumerate() {
            let mask = decode_mask(&read_texture(gpu, frame.masks(), i as u32, 2).await?);
            rows.push(quality::mask_metrics(
                w as usize,
                h as usize,
                &considered[i],
                truth,
                &mask,
            ));
            if i == 0 {
                let heat = quality::heatmap(&color, &considered[0], truth, &mask);
                self.shown = Shown::Heatmap(self.upload(&heat));
            }
            masks.push(mask);
        }
        self.compared_masks = masks;
        Ok(serde_json::json!({
            "technique": self.technique_label(),
            "adapter": gpu.adapter_summary(),
            "size": [w, h],
            "frame_ms": frame_ms,
            "reference_ms": reference_ms,
            "reference_kernel": format!("{:?}", bvh.kernel()),
            "lights": rows,
        }))
    }

    /// A texture of the frame's size and colour format holding `rgba`
    /// (swapped to BGRA for a canvas that prefers it).
    fn upload(&self, rgba: &[u8]) -> wgpu::Texture {
        let frame = &self.hf.frame;
        let mut texels = rgba.to_vec();
        frame.swap_rgba_order(&mut texels);
        let texture = crate::gpu::texture_2d(
            &self.gpu.device,
            "shown image",
            frame.width(),
            frame.height(),
            1,
            frame.color_format(),
            wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        );
        self.gpu.queue.write_texture(
            texture.as_image_copy(),
            &texels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * frame.width()),
                rows_per_image: Some(frame.height()),
            },
            texture.size(),
        );
        texture
    }

    /// Replaces the scene by a file's (its camera and lights, or the link's
    /// light preset when the file has it).
    pub(super) async fn open(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        let scene = crate::scene::load_bytes(name, bytes)?;
        let lights = match &self.args.view.light {
            Some(p) => scene
                .light_preset(p)
                .unwrap_or_else(|_| scene.lights.clone()),
            None => scene.lights.clone(),
        };
        if lights.len() > crate::frame::MAX_LIGHTS {
            bail!(
                "{name}: {} lights; at most {} are supported",
                lights.len(),
                crate::frame::MAX_LIGHTS
            );
        }
        let gpu = &self.gpu;
        let (scene_gpu, techniques) = checked(gpu, "uploading the scene", || {
            Ok((
                crate::frame::SceneGpu::upload(gpu, &scene)?,
                TechniqueInstance::per_light(gpu, self.choice(0), lights.len())?,
            ))
        })
        .await?;
        self.hf.scene_gpu = scene_gpu;
        self.hf.techniques = techniques;
        self.camera = scene.camera;
        self.lights = lights;
        self.lights_edited = false;
        self.scene = scene;
        self.shown = Shown::Image;
        self.opened_file = Some(name.to_string());
        Ok(())
    }

    /// The query string of what the page shows now.
    pub(super) fn link(&self) -> Result<String> {
        if let Some(f) = &self.opened_file {
            bail!("{f} was opened in the page: a link can name only built-in scenes");
        }
        if self.lights_edited {
            bail!("a light was changed in the page: a link names only the scene's light presets");
        }
        let choice = self.common_choice().ok_or_else(|| {
            anyhow!(
                "the lights have different techniques: a link names one technique for every light"
            )
        })?;
        let c = &self.camera;
        let v = |p: glam::Vec3| format!("{},{},{}", p.x, p.y, p.z);
        let (w, h) = self.args.view.size;
        // The technique as `compare` labels it: its preset, and in brackets
        // the values that differ from it.
        let mut pairs: Vec<(&str, String)> = vec![
            ("scene", self.args.view.scene.clone()),
            ("eye", v(c.eye)),
            ("target", v(c.target)),
            ("technique", crate::measure::choice_label(choice)),
            ("size", format!("{w}x{h}")),
        ];
        if let Some(l) = &self.args.view.light {
            pairs.push(("light", l.clone()));
        }
        Ok(query::link(&pairs))
    }
}
