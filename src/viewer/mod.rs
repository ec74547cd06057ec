//! `shadowlab view`: the interactive viewer. A winit window rendered by the
//! same [`Renderer`] as the headless commands, with egui panels generated
//! from the technique registry and parameter tables.

mod blit;
mod compose;
mod dock;
mod gfx;
mod heatmap;
mod input;
mod ui;

use crate::args::ViewArgs;
use crate::frame::SceneGpu;
use crate::gpu::GpuContext;
use crate::headless;
use crate::measure::flicker::CameraPath;
use crate::renderer::{FrameTimings, MipFilter, RenderSettings};
use crate::scene::{self, Camera, Light, Scene};
use crate::technique::{self, TechniqueChoice, TechniqueInstance};
use anyhow::{Result, anyhow};
use compose::Composite;
use gfx::Gfx;
use glam::Vec2;
pub use heatmap::Heatmap;
use std::path::PathBuf;
use std::sync::{Arc, mpsc};
use std::time::Instant;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::KeyCode;

/// Options of `shadowlab view`.
/// Frame from which a long `--frames` run counts as warmed up.
const STEADY_FROM: u32 = 100;
/// Frames compared at the start and the end of a long `--frames` run.
const STEADY_WINDOW: u32 = 300;

pub struct ViewerOptions {
    pub view: ViewArgs,
    pub technique: String,
    pub set: Vec<String>,
    pub screenshot: Option<PathBuf>,
    pub frames: Option<u32>,
    pub vsync: bool,
    /// Compute the error heatmap of light 1 at start-up (with `frames`, the
    /// viewer waits for it before it exits).
    pub heatmap: bool,
    /// Start with the technique debug views on.
    pub debug_views: bool,
    /// Start showing this light's visibility mask instead of the image.
    pub mask: Option<usize>,
    /// Start moving the camera along this path.
    pub camera_path: Option<CameraPath>,
}

/// The camera moving along a path: where it started and the frame reached.
#[derive(Clone, Copy, Debug)]
pub struct PathMotion {
    pub path: CameraPath,
    pub start: crate::scene::Camera,
    pub frame: u32,
}

/// What the main view shows.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Overlay {
    Image,
    /// The visibility mask of light N, in grey.
    Mask(usize),
}

/// The scene being viewed and everything derived from it.
pub struct SceneState {
    pub scene: Arc<Scene>,
    pub scene_gpu: SceneGpu,
    pub camera: Camera,
    pub lights: Vec<Light>,
    /// One technique instance per light.
    pub techniques: Vec<TechniqueInstance>,
}

impl SceneState {
    fn load(
        gpu: &GpuContext,
        scene: Scene,
        camera: Camera,
        lights: Vec<Light>,
        choice: &TechniqueChoice,
    ) -> Result<SceneState> {
        let scene_gpu = SceneGpu::upload(gpu, &scene)?;
        let techniques = TechniqueInstance::per_light(gpu, choice, crate::frame::MAX_LIGHTS)?;
        Ok(SceneState {
            scene: Arc::new(scene),
            scene_gpu,
            camera,
            lights,
            techniques,
        })
    }
}

/// Viewer state shown and edited by the panels.
pub struct ViewerState {
    pub scene_name: String,
    pub settings: RenderSettings,
    pub vsync: bool,
    /// Supersampling factor of the 3D view (1 = off, 2 = 2×2).
    pub supersampling: u32,
    /// The device's texture anisotropy, shown until one is chosen.
    pub default_anisotropy: u16,
    /// The device's mip filter, shown until one is chosen.
    pub default_mip_filter: MipFilter,
    pub overlay: Overlay,
    pub selected_light: usize,
    pub same_technique_for_all: bool,
    pub show_panel: bool,
    /// The first frame has fitted the layout to the window (a small window
    /// starts with the panel folded to its toggle).
    pub layout_fitted: bool,
    pub show_help: bool,
    pub last_timings: Option<FrameTimings>,
    pub frame_times: std::collections::VecDeque<f64>,
    /// The statistics panel's text and when it was last refreshed.
    pub stats_lines: Vec<String>,
    pub stats_at: Option<Instant>,
    pub error: Option<String>,
    pub heatmap: Option<Heatmap>,
    pub heatmap_job: Option<mpsc::Receiver<Result<(egui::ColorImage, String), String>>>,
    pub screenshot_requested: bool,
    /// Left edge of the 3D view in physical pixels (the width of the panel).
    pub view_left: u32,
    /// The dock's rectangle in physical pixels while it is shown: presses
    /// there belong to the dock, not to the camera.
    pub dock_rect: Option<egui::Rect>,
    /// Show the selected light's technique debug views (frusta, depth map).
    pub show_debug: bool,
    /// The camera path being followed, one step per frame.
    pub camera_motion: Option<PathMotion>,
    /// The path the panel's selector shows (applied when it changes).
    pub camera_path: Option<CameraPath>,
    /// Whether the technique instances were told to prepare them.
    debug_enabled: bool,
    /// The technique's debug images as egui textures.
    pub debug_images: Vec<(String, egui::TextureHandle)>,
    pub pending_scene: Option<String>,
    pub message: Option<String>,
}

