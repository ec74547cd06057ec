//! `shadowlab view`: the interactive viewer. A winit window rendered by the
//! same [`Renderer`] as the headless commands, with egui panels generated
//! from the technique registry and parameter tables.

mod blit;
mod orbit;
mod ui;

use crate::args::ViewArgs;
use crate::frame::{FrameTargets, SceneGpu};
use crate::gpu::GpuContext;
use crate::headless;
use crate::measure::flicker::{CameraPath, path_camera};
use crate::renderer::{FrameTimings, MipFilter, RenderSettings, Renderer};
use crate::scene::{self, Camera, Light, Scene};
use crate::technique::{self, TechniqueChoice, TechniqueInstance};
use anyhow::{Context as _, Result, anyhow};
use blit::{Blit, EguiLayer, LayerBlend};
use glam::Vec2;
use std::path::PathBuf;
use std::sync::{Arc, mpsc};
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Options of `shadowlab view`.
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

/// A window image holds sRGB-encoded bytes: the 3D view is written
/// through an sRGB view of it, egui (which blends in gamma space) through a
/// plain one. Frames are composed straight into the surface; a screenshot
/// composes the same frame once more into a texture that can be read.
struct WindowTarget<'a> {
    texture: &'a wgpu::Texture,
    srgb: &'a wgpu::TextureView,
    plain: &'a wgpu::TextureView,
}

/// The screenshot texture (the surface's format) with its two views.
struct Composite {
    texture: wgpu::Texture,
    srgb: wgpu::TextureView,
    plain: wgpu::TextureView,
}

/// What the main view shows.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Overlay {
    Image,
    /// The visibility mask of light N, in grey.
    Mask(usize),
}

/// A heatmap against `raytraced` computed on a background thread.
pub struct Heatmap {
    pub texture: egui::TextureHandle,
    pub summary: String,
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
        let techniques = (0..crate::frame::MAX_LIGHTS)
            .map(|_| TechniqueInstance::new(gpu, choice.clone()))
            .collect::<Result<_>>()?;
        Ok(SceneState {
            scene: Arc::new(scene),
            scene_gpu,
            camera,
            lights,
            techniques,
        })
    }
}

/// Everything that needs the window.
struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: GpuContext,
    renderer: Renderer,
    frame: Option<FrameTargets>,
    /// The frame's colour format: the window's (sRGB view) where the window
    /// takes copies, so that the view reaches it by a plain copy.
    frame_color_format: wgpu::TextureFormat,
    blit: Blit,
    /// egui's panels, drawn when they change and blended over every frame.
    egui_layer: Option<EguiLayer>,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
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

