//! The lab in a page: a [`Lab`] renders the link's view on WebGPU into the
//! canvas, switches technique and parameters from the same table as the
//! native viewer and `--set`, moves the camera, and compares the frame with
//! the reference, which runs on the page's one thread.

use super::present::{PendingDraw, PresentMode, Presenter};
use super::query::{self, PageArgs};
use super::readback::read_texture;
use crate::gpu::GpuContext;
use crate::headless::{HeadlessFrame, decode_mask};
use crate::measure::quality::{self, MaskMetrics};
use crate::renderer::RenderSettings;
use crate::scene::{Camera, Light, Scene, orbit};
use crate::technique::raytraced::ReferenceSettings;
use crate::technique::{self, Feedback, TechniqueChoice, TechniqueInstance};
use anyhow::{Context, Result, anyhow, bail};
use std::cell::RefCell;
use std::rc::Rc;
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
enum Shown {
    Image,
    /// The last comparison's heatmap, in the frame's colour format.
    Heatmap(wgpu::Texture),
}

struct Page {
    gpu: GpuContext,
    presenter: Presenter,
    scene: Scene,
    camera: Camera,
    lights: Vec<Light>,
    args: PageArgs,
    choice: TechniqueChoice,
    hf: HeadlessFrame,
    settings: RenderSettings,
    shown: Shown,
    /// The name of a file opened in the page, which no link can name.
    opened_file: Option<String>,
    /// Per light, the technique's mask of the last comparison.
    compared_masks: Vec<Vec<f32>>,
}

/// The page's lab; JavaScript calls its methods (`web/main.js`).
#[wasm_bindgen]
pub struct Lab {
    page: Rc<RefCell<Page>>,
}