impl ViewerState {
    /// Whether the right-hand dock (heatmap, debug views, help) is shown.
    pub fn dock_open(&self) -> bool {
        self.show_help
            || self.heatmap.is_some()
            || (self.show_debug && !self.debug_images.is_empty())
    }

    /// Closes every view of the dock.
    pub fn close_dock(&mut self) {
        self.show_help = false;
        self.show_debug = false;
        self.heatmap = None;
    }
}

struct App {
    options: ViewerOptions,
    gfx: Option<Gfx>,
    scene: Option<SceneState>,
    state: ViewerState,
    /// The pointer in physical pixels of the window.
    pointer: Vec2,
    buttons: [bool; 3],
    dragging_light: Option<usize>,
    keys: std::collections::HashSet<KeyCode>,
    last_frame: Instant,
    frames_rendered: u32,
    started: Instant,
    first_frame_logged: bool,
    /// Frame at which the start-up heatmap was requested, until it arrives.
    heatmap_started_at: Option<u32>,
    heatmap_reported: bool,
    /// Seconds between redraws after the first frames, of a `--frames` run
    /// (a bounded one; an open-ended session keeps none).
    intervals: Vec<f64>,
    /// Resident memory at frame [`STEADY_FROM`] of a `--frames` run.
    resident_at_steady: Option<u64>,
    exit_error: Option<anyhow::Error>,
    /// The scene, camera, lights and technique, loaded and checked before
    /// a window opens (bad input fails fast, with or without a display).
    preloaded: Option<(Scene, Camera, Vec<Light>, TechniqueChoice)>,
}

