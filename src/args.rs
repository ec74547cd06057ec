//! Command-line arguments shared by the headless commands and the viewer:
//! which scene, camera, lights, frame size, backend and render settings.

use crate::gpu::GpuContext;
use crate::renderer::{LightingModel, MipFilter, RenderSettings, Shading};
use crate::scene::{self, Camera, Light, LightType, Scene};
use anyhow::{Result, anyhow, bail};
use clap::Args;
use glam::Vec3;

/// Scene, camera and light selection shared by the frame commands.
#[derive(Args, Clone, Debug)]
pub struct ViewArgs {
    /// Built-in scene name or a scene file (.obj, .gltf, .glb, .toml).
    #[arg(long, default_value = "room")]
    pub scene: String,
    /// Camera preset of the scene.
    #[arg(long)]
    pub camera: Option<String>,
    /// Camera position x,y,z (overrides the preset's).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Camera target x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Camera up vector x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f32>,
    /// Near plane distance.
    #[arg(long)]
    pub near: Option<f32>,
    /// Far plane distance.
    #[arg(long)]
    pub far: Option<f32>,
    /// Light preset of the scene (e.g. point, spot, sun).
    #[arg(long)]
    pub light: Option<String>,
    /// Replace the lights by one light of this type.
    #[arg(long, value_parser = ["point", "spot", "directional"])]
    pub light_type: Option<String>,
    /// Position of that light x,y,z (point, spot).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub light_pos: Option<Vec3>,
    /// Direction of that light x,y,z (spot, directional).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub light_dir: Option<Vec3>,
    /// Frame size WxH.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Graphics backend (vulkan, metal, dx12); default: WGPU_BACKEND or all.
    #[arg(long)]
    pub backend: Option<String>,
    /// Shading mode.
    #[arg(long, value_enum, default_value = "pixel")]
    pub shading: Shading,
    /// Specular model.
    #[arg(long, value_enum, default_value = "blinn-phong")]
    pub lighting: LightingModel,
    /// Draw back faces too (disable back-face culling).
    #[arg(long)]
    pub no_cull: bool,
    /// Background colour r,g,b (linear, 0-1).
    #[arg(long, value_parser = parse_vec3)]
    pub background: Option<Vec3>,
    /// Do not draw the light icons.
    #[arg(long)]
    pub no_icons: bool,
    /// GPU memory budget in MiB: a frame or a technique's shadow resources
    /// (maps × faces × format × moments) that would take more are refused
    /// with an error before anything is allocated.
    #[arg(long, value_name = "MIB", default_value_t = crate::gpu::DEFAULT_MEMORY_BUDGET_MIB,
          value_parser = clap::value_parser!(u64).range(1..=(1u64 << 24)))]
    pub memory_budget: u64,
    /// Anisotropic filtering of material textures, 1 (trilinear) to 16;
    /// default 8 on GPUs, 1 on CPU adapters such as lavapipe (where any
    /// anisotropy more than doubles the cost of the lighting pass).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=16))]
    pub anisotropy: Option<u16>,
    /// Mip-level blending of material textures (linear = trilinear);
    /// default linear on GPUs, nearest on CPU adapters; anisotropy above 1
    /// implies linear.
    #[arg(long, value_enum)]
    pub mip_filter: Option<MipFilter>,
}

pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected x,y,z numbers, got '{s}'"))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(format!("expected three finite numbers x,y,z, got '{s}'")),
    }
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got '{s}'"))?;
    let w: u32 = w.parse().map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height in '{s}'"))?;
    if w == 0 || h == 0 {
        return Err(format!("frame size must be at least 1x1, got '{s}'"));
    }
    Ok((w, h))
}

impl ViewArgs {
    /// Loads the scene and resolves the camera and lights.
    pub fn resolve(&self) -> Result<(Scene, Camera, Vec<Light>)> {
        let scene = scene::load(&self.scene)?;
        let mut camera = match &self.camera {
            Some(p) => scene.camera_preset(p)?,
            None => scene.camera,
        };
        camera.eye = self.eye.unwrap_or(camera.eye);
        camera.target = self.target.unwrap_or(camera.target);
        camera.up = self.up.unwrap_or(camera.up);
        camera.fov_y_deg = self.fov.unwrap_or(camera.fov_y_deg);
        camera.near = self.near.unwrap_or(camera.near);
        camera.far = self.far.unwrap_or(camera.far);
        if self.up.is_none() {
            camera = camera.with_usable_up();
        }
        camera.validate()?;
        if self.light.is_none() && self.light_type.is_none() {
            scene.warn_default_light();
        }
        let mut lights = match &self.light {
            Some(p) => scene.light_preset(p)?,
            None => scene.lights.clone(),
        };
        if let Some(t) = &self.light_type {
            let kind: LightType = t.parse()?;
            let need_pos = || {
                self.light_pos
                    .ok_or_else(|| anyhow!("--light-type {t} needs --light-pos"))
            };
            let need_dir = || {
                self.light_dir
                    .ok_or_else(|| anyhow!("--light-type {t} needs --light-dir"))
            };
            let light = match kind {
                LightType::Point => Light::point(need_pos()?, 1.0),
                LightType::Spot => {
                    let p = need_pos()?;
                    Light::spot(p, p + need_dir()?, 1.0, 22.0, 32.0)
                }
                LightType::Directional => Light::directional(need_dir()?, 1.0),
            };
            lights = vec![light];
        } else if self.light_pos.is_some() || self.light_dir.is_some() {
            bail!("--light-pos/--light-dir need --light-type");
        }
        for l in &lights {
            l.validate()?;
        }
        if lights.len() > crate::frame::MAX_LIGHTS {
            bail!(
                "{}: {} lights; at most {} are supported",
                scene.source,
                lights.len(),
                crate::frame::MAX_LIGHTS
            );
        }
        Ok((scene, camera, lights))
    }

    /// A headless GPU context on the chosen backend with the memory budget.
    pub fn gpu(&self) -> Result<GpuContext> {
        let mut gpu = GpuContext::new(self.backend.as_deref())?;
        gpu.memory_budget = self.memory_budget << 20;
        Ok(gpu)
    }

    pub fn settings(&self) -> RenderSettings {
        RenderSettings {
            shading: self.shading,
            lighting: self.lighting,
            cull_back_faces: !self.no_cull,
            background: self.background,
            show_light_icons: !self.no_icons,
            gpu_timing: false,
            stage_waits: false,
            feedback: Default::default(),
            anisotropy: self.anisotropy,
            mip_filter: self.mip_filter,
        }
    }
}