fn js_error(e: anyhow::Error) -> JsValue {
    JsValue::from_str(&format!("{e:#}"))
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
    async fn create(
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
        if let Some(why) = unavailable(choice.family.id) {
            bail!("{} does not run in the page: {why}", choice.id());
        }
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
        let hf = checked(&gpu, "creating the renderer", || {
            let mut hf = HeadlessFrame::new(&gpu, &scene, &[choice.clone()], w, h)?;
            hf.frame = crate::frame::FrameTargets::with_color_format(&gpu, w, h, color_format)?;
            hf.techniques = TechniqueInstance::per_light(&gpu, &choice, lights.len())?;
            Ok(hf)
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
            choice,
            hf,
            settings,
            shown: Shown::Image,
            opened_file: None,
            compared_masks: vec![],
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

    fn render(&mut self) -> Result<f64> {
        let t = self.hf.render(
            &self.gpu,
            &self.scene,
            &self.camera,
            &self.lights,
            &self.settings,
        )?;
        Ok(t.total_ms)
    }

    /// Puts what the canvas shows on it (see [`Presenter::present`]).
    fn present(&self) -> Result<Option<PendingDraw>> {
        let source = match &self.shown {
            Shown::Image => self.hf.frame.color(),
            Shown::Heatmap(t) => t,
        };
        self.presenter.present(&self.gpu, source)
    }

    /// Replaces the technique (every light's instance).
    async fn set_choice(&mut self, choice: TechniqueChoice) -> Result<()> {
        if let Some(why) = unavailable(choice.family.id) {
            bail!("{} does not run in the page: {why}", choice.id());
        }
        let gpu = &self.gpu;
        let instances = checked(gpu, "creating the technique", || {
            TechniqueInstance::per_light(gpu, &choice, self.lights.len())
        })
        .await?;
        self.hf.techniques = instances;
        self.choice = choice;
        self.shown = Shown::Image;
        Ok(())
    }

    /// The frame against the reference, per light, and the heatmap of the
    /// first light shown on the canvas.
    async fn compare(&mut self) -> Result<serde_json::Value> {
        let mut frame_ms = 0.0;
        for _ in 0..SETTLING_FRAMES {
            frame_ms = self.render()?;
        }
        let (gpu, frame) = (&self.gpu, &self.hf.frame);
        let (w, h) = (frame.width(), frame.height());
        let pos = read_texture(gpu, frame.gbuffer_position(), 0, 16).await?;
        let nrm = read_texture(gpu, frame.gbuffer_normal(), 0, 8).await?;
        let mut color = read_texture(gpu, frame.color(), 0, 4).await?;
        let bgra = frame.color_format() == wgpu::TextureFormat::Bgra8UnormSrgb;
        if bgra {
            color.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        let considered = quality::considered_from_gbuffer(
            bytemuck::cast_slice(&pos),
            bytemuck::cast_slice(&nrm),
            &self.lights,
        );
        let reference = ReferenceSettings::defaults();
        let bvh = reference.casters(&self.scene, None)?;
        let start = crate::clock::Instant::now();
        let inv_view_proj = frame.uniform().inv_view_proj;
        let size = glam::UVec2::new(w, h);
        let truths: Vec<Vec<f32>> = self
            .lights
            .iter()
            .map(|l| reference.mask_from_gbuffer_bytes(&bvh, l, (&pos, &nrm), inv_view_proj, size))
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
                let mut heat = quality::heatmap(&color, &considered[0], truth, &mask);
                if bgra {
                    heat.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
                }
                self.shown = Shown::Heatmap(self.upload(&heat));
            }
            masks.push(mask);
        }
        self.compared_masks = masks;
        Ok(serde_json::json!({
            "technique": self.choice.id(),
            "adapter": gpu.adapter_summary(),
            "size": [w, h],
            "frame_ms": frame_ms,
            "reference_ms": reference_ms,
            "reference_kernel": format!("{:?}", bvh.kernel()),
            "lights": rows,
        }))
    }

    /// A texture of the frame's size and colour format holding `rgba`.
    fn upload(&self, rgba: &[u8]) -> wgpu::Texture {
        let frame = &self.hf.frame;
        let texture = crate::gpu::texture_2d(
            &self.gpu.device,
            "heatmap",
            frame.width(),
            frame.height(),
            1,
            frame.color_format(),
            wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        );
        self.gpu.queue.write_texture(
            texture.as_image_copy(),
            rgba,
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
    async fn open(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
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
                TechniqueInstance::per_light(gpu, &self.choice, lights.len())?,
            ))
        })
        .await?;
        self.hf.scene_gpu = scene_gpu;
        self.hf.techniques = techniques;
        self.camera = scene.camera;
        self.lights = lights;
        self.scene = scene;
        self.shown = Shown::Image;
        self.opened_file = Some(name.to_string());
        Ok(())
    }

    /// The query string of what the page shows now.
    fn link(&self) -> Result<String> {
        if let Some(f) = &self.opened_file {
            bail!("{f} was opened in the page: a link can name only built-in scenes");
        }
        let c = &self.camera;
        let v = |p: glam::Vec3| format!("{},{},{}", p.x, p.y, p.z);
        let (w, h) = self.args.view.size;
        let mut pairs: Vec<(&str, String)> = vec![
            ("scene", self.args.view.scene.clone()),
            ("eye", v(c.eye)),
            ("target", v(c.target)),
            ("technique", self.choice.id()),
            ("size", format!("{w}x{h}")),
        ];
        if let Some(l) = &self.args.view.light {
            pairs.push(("light", l.clone()));
        }
        let specs = self.choice.family.params;
        let defaults = technique::resolve(&self.choice.id()).map(|c| c.params.values);
        for (i, spec) in specs.iter().enumerate() {
            let value = self.choice.params.values[i];
            if defaults.as_ref().is_ok_and(|d| d[i] != value) {
                pairs.push(("set", format!("{}={}", spec.name, spec.format(value))));
            }
        }
        Ok(query::link(&pairs))
    }
}

/// The page, or an error while a comparison (or another awaited call)
/// holds it.
fn borrow(page: &RefCell<Page>) -> Result<std::cell::RefMut<'_, Page>, JsValue> {
    page.try_borrow_mut()
        .map_err(|_| JsValue::from_str("busy: a comparison is running"))
}

impl Lab {
    fn page(&self) -> Result<std::cell::RefMut<'_, Page>, JsValue> {
        borrow(&self.page)
    }
}

#[wasm_bindgen]
impl Lab {
    /// The lab on `canvas` for the URL's parameters (`pairs`: a JSON array
    /// of `[key, value]`, already decoded), presenting as `present` says
    /// (`webgpu` or `readback`).
    pub async fn create(
        canvas: web_sys::HtmlCanvasElement,
        pairs: String,
        present: String,
    ) -> Result<Lab, JsValue> {
        let present = PresentMode::parse(&present).map_err(js_error)?;
        let page = Page::create(canvas, &pairs, present)
            .await
            .map_err(js_error)?;
        Ok(Lab {
            page: Rc::new(RefCell::new(page)),
        })
    }