/// Runs the viewer until the window closes (or `--frames` frames with `--screenshot`).
pub fn run(options: ViewerOptions) -> Result<()> {
    let started = Instant::now();
    let (scene, camera, lights) = options.view.resolve()?;
    if let Some(m) = options.mask.filter(|&m| m >= lights.len()) {
        anyhow::bail!(
            "--mask {m}: there are {} light(s), numbered from 0",
            lights.len()
        );
    }
    let mut choice = technique::parse_choice(&options.technique)?;
    technique::apply_settings(&mut choice.params, &options.set)?;
    technique::warn_without_effect(&choice, &options.set, &lights);
    let preloaded = Some((scene, camera, lights, choice));
    let event_loop = EventLoop::new().map_err(|e| anyhow!("cannot open a window (no display? set DISPLAY or WAYLAND_DISPLAY, or run under xvfb-run): {e}"))?;
    let scene_name = options.view.scene.clone();
    let mut app = App {
        state: ViewerState {
            scene_name,
            settings: RenderSettings {
                gpu_timing: true,
                // The viewer never waits for a technique's read-back.
                feedback: crate::technique::Feedback::PreviousFrame,
                ..options.view.settings()
            },
            vsync: options.vsync,
            supersampling: 1,
            default_anisotropy: 1,
            default_mip_filter: MipFilter::Linear,
            overlay: options.mask.map_or(Overlay::Image, Overlay::Mask),
            selected_light: 0,
            same_technique_for_all: true,
            show_panel: true,
            layout_fitted: false,
            show_help: false,
            last_timings: None,
            frame_times: Default::default(),
            stats_lines: vec![],
            stats_at: None,
            error: None,
            heatmap: None,
            heatmap_job: None,
            screenshot_requested: false,
            view_left: 0,
            dock_rect: None,
            show_debug: options.debug_views,
            camera_motion: None,
            camera_path: options.camera_path,
            debug_enabled: false,
            debug_images: vec![],
            pending_scene: None,
            message: None,
        },
        options,
        gfx: None,
        scene: None,
        pointer: Vec2::ZERO,
        buttons: [false; 3],
        dragging_light: None,
        keys: Default::default(),
        last_frame: Instant::now(),
        frames_rendered: 0,
        started,
        first_frame_logged: false,
        heatmap_started_at: None,
        heatmap_reported: false,
        intervals: vec![],
        resident_at_steady: None,
        exit_error: None,
        preloaded,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("event loop: {e}"))?;
    match app.exit_error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

impl App {
    fn init(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let gfx = Gfx::new(event_loop, &self.options.view, self.state.vsync)?;
        self.state.default_anisotropy = gfx.gpu.default_anisotropy();
        self.state.default_mip_filter = MipFilter::default_for(&gfx.gpu);
        let (scene, camera, lights, choice) = self
            .preloaded
            .take()
            .ok_or_else(|| anyhow!("the viewer's window was created twice"))?;
        self.scene = Some(SceneState::load(&gfx.gpu, scene, camera, lights, &choice)?);
        self.gfx = Some(gfx);
        Ok(())
    }

    fn switch_scene(&mut self, name: &str) -> Result<()> {
        let (Some(gfx), Some(old)) = (&self.gfx, &self.scene) else {
            return Ok(());
        };
        let scene = scene::load(name)?;
        scene.warn_default_light();
        let choice = old.techniques[0].choice.clone();
        let (camera, lights) = (scene.camera, scene.lights.clone());
        self.scene = Some(SceneState::load(&gfx.gpu, scene, camera, lights, &choice)?);
        self.state.scene_name = name.to_string();
        self.state.heatmap = None;
        self.state.selected_light = 0;
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let now = Instant::now();
        let interval = (now - self.last_frame).as_secs_f64();
        let dt = interval.min(0.1) as f32;
        self.last_frame = now;
        if let Some(name) = self.state.pending_scene.take()
            && let Err(e) = self.switch_scene(&name)
        {
            self.state.error = Some(format!("{e:#}"));
        }
        self.update_camera(dt);
        self.poll_heatmap();
        let (Some(gfx), Some(scene)) = (&mut self.gfx, &mut self.scene) else {
            return Ok(());
        };
        let size = gfx.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(()); // minimised
        }
        let ss = self.state.supersampling.max(1);
        let left = self.state.view_left.min(size.width - 1);
        gfx.fit(
            size,
            self.state.vsync,
            (size.width - left) * ss,
            size.height * ss,
        )?;
        scene.render(gfx, &mut self.state);
        let mut actions = ui::Actions::default();
        let ui_frame = gfx.run_ui(|ui_root, gpu| {
            ui::build(ui_root, &mut self.state, scene, gpu, &mut actions);
        });
        let nl = scene.lights.len();
        let mode = match self.state.overlay {
            Overlay::Mask(l) if l < nl => [blit::BLIT_MASK, l as u32, 0, 0],
            _ if ss == 1 => [blit::BLIT_COPY, 0, 0, 0],
            _ => [blit::BLIT_FILTERED, 0, 0, 0],
        };
        // The last frame of --frames (after the start-up heatmap when one
        // was asked for) takes --screenshot's picture; the key, any frame's.
        let heatmap_pending = self.options.heatmap && !self.heatmap_reported;
        let done = self
            .options
            .frames
            .is_some_and(|n| self.frames_rendered + 1 >= n)
            && !heatmap_pending;
        let auto_path = self.options.screenshot.clone().filter(|_| done);
        let screenshot = (self.state.screenshot_requested || auto_path.is_some()).then(|| {
            Composite::new(
                &gfx.gpu.device,
                (size.width, size.height),
                gfx.config.format,
            )
        });
        gfx.present(ui_frame, mode, left, screenshot.as_ref());
        self.frames_rendered += 1;
        if !self.first_frame_logged {
            self.first_frame_logged = true;
            let ms = self.started.elapsed().as_secs_f64() * 1e3;
            log::info!("viewer start-up: first frame after {ms:.0} ms");
            println!("start-up: first frame after {ms:.0} ms");
        }
        if self.options.heatmap && self.frames_rendered == 1 {
            self.heatmap_started_at = Some(self.frames_rendered);
            actions.heatmap = true;
        }
        if let Some(composite) = &screenshot {
            self.state.screenshot_requested = false;
            let path = auto_path
                .unwrap_or_else(|| PathBuf::from(format!("shadowlab-{}.png", chrono_stamp())));
            save_screenshot(gfx, scene, &self.state, composite, &path)?;
            self.state.message = Some(format!("saved {}", path.display()));
            println!("screenshot: {}", path.display());
        }
        if self.frames_rendered > 3 && self.options.frames.is_some() {
            self.intervals.push(interval);
        }
        if self.frames_rendered == STEADY_FROM && self.options.frames.is_some() {
            self.resident_at_steady = crate::measure::soak::resident_bytes();
        }
        if done {
            self.finish(event_loop);
        }
        if actions.heatmap {
            self.start_heatmap();
        }
        if let Some(name) = actions.switch_scene {
            self.state.pending_scene = Some(name);
        }
        Ok(())
    }

    /// The end of a `--frames` run: what it showed and how fast, then exit.
    fn finish(&self, event_loop: &ActiveEventLoop) {
        if self.state.show_debug {
            println!("debug views: {} image(s)", self.state.debug_images.len());
        }
        if !self.intervals.is_empty() {
            let mean = self.intervals.iter().sum::<f64>() / self.intervals.len() as f64;
            println!(
                "viewer: {:.1} FPS ({:.1} ms per frame, window to window, over {} frames after the first 3)",
                1.0 / mean,
                mean * 1e3,
                self.intervals.len()
            );
            self.print_steadiness();
        }
        event_loop.exit();
    }

    /// For a long `--frames` run: the frame rate of frames
    /// [`STEADY_FROM`]..+300 against the last 300, and the resident memory
    /// gained after frame [`STEADY_FROM`].
    fn print_steadiness(&self) {
        let window = STEADY_WINDOW as usize;
        // Intervals start after the first 3 frames.
        let from = STEADY_FROM as usize - 3;
        if self.intervals.len() < from + 2 * window {
            return;
        }
        let fps = |v: &[f64]| v.len() as f64 / v.iter().sum::<f64>();
        let early = fps(&self.intervals[from..from + window]);
        let late = fps(&self.intervals[self.intervals.len() - window..]);
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        let memory = match (
            self.resident_at_steady,
            crate::measure::soak::resident_bytes(),
        ) {
            (Some(a), Some(b)) => format!(
                "; resident memory {:.1} MiB at frame {STEADY_FROM}, {:.1} MiB at the end ({:+.1})",
                mib(a),
                mib(b),
                mib(b) - mib(a)
            ),
            _ => String::new(),
        };
        println!(
            "viewer: steady: {early:.1} FPS over frames {STEADY_FROM}–{}, {late:.1} FPS over the last {window} ({:.2}×){memory}",
            STEADY_FROM + STEADY_WINDOW,
            late / early
        );
    }
}

