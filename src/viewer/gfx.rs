//! The viewer's window and everything that needs it: surface, device,
//! renderer, frame targets, blit and egui.

use super::blit::{self, Blit, EguiLayer};
use super::compose::{Composer, Composite, WindowTarget};
use crate::args::ViewArgs;
use crate::frame::FrameTargets;
use crate::gpu::GpuContext;
use crate::renderer::Renderer;
use anyhow::{Context as _, Result, anyhow};
use std::sync::Arc;
use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// egui's output for one frame, tessellated and ready to draw.
pub(super) struct UiFrame {
    pub jobs: Vec<egui::ClippedPrimitive>,
    pub pixels_per_point: f32,
    pub textures: egui::TexturesDelta,
}

/// Everything that needs the window.
pub(super) struct Gfx {
    pub window: Arc<Window>,
    pub surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    pub gpu: GpuContext,
    pub renderer: Renderer,
    pub frame: Option<FrameTargets>,
    /// The frame's colour format: the window's (sRGB view) where the window
    /// takes copies, so that the view reaches it by a plain copy.
    pub frame_color_format: wgpu::TextureFormat,
    pub blit: Blit,
    /// egui's panels, drawn when they change and blended over every frame.
    pub egui_layer: Option<EguiLayer>,
    pub egui_ctx: egui::Context,
    pub egui_state: egui_winit::State,
    pub egui_renderer: egui_wgpu::Renderer,
}

impl Gfx {
    /// Fits the surface to the window's `size` and the present mode to
    /// `vsync`, and the frame targets to `width`×`height` (the 3D view,
    /// supersampled), each only where it changed.
    pub fn fit(
        &mut self,
        size: PhysicalSize<u32>,
        vsync: bool,
        width: u32,
        height: u32,
    ) -> Result<()> {
        let mode = present_mode(vsync);
        if (
            self.config.width,
            self.config.height,
            self.config.present_mode,
        ) != (size.width, size.height, mode)
        {
            self.config.width = size.width;
            self.config.height = size.height;
            self.config.present_mode = mode;
            self.surface.configure(&self.gpu.device, &self.config);
        }
        if self
            .frame
            .as_ref()
            .is_none_or(|f| (f.width(), f.height()) != (width, height))
        {
            self.frame = Some(FrameTargets::with_color_format(
                &self.gpu,
                width,
                height,
                self.frame_color_format,
            )?);
        }
        Ok(())
    }

    /// Runs egui's pass over `build` (given the device, which the panels
    /// query) and hands the platform its output (cursor, clipboard).
    pub fn run_ui(&mut self, mut build: impl FnMut(&mut egui::Ui, &GpuContext)) -> UiFrame {
        let raw_input = self.egui_state.take_egui_input(&self.window);
        let gpu = &self.gpu;
        let output = self.egui_ctx.run_ui(raw_input, |ui| build(ui, gpu));
        self.egui_state
            .handle_platform_output(&self.window, output.platform_output);
        let pixels_per_point = output.pixels_per_point;
        UiFrame {
            jobs: self.egui_ctx.tessellate(output.shapes, pixels_per_point),
            pixels_per_point,
            textures: output.textures_delta,
        }
    }

    /// Draws the frame: egui's texture changes and its panel layer (redrawn
    /// only when they changed), then the 3D view right of `left` in the
    /// blit's `mode` (`blit::BLIT_*`, light, 0, 0) with the panels over it,
    /// into `screenshot` where given and into the window; submits and
    /// presents (a lost or outdated surface is reconfigured and this frame
    /// skipped).
    pub fn present(
        &mut self,
        mut ui: UiFrame,
        mode: [u32; 4],
        left: u32,
        screenshot: Option<&Composite>,
    ) {
        let size = (self.config.width, self.config.height);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: ui.pixels_per_point,
        };
        let textures_changed = !ui.textures.set.is_empty();
        for (id, deltas) in ui.textures.set.drain() {
            for delta in &deltas {
                self.egui_renderer
                    .update_texture(&self.gpu.device, &self.gpu.queue, id, delta);
            }
        }
        let plain = self.config.format;
        if self.egui_layer.as_ref().is_none_or(|l| l.size() != size) {
            self.egui_layer = Some(EguiLayer::new(&self.gpu.device, plain, size.0, size.1));
        }
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        let layer = self.egui_layer.as_mut().expect("created above");
        let cmd = layer.draw(
            &self.gpu,
            &mut self.egui_renderer,
            &mut enc,
            &ui.jobs,
            &screen,
            textures_changed,
        );
        let frame = self.frame.as_ref().expect("fitted before the frame");
        let mut composer = Composer {
            gpu: &self.gpu,
            blit: &mut self.blit,
            frame,
            layer: layer.view(),
            masks: frame.masks().create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            }),
            mode,
            left,
            size,
            panels: blit::primitives_bounds(&ui.jobs, ui.pixels_per_point, size.0, size.1),
            plain,
        };
        if let Some(c) = screenshot {
            composer.compose(&mut enc, c.target());
        }
        let surface_texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                None
            }
            _ => None,
        };
        if let Some(st) = &surface_texture {
            let srgb = st.texture.create_view(&wgpu::TextureViewDescriptor {
                format: Some(plain.add_srgb_suffix()),
                ..Default::default()
            });
            let plain = st.texture.create_view(&Default::default());
            composer.compose(
                &mut enc,
                WindowTarget {
                    texture: &st.texture,
                    srgb: &srgb,
                    plain: &plain,
                },
            );
        }
        self.gpu.queue.submit(cmd.into_iter().chain([enc.finish()]));
        if let Some(st) = surface_texture {
            self.window.pre_present_notify();
            self.gpu.queue.present(st);
        }
        for id in ui.textures.free.drain() {
            self.egui_renderer.free_texture(&id);
        }
    }

    /// Opens the window (`view.size`) on `view.backend`'s adapter and sets
    /// up its surface (plain format with its sRGB twin), renderer and egui.
    pub fn new(event_loop: &ActiveEventLoop, view: &ViewArgs, vsync: bool) -> Result<Gfx> {
        let (w, h) = view.size;
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title("shadowlab")
                        .with_inner_size(winit::dpi::PhysicalSize::new(w, h)),
                )
                .context("creating the window")?,
        );
        let backends = match view.backend.as_deref() {
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
        gpu.memory_budget = view.memory_budget << 20;
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
        config.present_mode = present_mode(vsync);
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
        Ok(Gfx {
            frame_color_format,
            blit: Blit::new(&gpu),
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
        })
    }
}

/// The surface's present mode for the vsync switch.
fn present_mode(vsync: bool) -> wgpu::PresentMode {
    if vsync {
        wgpu::PresentMode::AutoVsync
    } else {
        wgpu::PresentMode::AutoNoVsync
    }
}