    /// Renders and shows one frame; resolves to its CPU time in ms (0 while
    /// a comparison runs).
    pub fn frame(&self) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let (ms, draw) = {
                let Ok(mut p) = page.try_borrow_mut() else {
                    return Ok(JsValue::from_f64(0.0));
                };
                let ms = p.render().map_err(js_error)?;
                (ms, p.present().map_err(js_error)?)
            };
            if let Some(d) = draw {
                d.draw().await.map_err(js_error)?;
            }
            Ok(JsValue::from_f64(ms))
        })
    }

    /// Compares the frame with the reference; resolves to a JSON report.
    pub fn compare(&self) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            let report = p.compare().await.map_err(js_error)?;
            if let Some(d) = p.present().map_err(js_error)? {
                d.draw().await.map_err(js_error)?;
            }
            Ok(JsValue::from_str(&report.to_string()))
        })
    }

    /// Switches to technique `spec` (`family:preset[key=value,...]`).
    pub fn set_technique(&self, spec: String) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            let choice = technique::parse_choice(&spec).map_err(js_error)?;
            p.set_choice(choice).await.map_err(js_error)?;
            Ok(JsValue::UNDEFINED)
        })
    }

    /// Sets one parameter of the technique's table (`--set key=value`).
    pub fn set_param(&self, key: String, value: String) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            let mut choice = p.choice.clone();
            choice.params.set(&key, &value).map_err(js_error)?;
            p.set_choice(choice).await.map_err(js_error)?;
            Ok(JsValue::UNDEFINED)
        })
    }

    /// The technique's table: every row (name, kind, default, min, max,
    /// step, doc), its current value and whether it applies to each light.
    pub fn parameters(&self) -> Result<String, JsValue> {
        let p = self.page()?;
        let params = &p.choice.params;
        let rows: Vec<serde_json::Value> = params
            .specs
            .iter()
            .zip(&params.values)
            .map(|(spec, &v)| {
                let applies: Vec<bool> = p
                    .lights
                    .iter()
                    .map(|l| params.applies(spec, Some(l.kind)))
                    .collect();
                serde_json::json!({"spec": spec, "value": spec.format(v), "applies": applies})
            })
            .collect();
        Ok(serde_json::json!({"technique": p.choice.id(), "rows": rows}).to_string())
    }

    /// Every preset, with why it does not run in the page where it does not.
    pub fn techniques() -> String {
        let rows: Vec<serde_json::Value> = technique::preset_ids()
            .into_iter()
            .map(|id| {
                let family = id.split(':').next().unwrap_or_default().to_string();
                serde_json::json!({"id": id, "unavailable": unavailable(&family)})
            })
            .collect();
        serde_json::Value::from(rows).to_string()
    }

    /// Built-in scene names.
    pub fn scenes() -> String {
        serde_json::json!(crate::scene::builtin::NAMES).to_string()
    }

    /// Orbits the camera by `dx`, `dy` radians (yaw, pitch).
    pub fn orbit(&self, dx: f32, dy: f32) -> Result<(), JsValue> {
        let mut p = self.page()?;
        orbit::orbit(&mut p.camera, dx, dy);
        p.shown = Shown::Image;
        Ok(())
    }

    /// Moves the camera towards (`factor` < 1) or away from its target.
    pub fn zoom(&self, factor: f32) -> Result<(), JsValue> {
        let mut p = self.page()?;
        orbit::zoom(&mut p.camera, factor);
        p.shown = Shown::Image;
        Ok(())
    }

    /// Pans by fractions of the distance to the target.
    pub fn pan(&self, dx: f32, dy: f32) -> Result<(), JsValue> {
        let mut p = self.page()?;
        orbit::pan(&mut p.camera, dx, dy);
        p.shown = Shown::Image;
        Ok(())
    }

    /// Shows the rendered image again instead of the heatmap.
    pub fn show_image(&self) -> Result<(), JsValue> {
        self.page()?.shown = Shown::Image;
        Ok(())
    }

    /// The query string that reproduces the view shown.
    pub fn link(&self) -> Result<String, JsValue> {
        self.page()?.link().map_err(js_error)
    }

    /// Opens a glTF, GLB or OBJ file's bytes as the scene.
    pub fn load_file(&self, name: String, bytes: Vec<u8>) -> js_sys::Promise {
        let page = self.page.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut p = borrow(&page)?;
            p.open(&name, &bytes).await.map_err(js_error)?;
            Ok(JsValue::UNDEFINED)
        })
    }

    /// Light `light`'s mask of the last comparison, one byte a pixel
    /// (255 = lit), rows top first, in base64: what the test suite compares
    /// with the native build's mask of the same frame.
    pub fn compared_mask(&self, light: usize) -> Result<String, JsValue> {
        use base64::Engine as _;
        let p = self.page()?;
        let mask = p
            .compared_masks
            .get(light)
            .ok_or_else(|| JsValue::from_str("no comparison of that light has run"))?;
        let bytes: Vec<u8> = mask
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect();
        Ok(base64::engine::general_purpose::STANDARD.encode(bytes))
    }

    /// The adapter's name, type and backend.
    pub fn adapter(&self) -> Result<String, JsValue> {
        Ok(self.page()?.gpu.adapter_summary())
    }
}