struct App {
    options: ViewerOptions,
    gfx: Option<Gfx>,
    scene: Option<SceneState>,
    state: ViewerState,
    cursor: Vec2,
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
    /// Seconds between redraws, after the first frames.
    intervals: Vec<f64>,
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
        cursor: Vec2::ZERO,
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
        let (w, h) = self.options.view.size;
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title("shadowlab")
                        .with_inner_size(winit::dpi::PhysicalSize::new(w, h)),
                )
                .context("creating the window")?,
        );
        let backends = match self.options.view.backend.as_deref() {
            Some(b) => crate::gpu::parse_backend(b)?,
            None => wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY),
        };
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle().with_env()
        });
        let surface = instance
            .create_surface(window.clone())
            .context("creating the window surface")?;
        let mut gpu = GpuContext::with_instance(instance, backends, Some(&surface))?;
        gpu.memory_budget = self.options.view.memory_budget << 20;
        self.state.default_anisotropy = gpu.default_anisotropy();
        self.state.default_mip_filter = MipFilter::default_for(&gpu);
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| anyhow!("the adapter cannot present to this window"))?;
        // The plain format with its sRGB twin as a view format.
        let caps = surface.get_capabilities(&gpu.adapter);
        if let Some(f) = caps.formats.iter().find(|f| f.is_srgb()) {
            config.format = f.remove_srgb_suffix();
        }
        config.view_formats = vec![config.format.add_srgb_suffix()];
        config.present_mode = present_mode(self.state.vsync);
        // The view is copied into the window when the window takes copies
        // in a colour format of frames; otherwise it is drawn (a blit).
        let frame_color_format = if caps.usages.contains(wgpu::TextureUsages::COPY_DST)
            && crate::frame::COLOR_FORMATS.contains(&config.format.add_srgb_suffix())
        {
            config.usage |= wgpu::TextureUsages::COPY_DST;
            config.format.add_srgb_suffix()
        } else {
            crate::frame::COLOR_FORMAT
        };
        surface.configure(&gpu.device, &config);
        crate::frame::check_formats(&gpu)?;
        let renderer = Renderer::new(&gpu);
        let (scene, camera, lights, choice) = self
            .preloaded
            .take()
            .ok_or_else(|| anyhow!("the viewer's window was created twice"))?;
        self.scene = Some(SceneState::load(&gpu, scene, camera, lights, &choice)?);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.max_texture_size() as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(
            &gpu.device,
            config.format,
            egui_wgpu::RendererOptions {
                // Dithering adds noise per pixel of every egui triangle:
                // measurable on CPU adapters, invisible on 8-bit panels.
                dithering: false,
                ..Default::default()
            },
        );
        self.gfx = Some(Gfx {
            frame_color_format,
            blit: Blit::new(&gpu.device),
            egui_layer: None,
            window,
            surface,
            config,
            gpu,
            renderer,
            frame: None,
            egui_ctx,
            egui_state,
            egui_renderer,
        });
        Ok(())
    }

    fn switch_scene(&mut self, name: &str) -> Result<()> {
        let (Some(gfx), Some(old)) = (&self.gfx, &self.scene) else {
            return Ok(());
        };
        let scene = scene::load(name)?;
        let choice = old.techniques[0].choice.clone();
        let (camera, lights) = (scene.camera, scene.lights.clone());
        self.scene = Some(SceneState::load(&gfx.gpu, scene, camera, lights, &choice)?);
        self.state.scene_name = name.to_string();
        self.state.heatmap = None;
        self.state.selected_light = 0;
        Ok(())
    }

    fn update_camera(&mut self, dt: f32) {
        let Some(s) = &mut self.scene else { return };
        // The path selector: (re)start from the current camera, or stop.
        let motion = &mut self.state.camera_motion;
        if motion.map(|m| m.path) != self.state.camera_path {
            *motion = self.state.camera_path.map(|path| PathMotion {
                path,
                start: s.camera,
                frame: 0,
            });
        }
        if let Some(m) = motion {
            m.frame += 1;
            s.camera = path_camera(&m.start, m.path, m.frame);
        }
        let speed = (s.camera.eye - s.camera.target).length().max(1.0) * dt;
        let k = |c: KeyCode| self.keys.contains(&c) as i32 as f32;
        let (f, r, u) = (
            k(KeyCode::KeyW) - k(KeyCode::KeyS),
            k(KeyCode::KeyD) - k(KeyCode::KeyA),
            k(KeyCode::KeyE) - k(KeyCode::KeyQ),
        );
        if f != 0.0 || r != 0.0 || u != 0.0 {
            orbit::fly(&mut s.camera, f * speed, r * speed, u * speed);
        }
        // Arrow keys and PageUp/PageDown move the selected light.
        let (lx, lz, ly) = (
            k(KeyCode::ArrowRight) - k(KeyCode::ArrowLeft),
            k(KeyCode::ArrowDown) - k(KeyCode::ArrowUp),
            k(KeyCode::PageUp) - k(KeyCode::PageDown),
        );
        if let Some(l) = s.lights.get_mut(self.state.selected_light)
            && (lx != 0.0 || ly != 0.0 || lz != 0.0)
        {
            l.position += glam::Vec3::new(lx, ly, lz) * speed * 0.5;
        }
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
        let (Some(gfx), Some(scene)) = (&mut self.gfx, &mut self.scene) else {
            return Ok(());
        };
        let size = gfx.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(()); // minimised
        }
        if (gfx.config.width, gfx.config.height) != (size.width, size.height) {
            gfx.config.width = size.width;
            gfx.config.height = size.height;
            gfx.surface.configure(&gfx.gpu.device, &gfx.config);
        }
        let wanted = gfx.config.present_mode;
        if wanted != present_mode(self.state.vsync) {
            gfx.config.present_mode = present_mode(self.state.vsync);
            gfx.surface.configure(&gfx.gpu.device, &gfx.config);
        }
        let ss = self.state.supersampling.max(1);
        let left = self.state.view_left.min(size.width - 1);
        let view_w = size.width - left;
        let (fw, fh) = (view_w * ss, size.height * ss);
        if gfx
            .frame
            .as_ref()
            .is_none_or(|f| (f.width(), f.height()) != (fw, fh))
        {
            gfx.frame = Some(FrameTargets::with_color_format(
                &gfx.gpu,
                fw,
                fh,
                gfx.frame_color_format,
            )?);
        }
        if self.state.show_debug != self.state.debug_enabled {
            for t in &mut scene.techniques {
                t.technique.enable_debug(self.state.show_debug);
            }
            self.state.debug_enabled = self.state.show_debug;
            self.state.debug_images.clear();
        }
        let frame = gfx.frame.as_mut().expect("created above");
        let nl = scene.lights.len();
        let result = gfx.gpu.checked("rendering", || {
            gfx.renderer.render(
                &gfx.gpu,
                &scene.scene,
                &scene.scene_gpu,
                frame,
                &scene.camera,
                &scene.lights,
                &mut scene.techniques[..nl.max(1)],
                &self.state.settings,
            )
        });
        match result {
            Ok(t) => {
                self.state.frame_times.push_back(t.total_ms);
                if self.state.frame_times.len() > 60 {
                    self.state.frame_times.pop_front();
                }
                self.state.last_timings = Some(t);
                self.state.error = None;
                if self.state.show_debug {
                    let li = self.state.selected_light.min(nl.max(1) - 1);
                    match scene.techniques[li].technique.debug_views(&gfx.gpu) {
                        Ok(views) => {
                            gfx.renderer.draw_lines(&gfx.gpu, frame, &views.lines);
                            self.state.debug_images = views
                                .images
                                .into_iter()
                                .map(|im| {
                                    let img = egui::ColorImage::from_rgba_unmultiplied(
                                        [im.width as usize, im.height as usize],
                                        &im.rgba,
                                    );
                                    (
                                        im.label,
                                        gfx.egui_ctx.load_texture(
                                            "technique debug",
                                            img,
                                            egui::TextureOptions::LINEAR,
                                        ),
                                    )
                                })
                                .collect();
                        }
                        Err(e) => self.state.error = Some(format!("{e:#}")),
                    }
                }
            }
            Err(e) => self.state.error = Some(format!("{e:#}")),
        }
        // Poll the heatmap job.
        if let Some(rx) = &self.state.heatmap_job {
            match rx.try_recv() {
                Ok(Ok((img, summary))) => {
                    let texture =
                        gfx.egui_ctx
                            .load_texture("heatmap", img, egui::TextureOptions::LINEAR);
                    if let Some(at) = self.heatmap_started_at.take() {
                        println!(
                            "heatmap: {summary} ({} frames rendered while it was computed)",
                            self.frames_rendered - at
                        );
                        self.heatmap_reported = true;
                    }
                    self.state.heatmap = Some(Heatmap { texture, summary });
                    self.state.heatmap_job = None;
                }
                Ok(Err(e)) => {
                    self.state.error = Some(e);
                    self.state.heatmap_job = None;
                }
                Err(mpsc::TryRecvError::Empty) => {}
                Err(mpsc::TryRecvError::Disconnected) => self.state.heatmap_job = None,
            }
        }

        // egui
        let raw_input = gfx.egui_state.take_egui_input(&gfx.window);
        let mut actions = ui::Actions::default();
        let mut full_output = gfx.egui_ctx.run_ui(raw_input, |ui_root| {
            ui::build(ui_root, &mut self.state, scene, &gfx.gpu, &mut actions);
        });
        gfx.egui_state
            .handle_platform_output(&gfx.window, full_output.platform_output);
        let ppp = full_output.pixels_per_point;
        let jobs = gfx.egui_ctx.tessellate(full_output.shapes, ppp);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.width, size.height],
            pixels_per_point: ppp,
        };
        let mut textures_delta = std::mem::take(&mut full_output.textures_delta);
        let textures_changed = !textures_delta.set.is_empty();
        for (id, deltas) in textures_delta.set.drain() {
            for delta in &deltas {
                gfx.egui_renderer
                    .update_texture(&gfx.gpu.device, &gfx.gpu.queue, id, delta);
            }
        }
        let frame = gfx.frame.as_ref().expect("created above");
        let mask_view = frame.masks().create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let mut enc = gfx.gpu.device.create_command_encoder(&Default::default());
        let mode = match self.state.overlay {
            Overlay::Mask(l) if l < nl => [blit::BLIT_MASK, l as u32, 0, 0],
            _ if ss == 1 => [blit::BLIT_COPY, 0, 0, 0],
            _ => [blit::BLIT_FILTERED, 0, 0, 0],
        };
        let view3d = [left as f32, 0.0, view_w as f32, size.height as f32];
        let plain = gfx.config.format;
        let srgb = plain.add_srgb_suffix();
        // egui's panels, drawn into their layer only when they changed.
        if gfx
            .egui_layer
            .as_ref()
            .is_none_or(|l| l.size() != (size.width, size.height))
        {
            gfx.egui_layer = Some(EguiLayer::new(
                &gfx.gpu.device,
                plain,
                size.width,
                size.height,
            ));
        }
        let layer = gfx.egui_layer.as_mut().expect("created above");
        let mut cmd = vec![];
        if layer.needs_drawing(&jobs, textures_changed) {
            cmd = gfx.egui_renderer.update_buffers(
                &gfx.gpu.device,
                &gfx.gpu.queue,
                &mut enc,
                &jobs,
                &screen,
            );
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: layer.view(),
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                })
                .forget_lifetime();
            gfx.egui_renderer.render(&mut pass, &jobs, &screen);
        }
        let layer = gfx.egui_layer.as_ref().expect("created above");
        let panels = blit::primitives_bounds(&jobs, ppp, size.width, size.height);
        // The view one texel per pixel in the window's format is copied (on
        // a CPU adapter a draw costs about as much as the prepass), the panels
        // left of it are drawn opaque and the panels over it blended.
        let copy_view = mode[0] == blit::BLIT_COPY && frame.color_format() == srgb;
        let mut compose = |enc: &mut wgpu::CommandEncoder, target: WindowTarget| {
            if copy_view {
                enc.copy_texture_to_texture(
                    frame.color().as_image_copy(),
                    wgpu::TexelCopyTextureInfo {
                        texture: target.texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d {
                            x: left,
                            y: 0,
                            z: 0,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    frame.color().size(),
                );
                if left > 0 {
                    let beside = [0, 0, left, size.height];
                    gfx.blit.draw_layer(
                        &gfx.gpu,
                        enc,
                        beside,
                        (target.plain, plain),
                        layer.view(),
                        &mask_view,
                        LayerBlend::Opaque,
                    );
                }
                if let Some(over) = panels.and_then(|r| blit::right_of(r, left)) {
                    gfx.blit.draw_layer(
                        &gfx.gpu,
                        enc,
                        over,
                        (target.plain, plain),
                        layer.view(),
                        &mask_view,
                        LayerBlend::Over,
                    );
                }
                return;
            }
            gfx.blit.draw(
                &gfx.gpu,
                enc,
                view3d,
                target.srgb,
                srgb,
                frame.color_view(),
                &mask_view,
                mode,
            );
            if let Some(rect) = panels {
                gfx.blit.draw_layer(
                    &gfx.gpu,
                    enc,
                    rect,
                    (target.plain, plain),
                    layer.view(),
                    &mask_view,
                    LayerBlend::Over,
                );
            }
        };
        // The screenshot of this frame, when one is due.
        let heatmap_pending = self.options.heatmap && !self.heatmap_reported;
        let done = self
            .options
            .frames
            .is_some_and(|n| self.frames_rendered + 1 >= n)
            && !heatmap_pending;
        let auto_path = self.options.screenshot.clone().filter(|_| done);
        let screenshot = (self.state.screenshot_requested || auto_path.is_some()).then(|| {
            let texture = gfx.gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: wgpu::Extent3d {
                    width: size.width,
                    height: size.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: plain,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                view_formats: &[srgb],
            });
            Composite {
                srgb: texture.create_view(&wgpu::TextureViewDescriptor {
                    format: Some(srgb),
                    ..Default::default()
                }),
                plain: texture.create_view(&Default::default()),
                texture,
            }
        });
        if let Some(c) = &screenshot {
            compose(
                &mut enc,
                WindowTarget {
                    texture: &c.texture,
                    srgb: &c.srgb,
                    plain: &c.plain,
                },
            );
        }
        let surface_texture = match gfx.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                gfx.surface.configure(&gfx.gpu.device, &gfx.config);
                None
            }
            _ => None,
        };
        if let Some(st) = &surface_texture {
            let view_srgb = st.texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(srgb),
                ..Default::default()
            });
            let view_plain = st.texture.create_view(&Default::default());
            compose(
                &mut enc,
                WindowTarget {
                    texture: &st.texture,
                    srgb: &view_srgb,
                    plain: &view_plain,
                },
            );
        }
        gfx.gpu.queue.submit(cmd.into_iter().chain([enc.finish()]));
        if let Some(st) = surface_texture {
            gfx.window.pre_present_notify();
            gfx.gpu.queue.present(st);
        }
        for id in textures_delta.free.drain() {
            gfx.egui_renderer.free_texture(&id);
        }
        self.frames_rendered += 1;
        if !self.first_frame_logged {
            self.first_frame_logged = true;
            log::info!(
                "viewer start-up: first frame after {:.0} ms",
                self.started.elapsed().as_secs_f64() * 1e3
            );
            println!(
                "start-up: first frame after {:.0} ms",
                self.started.elapsed().as_secs_f64() * 1e3
            );
        }

        if self.options.heatmap && self.frames_rendered == 1 {
            self.heatmap_started_at = Some(self.frames_rendered);
            actions.heatmap = true;
        }
        // Screenshots: the key, or --screenshot after --frames (and after
        // the start-up heatmap when one was asked for).
        if let Some(composite) = &screenshot {
            self.state.screenshot_requested = false;
            let path = auto_path
                .unwrap_or_else(|| PathBuf::from(format!("shadowlab-{}.png", chrono_stamp())));
            let mut rgba = gfx.gpu.read_texture(&composite.texture, 0, 4)?;
            if matches!(plain, wgpu::TextureFormat::Bgra8Unorm) {
                for p in rgba.chunks_exact_mut(4) {
                    p.swap(0, 2);
                }
            }
            image::save_buffer(
                &path,
                &rgba,
                size.width,
                size.height,
                image::ExtendedColorType::Rgba8,
            )
            .with_context(|| format!("writing {}", path.display()))?;
            let timings = self.state.last_timings.clone().unwrap_or_default();
            let record = headless::FrameRecord {
                scene: &scene.scene,
                scene_gpu: &scene.scene_gpu,
                camera: &scene.camera,
                lights: &scene.lights,
                techniques: scene.techniques.iter().take(nl).collect(),
                settings: &self.state.settings,
                frame,
                timings: &timings,
                adapter: gfx.gpu.adapter_summary(),
                anisotropy: self.state.settings.texture_anisotropy(&gfx.gpu),
                mip_filter: self.state.settings.texture_mip_filter(&gfx.gpu),
                extra_timings: serde_json::json!({"supersampling": ss}),
            };
            std::fs::write(
                path.with_extension("json"),
                serde_json::to_string_pretty(&headless::frame_json(&record))?,
            )?;
            self.state.message = Some(format!("saved {}", path.display()));
            println!("screenshot: {}", path.display());
        }
        if self.frames_rendered > 3 {
            self.intervals.push(interval);
        }
        if done && self.state.show_debug {
            println!("debug views: {} image(s)", self.state.debug_images.len());
        }
        if done {
            if !self.intervals.is_empty() {
                let mean = self.intervals.iter().sum::<f64>() / self.intervals.len() as f64;
                println!(
                    "viewer: {:.1} FPS ({:.1} ms per frame, window to window, over {} frames after the first 3)",
                    1.0 / mean,
                    mean * 1e3,
                    self.intervals.len()
                );
            }
            event_loop.exit();
        }
        if actions.heatmap {
            self.start_heatmap();
        }
        if let Some(name) = actions.switch_scene {
            self.state.pending_scene = Some(name);
        }
        Ok(())
    }

    /// Starts the heatmap of the selected light's mask against `raytraced`
    /// on a background thread (reads back the frame first).
    fn start_heatmap(&mut self) {
        let (Some(gfx), Some(scene)) = (&self.gfx, &self.scene) else {
            return;
        };
        let Some(frame) = &gfx.frame else { return };
        let li = self
            .state
            .selected_light
            .min(scene.lights.len().saturating_sub(1));
        let Some(light) = scene.lights.get(li).copied() else {
            return;
        };
        let read = || -> Result<FrameData> {
            Ok(FrameData {
                width: frame.width() as usize,
                height: frame.height() as usize,
                positions: gfx.gpu.read_texture(frame.gbuffer_position(), 0, 16)?,
                normals: gfx.gpu.read_texture(frame.gbuffer_normal(), 0, 8)?,
                mask: gfx.gpu.read_texture(frame.masks(), li as u32, 2)?,
                color: frame.read_color_rgba(&gfx.gpu)?,
            })
        };
        let data = match read() {
            Ok(d) => d,
            Err(e) => {
                self.state.error = Some(format!("{e:#}"));
                return;
            }
        };
        let scene_arc = scene.scene.clone();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(heatmap_job(&scene_arc, &light, &data));
        });
        self.state.heatmap_job = Some(rx);
    }
}

