//! The real-time renderer: a depth + G-buffer prepass, one visibility mask
//! per light written by that light's shadow technique (through
//! `dyn ShadowTechnique` only), and a forward lighting pass (depth test
//! EQUAL against the prepass) that composes
//! `ambient + Σ visibility × (diffuse + specular)`; light icons on top.
//! A frame writes one uniform buffer, records its passes and waits for the
//! GPU once (or after each stage when measuring, [`RenderSettings::stage_waits`]).

mod icons;
mod lighting;
mod lines;
mod overlay;
mod timing;

pub use lighting::LitKey;
use lighting::LitLights;
pub use timing::{FrameTimings, GpuPassTimes};

use crate::clock::Instant;
use crate::frame::{self, FrameLayouts, FrameTargets, MAX_LIGHTS, SceneGpu};
use crate::gpu::{GpuContext, WorkStage};
use crate::scene::{AlphaMode, Camera, Light, Scene};
use crate::technique::{Feedback, MaskContext, TechniqueInstance, TechniqueNeeds};
use anyhow::{Result, bail};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Shading modes of [004].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// One normal per face.
    Flat,
    /// Intensities per vertex, interpolated.
    Gouraud,
    /// Normals interpolated, lighting per pixel, normal maps applied.
    Pixel,
}

/// How material textures blend between mip levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum MipFilter {
    /// Bilinear within the nearest level (half the texel reads of linear).
    Nearest,
    /// Trilinear: bilinear in the two nearest levels, blended.
    Linear,
}

impl MipFilter {
    /// Linear (trilinear filtering) on GPUs; nearest on CPU adapters, where
    /// the second level's reads are shader time (on lavapipe about 3.5 ms
    /// of a 24 ms lighting pass on `room` at 1280×720).
    pub fn default_for(gpu: &GpuContext) -> MipFilter {
        if gpu.is_cpu_adapter() {
            MipFilter::Nearest
        } else {
            MipFilter::Linear
        }
    }
}

/// Specular model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum LightingModel {
    /// `(V·R)^n`
    Phong,
    /// `(N·H)^n`
    BlinnPhong,
}

/// Renderer-wide settings (not technique parameters).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct RenderSettings {
    pub shading: Shading,
    pub lighting: LightingModel,
    pub cull_back_faces: bool,
    /// Linear RGB; `None` takes the scene's.
    pub background: Option<Vec3>,
    pub show_light_icons: bool,
    /// Measure each pass with GPU timestamp queries (when the adapter has them).
    #[serde(default)]
    pub gpu_timing: bool,
    /// Wait for the GPU after each stage (prepass, masks, lighting) so that
    /// each stage's wall time is its own (`bench`); otherwise a frame is
    /// submitted and waited for once, and the GPU times are those of the
    /// last frame whose timestamps have arrived.
    #[serde(default)]
    pub stage_waits: bool,
    /// How techniques read back GPU results they need on the CPU: this
    /// frame's (waiting) or the latest arrived (the viewer, no stall).
    #[serde(default)]
    pub feedback: Feedback,
    /// Anisotropic filtering of material textures, 1 (trilinear) to 16;
    /// `None`: the device's default ([`GpuContext::default_anisotropy`]).
    #[serde(default)]
    pub anisotropy: Option<u16>,
    /// Mip-level blending of material textures; `None`: the device's
    /// default ([`MipFilter::default_for`]).
    #[serde(default)]
    pub mip_filter: Option<MipFilter>,
}

impl RenderSettings {
    /// The anisotropy the material textures are filtered with on `gpu`:
    /// the chosen one (1 to 16) or the device's default.
    pub fn texture_anisotropy(&self, gpu: &GpuContext) -> u16 {
        self.anisotropy
            .unwrap_or_else(|| gpu.default_anisotropy())
            .clamp(1, 16)
    }

    /// The mip filter the material textures are sampled with on `gpu`:
    /// linear whenever the anisotropy is above 1 (anisotropic filtering
    /// needs every filter linear), else the chosen one or the device's.
    pub fn texture_mip_filter(&self, gpu: &GpuContext) -> MipFilter {
        if self.texture_anisotropy(gpu) > 1 {
            return MipFilter::Linear;
        }
        self.mip_filter
            .unwrap_or_else(|| MipFilter::default_for(gpu))
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            shading: Shading::Pixel,
            lighting: LightingModel::BlinnPhong,
            cull_back_faces: true,
            background: None,
            show_light_icons: true,
            gpu_timing: false,
            stage_waits: false,
            feedback: Feedback::ThisFrame,
            anisotropy: None,
            mip_filter: None,
        }
    }
}