impl SceneState {
    /// Renders the frame into `gfx`'s targets with `state`'s settings, and
    /// the selected light's debug views when they are on; the timings or the
    /// error go to `state`.
    fn render(&mut self, gfx: &mut Gfx, state: &mut ViewerState) {
        if state.show_debug != state.debug_enabled {
            for t in &mut self.techniques {
                t.technique.enable_debug(state.show_debug);
            }
            state.debug_enabled = state.show_debug;
            state.debug_images.clear();
        }
        let frame = gfx.frame.as_mut().expect("fitted before the frame");
        let nl = self.lights.len();
        let result = gfx.gpu.checked("rendering", || {
            gfx.renderer.render(
                &gfx.gpu,
                &self.scene,
                &self.scene_gpu,
                frame,
                &self.camera,
                &self.lights,
                &mut self.techniques[..nl.max(1)],
                &state.settings,
            )
        });
        let timings = match result {
            Ok(t) => t,
            Err(e) => {
                state.error = Some(format!("{e:#}"));
                return;
            }
        };
        state.frame_times.push_back(timings.total_ms);
        if state.frame_times.len() > 60 {
            state.frame_times.pop_front();
        }
        state.last_timings = Some(timings);
        state.error = None;
        if state.show_debug {
            let li = state.selected_light.min(nl.max(1) - 1);
            match self.techniques[li].technique.debug_views(&gfx.gpu) {
                Ok(views) => {
                    gfx.renderer.draw_lines(&gfx.gpu, frame, &views.lines);
                    state.debug_images = dock::debug_textures(&gfx.egui_ctx, views.images);
                }
                Err(e) => state.error = Some(format!("{e:#}")),
            }
        }
    }
}

/// Writes `composite` to `path` as a PNG and the frame's record beside it
/// (`path` with a .json extension: scene, camera, lights, techniques,
/// timings, as `render` writes).
fn save_screenshot(
    gfx: &Gfx,
    scene: &SceneState,
    state: &ViewerState,
    composite: &Composite,
    path: &std::path::Path,
) -> Result<()> {
    composite.save_png(&gfx.gpu, path)?;
    let timings = state.last_timings.clone().unwrap_or_default();
    let record = headless::FrameRecord {
        scene: &scene.scene,
        scene_gpu: &scene.scene_gpu,
        camera: &scene.camera,
        lights: &scene.lights,
        techniques: scene.techniques.iter().take(scene.lights.len()).collect(),
        settings: &state.settings,
        frame: gfx.frame.as_ref().expect("fitted before the frame"),
        timings: &timings,
        adapter: gfx.gpu.adapter_summary(),
        anisotropy: state.settings.texture_anisotropy(&gfx.gpu),
        mip_filter: state.settings.texture_mip_filter(&gfx.gpu),
        extra_timings: serde_json::json!({"supersampling": state.supersampling.max(1)}),
    };
    std::fs::write(
        path.with_extension("json"),
        serde_json::to_string_pretty(&headless::frame_json(&record))?,
    )?;
    Ok(())
}

/// Seconds since the Unix epoch, for screenshot names.
fn chrono_stamp() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}