/// G-buffer, one light's mask and the colour image of a frame, read back.
struct FrameData {
    width: usize,
    height: usize,
    positions: Vec<u8>,
    normals: Vec<u8>,
    mask: Vec<u8>,
    color: Vec<u8>,
}

/// The work of the heatmap thread.
fn heatmap_job(
    scene: &Scene,
    light: &Light,
    data: &FrameData,
) -> Result<(egui::ColorImage, String), String> {
    let (w, h) = (data.width, data.height);
    let (pos, nrm, mask, color) = (&data.positions, &data.normals, &data.mask, &data.color);
    use crate::technique::raytraced::{ReferenceSettings, mask_from_gbuffer};
    let positions: &[[f32; 4]] = bytemuck::cast_slice(pos);
    let normals: Vec<glam::Vec3> = bytemuck::cast_slice::<u8, [half::f16; 4]>(nrm)
        .iter()
        .map(|n| glam::Vec3::new(n[0].to_f32(), n[1].to_f32(), n[2].to_f32()).normalize_or_zero())
        .collect();
    let test: Vec<f32> = bytemuck::cast_slice::<u8, half::f16>(mask)
        .iter()
        .map(|v| v.to_f32())
        .collect();
    let settings = ReferenceSettings::defaults();
    let bvh = settings
        .casters(scene, None)
        .map_err(|e| format!("{e:#}"))?;
    let reference = mask_from_gbuffer(
        &bvh,
        light,
        positions,
        &normals,
        settings.samples_for(light),
        settings.offset_ulps,
    );
    let considered: Vec<bool> = positions
        .iter()
        .zip(bytemuck::cast_slice::<u8, [half::f16; 4]>(nrm))
        .zip(&normals)
        .map(|((p, n), nv)| {
            p[3] > 0.5
                && n[3].to_f32() > 0.5
                && light.reaches(glam::Vec3::new(p[0], p[1], p[2]), *nv)
        })
        .collect();
    let m = crate::measure::quality::mask_metrics(w, h, &considered, &reference, &test);
    let rgba = crate::measure::quality::heatmap(color, &considered, &reference, &test);
    let summary = format!(
        "false shadow {:.3} %, false lit {:.3} % (edge {:.3} %, interior {:.3} %), MAE {:.4}",
        m.all.false_shadow_pct,
        m.all.false_lit_pct,
        m.edge.total_pct,
        m.interior.total_pct,
        m.mean_abs_error
    );
    Ok((
        egui::ColorImage::from_rgba_unmultiplied([w, h], &rgba),
        summary,
    ))
}