/// The camera a frame is seen from and the one its techniques fit their
/// light views to (the same but when measuring flicker).
#[derive(Clone, Copy)]
pub struct FrameCameras<'a> {
    pub view: &'a Camera,
    pub fit: &'a Camera,
}

/// The renderer's passes; their pipelines come from the device's cache.
pub struct Renderer {
    gbuffer_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    lighting: lighting::Lighting,
    icons: icons::LightIcons,
    lines: lines::LineRenderer,
    timer: Option<timing::GpuTimer>,
    /// The G-buffer seen from [`FrameCameras::fit`] where that is not the
    /// frame's camera ([`MaskContext::fit_frame`]); made on first use.
    fit_frame: Option<FrameTargets>,
}

impl Renderer {
    pub fn new(gpu: &GpuContext) -> Renderer {
        let device = &gpu.device;
        let layouts = FrameLayouts::of(gpu);
        let module = lighting::scene_module(gpu);
        let gbuffer_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(&layouts.frame), Some(&layouts.objects)],
            immediate_size: 0,
        });
        Renderer {
            lighting: lighting::Lighting::new(gpu, &layouts),
            icons: icons::LightIcons::new(gpu, &layouts.frame),
            lines: lines::LineRenderer::new(gpu, &layouts.frame),
            timer: gpu.timestamps.then(|| timing::GpuTimer::new(device)),
            fit_frame: None,
            gbuffer_layout,
            module,
        }
    }

    /// The prepass pipeline (back faces culled or not; `cutout`: the
    /// fragment stage drops the holes of cut-out surfaces).
    fn gbuffer_pipeline(
        &self,
        gpu: &GpuContext,
        cull_back_faces: bool,
        cutout: bool,
    ) -> wgpu::RenderPipeline {
        gpu.cache
            .render_pipeline("prepass", &(cull_back_faces, cutout), || {
                gpu.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("gbuffer"),
                        layout: Some(&self.gbuffer_layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some("vs_gbuffer"),
                            compilation_options: Default::default(),
                            buffers: &[Some(frame::VERTEX_LAYOUT)],
                        },
                        primitive: wgpu::PrimitiveState {
                            cull_mode: cull_back_faces.then_some(wgpu::Face::Back),
                            ..Default::default()
                        },
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format: gpu.depth_format,
                            depth_write_enabled: Some(true),
                            depth_compare: Some(frame::DEPTH_NEARER),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        multisample: Default::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &self.module,
                            entry_point: Some(if cutout {
                                "fs_gbuffer_cutout"
                            } else {
                                "fs_gbuffer"
                            }),
                            compilation_options: Default::default(),
                            targets: &[
                                Some(frame::GBUFFER_POSITION_FORMAT.into()),
                                Some(frame::GBUFFER_NORMAL_FORMAT.into()),
                                Some(frame::GBUFFER_PART_FORMAT.into()),
                            ],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
            })
    }

    pub fn draw_lines(
        &self,
        gpu: &GpuContext,
        frame: &FrameTargets,
        lines: &[crate::technique::DebugLine],
    ) {
        self.lines.draw(gpu, frame, lines);
    }

    /// Renders one frame into the frame's colour target: prepass, one mask
    /// per light from `techniques[i]`, lighting, icons. The prepass is
    /// submitted on its own (CPU techniques read the G-buffer back while
    /// recording their masks); masks and lighting follow in one submission,
    /// and the frame waits for the GPU once at its end.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        frame: &mut FrameTargets,
        camera: &Camera,
        lights: &[Light],
        techniques: &mut [TechniqueInstance],
        settings: &RenderSettings,
    ) -> Result<FrameTimings> {
        let cameras = FrameCameras {
            view: camera,
            fit: camera,
        };
        self.render_fitted(
            gpu, scene, scene_gpu, frame, cameras, lights, techniques, settings,
        )
    }

    /// As [`Renderer::render`], with the techniques' light views fitted to
    /// `cameras.fit` while the frame is seen from `cameras.view`.
    #[allow(clippy::too_many_arguments)]
    pub fn render_fitted(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        frame: &mut FrameTargets,
        cameras: FrameCameras,
        lights: &[Light],
        techniques: &mut [TechniqueInstance],
        settings: &RenderSettings,
    ) -> Result<FrameTimings> {
        let camera = cameras.view;
        check_frame(camera, lights, techniques)?;
        let t0 = Instant::now();
        let needs = TechniqueNeeds::of(&techniques[..lights.len()]);
        let (width, height) = (frame.width(), frame.height());
        let uniform_of = |seen_by: &Camera| {
            frame::frame_uniform(
                scene,
                seen_by,
                lights,
                needs.infinite_far_plane,
                width,
                height,
            )
        };
        frame.set_uniform(gpu, uniform_of(camera));
        let queries = match self.timer.as_mut() {
            Some(t) if settings.gpu_timing => Some(t.begin_frame()),
            _ => None,
        };
        let stamp = |enc: &mut wgpu::CommandEncoder, pair: u32, end: bool| {
            if let Some(q) = &queries {
                q.stamp(enc, pair, end);
            }
        };
        let stage_wait = || -> Result<Instant> {
            if settings.stage_waits {
                gpu.wait_idle()?;
            }
            Ok(Instant::now())
        };

        let mut enc = gpu.device.create_command_encoder(&Default::default());
        gpu.set_work_stage(WorkStage::Prepass);
        stamp(&mut enc, timing::PREPASS, false);
        self.record_prepass(gpu, &mut enc, scene_gpu, frame, settings);
        stamp(&mut enc, timing::PREPASS, true);
        gpu.queue.submit([enc.finish()]);
        let separate_fit = cameras.fit != camera;
        if separate_fit {
            self.render_fit_prepass(gpu, scene_gpu, frame, uniform_of(cameras.fit), settings)?;
        }
        let t1 = stage_wait()?;

        let mut enc = gpu.device.create_command_encoder(&Default::default());
        gpu.set_work_stage(WorkStage::Masks);
        stamp(&mut enc, timing::MASKS, false);
        let fit_frame = match &self.fit_frame {
            Some(f) if separate_fit => f,
            _ => frame,
        };
        for (i, light) in lights.iter().enumerate() {
            let ctx = MaskContext {
                gpu,
                scene,
                scene_gpu,
                frame,
                light_index: i,
                light,
                camera,
                fit_camera: cameras.fit,
                fit_frame,
                target: frame.mask_layer(i),
                feedback: settings.feedback,
            };
            techniques[i].technique.render_mask(&ctx, &mut enc)?;
        }
        stamp(&mut enc, timing::MASKS, true);
        let t2 = if settings.stage_waits {
            gpu.queue.submit([enc.finish()]);
            enc = gpu.device.create_command_encoder(&Default::default());
            stage_wait()?
        } else {
            Instant::now()
        };
        gpu.set_work_stage(WorkStage::Lighting);
        stamp(&mut enc, timing::LIGHTING, false);
        let lit = LitLights::of(lights, &needs.compose);
        self.record_lighting(
            gpu, &mut enc, scene, scene_gpu, frame, lights, lit, settings,
        );
        stamp(&mut enc, timing::LIGHTING, true);
        if let Some(t) = self.timer.as_mut().filter(|_| settings.gpu_timing) {
            t.resolve(&mut enc);
        }
        gpu.queue.submit([enc.finish()]);
        if let Some(t) = self.timer.as_mut().filter(|_| settings.gpu_timing) {
            t.request_readback();
        }
        gpu.wait_idle()?;
        let t3 = Instant::now();
        for inst in techniques.iter_mut().take(lights.len()) {
            inst.technique.after_frame(gpu)?;
        }
        let gpu_times = match self.timer.as_mut().filter(|_| settings.gpu_timing) {
            Some(t) => t.latest(gpu)?,
            None => None,
        };
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        Ok(FrameTimings {
            prepass_ms: ms(t0, t1),
            masks_ms: ms(t1, t2),
            lighting_ms: ms(t2, t3),
            total_ms: ms(t0, t3),
            gpu: gpu_times,
        })
    }

    /// The prepass seen from the fit camera (`uniform`) into
    /// [`Renderer::fit_frame`], sized as `frame`: what the camera the light
    /// views are fitted to sees, for fits to the pixels seen (SDSM's
    /// reduction).
    fn render_fit_prepass(
        &mut self,
        gpu: &GpuContext,
        scene_gpu: &SceneGpu,
        frame: &FrameTargets,
        uniform: frame::FrameUniform,
        settings: &RenderSettings,
    ) -> Result<()> {
        let (w, h) = (frame.width(), frame.height());
        let mut fit_frame = match self.fit_frame.take() {
            Some(f) if (f.width(), f.height()) == (w, h) => f,
            _ => FrameTargets::new(gpu, w, h)?,
        };
        fit_frame.set_uniform(gpu, uniform);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.record_prepass(gpu, &mut enc, scene_gpu, &fit_frame, settings);
        gpu.queue.submit([enc.finish()]);
        self.fit_frame = Some(fit_frame);
        Ok(())
    }

    /// Depth, stencil (cleared) and G-buffer (position, normal, convex
    /// part) of every object.
    fn record_prepass(
        &self,
        gpu: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        scene_gpu: &SceneGpu,
        frame: &FrameTargets,
        settings: &RenderSettings,
    ) {
        let [position, normal] = frame.gbuffer_views();
        let mut pass = gpu.render_pass(
            enc,
            &wgpu::RenderPassDescriptor {
                label: Some("prepass"),
                color_attachments: &[
                    Some(color_attachment(position, wgpu::Color::TRANSPARENT)),
                    Some(color_attachment(normal, wgpu::Color::TRANSPARENT)),
                    Some(color_attachment(
                        frame.gbuffer_part_view(),
                        wgpu::Color::TRANSPARENT,
                    )),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: frame.depth_view(),
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(frame::DEPTH_CLEAR),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0),
                        store: wgpu::StoreOp::Store,
                    }),
                }),
                ..Default::default()
            },
        );
        pass.set_bind_group(frame::FRAME_GROUP, frame.frame_bind_group(), &[]);
        pass.set_bind_group(frame::OBJECTS_GROUP, &scene_gpu.object_bind_group, &[]);
        // Translucent surfaces are not in the G-buffer: what lies behind
        // them receives the shadows (the lighting pass blends them over).
        for alpha in [AlphaMode::Opaque, AlphaMode::Mask] {
            let cutout = alpha == AlphaMode::Mask;
            pass.set_pipeline(&self.gbuffer_pipeline(gpu, settings.cull_back_faces, cutout));
            scene_gpu.draw_objects(&mut pass, |d| d.alpha_mode == alpha);
        }
    }

    /// The lighting pass over the prepass's depth, then the light icons.
    #[allow(clippy::too_many_arguments)]
    fn record_lighting(
        &self,
        gpu: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        frame: &FrameTargets,
        lights: &[Light],
        lit: LitLights,
        settings: &RenderSettings,
    ) {
        let bg = settings.background.unwrap_or(scene.background);
        let mut pass = gpu.render_pass(
            enc,
            &wgpu::RenderPassDescriptor {
                label: Some("lighting"),
                color_attachments: &[Some(color_attachment(
                    frame.color_view(),
                    wgpu::Color {
                        r: bg.x as f64,
                        g: bg.y as f64,
                        b: bg.z as f64,
                        a: 1.0,
                    },
                ))],
                depth_stencil_attachment: Some(frame.kept_depth()),
                ..Default::default()
            },
        );
        self.lighting
            .draw(gpu, &mut pass, scene_gpu, frame, lit, settings);
        if settings.show_light_icons {
            self.icons
                .draw(gpu, &mut pass, frame, lights, &scene_gpu.bounds);
        }
    }
}

fn color_attachment(
    view: &wgpu::TextureView,
    clear: wgpu::Color,
) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            store: wgpu::StoreOp::Store,
        },
    }
}
/// A frame's inputs that no pass can draw: more lights than the lighting
/// pass takes, a light without a technique, a bad camera or light.
fn check_frame(camera: &Camera, lights: &[Light], techniques: &[TechniqueInstance]) -> Result<()> {
    if lights.len() > MAX_LIGHTS {
        bail!(
            "{} lights given; at most {MAX_LIGHTS} are supported",
            lights.len()
        );
    }
    if techniques.len() < lights.len() {
        bail!("one technique instance per light is needed");
    }
    camera.validate()?;
    for l in lights {
        l.validate()?;
    }
    Ok(())
}