fn present_mode(vsync: bool) -> wgpu::PresentMode {
    if vsync {
        wgpu::PresentMode::AutoVsync
    } else {
        wgpu::PresentMode::AutoNoVsync
    }
}

/// Seconds since the Unix epoch, for screenshot names.
fn chrono_stamp() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none()
            && let Err(e) = self.init(event_loop)
        {
            self.exit_error = Some(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = &mut self.gfx else { return };
        let consumed = gfx.egui_state.on_window_event(&gfx.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.exit_error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                if event.state == ElementState::Pressed {
                    if !consumed && !gfx.egui_ctx.egui_wants_keyboard_input() {
                        self.keys.insert(code);
                        match code {
                            KeyCode::F12 | KeyCode::KeyP => self.state.screenshot_requested = true,
                            KeyCode::F1 => self.state.show_help = !self.state.show_help,
                            KeyCode::Tab => self.state.show_panel = !self.state.show_panel,
                            KeyCode::KeyM => {
                                self.state.overlay = match self.state.overlay {
                                    Overlay::Image => Overlay::Mask(self.state.selected_light),
                                    Overlay::Mask(_) => Overlay::Image,
                                }
                            }
                            KeyCode::KeyH => self.start_heatmap(),
                            KeyCode::Digit1
                            | KeyCode::Digit2
                            | KeyCode::Digit3
                            | KeyCode::Digit4 => {
                                let i = match code {
                                    KeyCode::Digit1 => 0,
                                    KeyCode::Digit2 => 1,
                                    KeyCode::Digit3 => 2,
                                    _ => 3,
                                };
                                if self.scene.as_ref().is_some_and(|s| i < s.lights.len()) {
                                    self.state.selected_light = i;
                                }
                            }
                            KeyCode::Escape => event_loop.exit(),
                            _ => {}
                        }
                    }
                } else {
                    self.keys.remove(&code);
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                // Cursor relative to the 3D view (right of the panel).
                let p = Vec2::new(
                    position.x as f32 - self.state.view_left as f32,
                    position.y as f32,
                );
                let d = p - self.cursor;
                self.cursor = p;
                let size = gfx.window.inner_size();
                let sz = Vec2::new(
                    size.width.saturating_sub(self.state.view_left).max(1) as f32,
                    size.height.max(1) as f32,
                );
                let Some(s) = &mut self.scene else { return };
                if let Some(li) = self.dragging_light {
                    let vp = s.camera.projection(sz.x / sz.y) * s.camera.view();
                    if let Some(l) = s.lights.get_mut(li)
                        && let Some(q) = orbit::drag_point(&s.camera, vp, sz, p, l.position)
                    {
                        l.position = q;
                    }
                } else if self.buttons[0] {
                    orbit::orbit(&mut s.camera, d.x / sz.y * 3.0, d.y / sz.y * 3.0);
                } else if self.buttons[2] {
                    orbit::pan(&mut s.camera, d.x / sz.y, d.y / sz.y);
                } else if self.buttons[1] {
                    orbit::zoom(&mut s.camera, (1.0 + d.y / sz.y * 2.0).max(0.1));
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let i = match button {
                    MouseButton::Left => 0,
                    MouseButton::Middle => 1,
                    MouseButton::Right => 2,
                    _ => return,
                };
                let pressed = state == ElementState::Pressed;
                if pressed && consumed {
                    return;
                }
                self.buttons[i] = pressed;
                if !pressed {
                    self.dragging_light = None;
                } else if i == 0 {
                    // Grab a light icon within 16 px of the cursor.
                    let size = gfx.window.inner_size();
                    let sz = Vec2::new(
                        size.width.saturating_sub(self.state.view_left).max(1) as f32,
                        size.height.max(1) as f32,
                    );
                    if let Some(s) = &self.scene {
                        let vp = s.camera.projection(sz.x / sz.y) * s.camera.view();
                        self.dragging_light = s.lights.iter().position(|l| {
                            l.kind != crate::scene::LightType::Directional
                                && orbit::project(vp, sz, l.position)
                                    .is_some_and(|q| q.distance(self.cursor) < 16.0)
                        });
                        if let Some(li) = self.dragging_light {
                            self.state.selected_light = li;
                        }
                    }
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let y = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(s) = &mut self.scene {
                    orbit::zoom(&mut s.camera, 0.9f32.powf(y));
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gfx) = &self.gfx {
            gfx.window.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, shapes};
    use crate::technique::raytraced::{ReferenceSettings, mask_from_gbuffer};
    use glam::{Mat4, Vec3};

    /// A floor at y = 30 and a box whose top edge, under a sun 3° above the
    /// horizon, casts a shadow boundary onto the floor; a one-row G-buffer
    /// of floor points across that boundary, 0.5 mm apart.
    fn grazing_boundary() -> (Scene, Light, Vec<[f32; 4]>, Vec<Vec3>) {
        let mut s = Scene::new("grazing");
        let grey = s.add_material(Material::color("grey", Vec3::splat(0.7)));
        let floor = s.add_mesh(shapes::plane(20.0, 20.0, 2));
        s.add_object(
            "Floor",
            floor,
            grey,
            Mat4::from_translation(Vec3::new(0.0, 30.0, 0.0)),
        );
        let cube = s.add_mesh(shapes::cuboid(Vec3::new(0.2, 0.1, 4.0)));
        s.add_object(
            "Box",
            cube,
            grey,
            Mat4::from_translation(Vec3::new(0.0, 30.0, 0.0)),
        );
        let angle = 3f32.to_radians();
        let light = Light::directional(Vec3::new(angle.cos(), -angle.sin(), 0.0), 1.0);
        s.lights = vec![light];
        s.finalize().unwrap();
        // The box's top edge at x = 0.1, height 0.05: the boundary lies
        // 0.05 / tan 3° past it.
        let boundary = 0.1 + 0.05 / angle.tan();
        let positions: Vec<[f32; 4]> = (0..400)
            .map(|i| [boundary - 0.1 + i as f32 * 0.0005, 30.0, 0.0, 1.0])
            .collect();
        let normals = vec![Vec3::Y; positions.len()];
        (s, light, positions, normals)
    }

    /// The heatmap measures a technique against the reference as `compare`
    /// does, with the reference's own ray offset: the ray-traced mask itself
    /// shows no error, although a different offset (the 512 ULPs once
    /// hard-coded here) moves this boundary by several samples.
    #[test]
    fn the_heatmap_uses_the_reference_settings() {
        let (scene, light, positions, normals) = grazing_boundary();
        let settings = ReferenceSettings::defaults();
        let bvh = settings.casters(&scene, None).unwrap();
        let mask = mask_from_gbuffer(&bvh, &light, &positions, &normals, 1, settings.offset_ulps);
        let other = mask_from_gbuffer(&bvh, &light, &positions, &normals, 1, 512.0);
        let moved = mask.iter().zip(&other).filter(|(a, b)| a != b).count();
        assert!(moved >= 5, "a 512-ULP offset moves {moved} samples");
        assert!(mask.contains(&0.0) && mask.contains(&1.0));
        let f16s = |v: &[f32]| -> Vec<u8> {
            v.iter()
                .flat_map(|x| half::f16::from_f32(*x).to_le_bytes())
                .collect()
        };
        let data = FrameData {
            width: positions.len(),
            height: 1,
            positions: bytemuck::cast_slice(&positions).to_vec(),
            normals: f16s(
                &normals
                    .iter()
                    .flat_map(|n| [n.x, n.y, n.z, 1.0])
                    .collect::<Vec<_>>(),
            ),
            mask: f16s(&mask),
            color: vec![128; positions.len() * 4],
        };
        let (_, summary) = heatmap_job(&scene, &light, &data).unwrap();
        assert!(
            summary.starts_with("false shadow 0.000 %, false lit 0.000 %"),
            "{summary}"
        );
        let data = FrameData {
            mask: f16s(&other),
            ..data
        };
        let (_, summary) = heatmap_job(&scene, &light, &data).unwrap();
        assert!(
            !summary.starts_with("false shadow 0.000 %, false lit 0.000 %"),
            "{summary}"
        );
    }
}
