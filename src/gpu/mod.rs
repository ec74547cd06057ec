//! GPU layer: the context (adapter selection — `--backend`, `WGPU_BACKEND`,
//! real GPUs before the CPU adapter — and device creation with the optional
//! features the techniques use), texture readback (waiting, and
//! [`readback`] without waiting), the per-device pipeline cache
//! ([`cache`]) and texture, bind-layout and shader helpers ([`helpers`]). It knows nothing of scenes, frames or techniques.

pub mod cache;
pub mod helpers;
pub mod live;
pub mod readback;
pub mod timestamps;
pub mod uniform_space;
#[cfg(test)]
pub mod wgsl_layout;
pub mod work;

pub use cache::{DeviceCache, PIPELINE_CACHE_BOUND};
pub use helpers::*;
pub use live::LiveResources;
pub use readback::{AsyncReadback, FrameFeedback};
pub use timestamps::{SectionTimer, Stamps, TimestampPairs};
pub use uniform_space::UniformSpace;
pub use work::{FrameWork, StageWork, WorkStage};

use anyhow::{Result, bail};

/// Raised when no adapter exists; the CLI maps it to exit code 2.
#[derive(Debug, thiserror::Error)]
#[error(
    "no graphics adapter found for backend(s) {backends}. Without a GPU, install Mesa's CPU \
     Vulkan driver (lavapipe): `sudo apt-get install mesa-vulkan-drivers` on Debian/Ubuntu; with a \
     GPU, install its Vulkan driver (e.g. `mesa-vulkan-drivers` for AMD/Intel, the NVIDIA \
     driver's Vulkan ICD), or choose another backend with --backend vulkan|metal|dx12"
)]
pub struct NoAdapter {
    pub backends: String,
}

/// Default of `--memory-budget`: the most GPU memory, in MiB, that one
/// frame's targets or one technique instance's shadow resources may take.
/// wgpu cannot query a device's memory; 4 GiB fits every GPU we target and
/// a 24 GiB machine running lavapipe.
pub const DEFAULT_MEMORY_BUDGET_MIB: u64 = 4096;

pub struct GpuContext {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Timestamp queries inside encoders are available.
    pub timestamps: bool,
    /// Pipeline-statistics queries are available.
    pub pipeline_statistics: bool,
    /// `unclipped_depth` (depth clamp) is available.
    pub depth_clamp: bool,
    /// The camera's depth-stencil format: 32-bit float depth where the
    /// adapter has `DEPTH32FLOAT_STENCIL8` (with the camera's reversed
    /// depth, nearly uniform relative precision to any distance), else
    /// `Depth24PlusStencil8`.
    pub depth_format: wgpu::TextureFormat,
    /// Where shaders read their parameter blocks from on this device.
    pub uniform_space: UniformSpace,
    /// Bytes one frame's targets or one technique instance's resources may
    /// take ([`GpuContext::check_allocation`]); `--memory-budget` sets it.
    pub memory_budget: u64,
    /// Pipelines and per-family resources shared by every user of the device.
    pub cache: DeviceCache,
    /// Times the CPU has waited for the GPU ([`GpuContext::waits`]).
    waits: std::sync::atomic::AtomicU64,
    /// The pipeline-statistics queries of a frame being counted
    /// ([`GpuContext::count_work`]).
    work: work::WorkCounter,
    /// Set by the device-lost callback: why the device was lost.
    lost: std::sync::Arc<std::sync::Mutex<Option<String>>>,
}

/// Parses a backend name as accepted by `--backend`.
pub fn parse_backend(name: &str) -> Result<wgpu::Backends> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "vulkan" | "vk" => wgpu::Backends::VULKAN,
        "gl" | "gles" | "opengl" => bail!(
            "the OpenGL backend is not built into shadowlab: wgpu's GL backend cannot render to Rgba32Float, the G-buffer's position format; use --backend vulkan (Mesa's lavapipe runs on any machine)"
        ),
        "metal" | "mtl" => wgpu::Backends::METAL,
        "dx12" | "d3d12" => wgpu::Backends::DX12,
        "all" | "auto" => wgpu::Backends::all(),
        _ => bail!("unknown backend '{name}' (valid: vulkan, metal, dx12, auto)"),
    })
}

fn rank(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// A texture's texels copied into a `MAP_READ` buffer
/// ([`GpuContext::copy_texture`]), rows padded.
pub struct TextureCopy {
    pub buffer: wgpu::Buffer,
    padded_row: usize,
    row: usize,
}

impl TextureCopy {
    /// The mapped buffer's bytes with the rows' padding dropped.
    pub fn unpad(&self, data: &[u8]) -> Vec<u8> {
        data.chunks(self.padded_row)
            .flat_map(|r| &r[..self.row])
            .copied()
            .collect()
    }
}

impl GpuContext {
    /// Creates a headless context. `backend` (from `--backend`) wins over the
    /// `WGPU_BACKEND` environment variable; among adapters a real GPU is
    /// preferred, then the CPU adapter (lavapipe).
    pub fn new(backend: Option<&str>) -> Result<GpuContext> {
        let explicit = match backend {
            Some(b) => Some(parse_backend(b)?),
            None => wgpu::Backends::from_env(),
        };
        let make = |backends| {
            wgpu::Instance::new(wgpu::InstanceDescriptor {
                backends,
                ..wgpu::InstanceDescriptor::new_without_display_handle().with_env()
            })
        };
        match explicit {
            Some(b) => Self::with_instance(make(b), b, None),
            // Vulkan/Metal/DX12 first; OpenGL only when none of them has an
            // adapter (probing GL prints EGL noise on headless machines).
            None => {
                Self::with_instance(make(wgpu::Backends::PRIMARY), wgpu::Backends::PRIMARY, None)
                    .or_else(|e| match e.downcast_ref::<NoAdapter>() {
                        Some(_) => Self::with_instance(
                            make(wgpu::Backends::GL),
                            wgpu::Backends::all(),
                            None,
                        ),
                        None => Err(e),
                    })
            }
        }
    }

    /// Runs `f` inside validation and out-of-memory error scopes and turns
    /// a captured wgpu error into an `Err` naming `what`.
    /// A lost device (driver reset, GPU removed, or destroyed) is an error
    /// too, before and after `f`.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn checked<T>(&self, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        self.check_not_lost(what)?;
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let r = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        self.check_not_lost(what)?;
        if let Some(e) = o {
            bail!(
                "{what}: the GPU is out of memory ({e}); choose smaller sizes, or set --memory-budget below the device's memory so that such requests are refused up front"
            );
        }
        if let Some(e) = v {
            bail!("{what}: {e}");
        }
        r
    }

    /// In the browser, where the scopes' results can only be awaited, `f`
    /// runs alone: the page awaits its own scopes around each frame.
    #[cfg(target_arch = "wasm32")]
    pub fn checked<T>(&self, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        self.check_not_lost(what)?;
        f()
    }

    /// An error once the device has been lost.
    pub fn check_not_lost(&self, what: &str) -> Result<()> {
        let lost = self.lost.lock().map(|l| l.clone()).unwrap_or(None);
        match lost {
            Some(why) => bail!(
                "{what}: the GPU device was lost ({why}); restart shadowlab (a driver reset or a removed GPU causes this)"
            ),
            None => Ok(()),
        }
    }

    /// Creates the context on `instance`, with an adapter that can present to
    /// `surface` when one is given (the viewer).
    pub fn with_instance(
        instance: wgpu::Instance,
        backends: wgpu::Backends,
        surface: Option<&wgpu::Surface>,
    ) -> Result<GpuContext> {
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        if let Some(s) = surface {
            adapters.retain(|a| a.is_surface_supported(s));
        }
        adapters.sort_by_key(|a| rank(a.get_info().device_type));
        let Some(adapter) = adapters.into_iter().next() else {
            return Err(NoAdapter {
                backends: format!("{backends:?}"),
            }
            .into());
        };
        pollster::block_on(Self::from_adapter(instance, adapter))
    }

    /// Creates the context on `adapter` with the optional features the
    /// techniques use (awaited: the browser build cannot block).
    pub async fn from_adapter(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
    ) -> Result<GpuContext> {
        let info = adapter.get_info();
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::PIPELINE_STATISTICS_QUERY
            | wgpu::Features::DEPTH_CLIP_CONTROL
            | wgpu::Features::DEPTH32FLOAT_STENCIL8
            | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        let features = adapter.features() & wanted;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("shadowlab"),
                required_features: features,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await?;
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            log::error!("wgpu: {e}");
        }));
        let lost = std::sync::Arc::new(std::sync::Mutex::new(None));
        let lost_writer = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            log::error!("GPU device lost ({reason:?}): {message}");
            if let Ok(mut l) = lost_writer.lock() {
                *l = Some(format!("{reason:?}: {message}"));
            }
        });
        log::info!(
            "adapter: {} ({:?}, {:?}, driver {} {})",
            info.name,
            info.device_type,
            info.backend,
            info.driver,
            info.driver_info
        );
        Ok(GpuContext {
            timestamps: features.contains(
                wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
            ),
            pipeline_statistics: features.contains(wgpu::Features::PIPELINE_STATISTICS_QUERY),
            depth_clamp: features.contains(wgpu::Features::DEPTH_CLIP_CONTROL),
            depth_format: if features.contains(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
                wgpu::TextureFormat::Depth32FloatStencil8
            } else {
                log::info!("no DEPTH32FLOAT_STENCIL8: the camera's depth is Depth24PlusStencil8");
                wgpu::TextureFormat::Depth24PlusStencil8
            },
            uniform_space: UniformSpace::for_adapter(&info),
            memory_budget: DEFAULT_MEMORY_BUDGET_MIB << 20,
            cache: DeviceCache::default(),
            waits: Default::default(),
            work: Default::default(),
            lost,
            instance,
            adapter,
            device,
            queue,
            info,
        })
    }

    /// Anisotropic filtering of material textures when none is asked for:
    /// 8 on GPUs; 1 (trilinear only) on CPU adapters, where every extra
    /// sample costs shader time (on lavapipe any anisotropy more than
    /// doubles the lighting pass of `room`).
    pub fn default_anisotropy(&self) -> u16 {
        if self.is_cpu_adapter() { 1 } else { 8 }
    }

    /// Whether the adapter rasterises on the CPU (lavapipe, WARP, SwiftShader).
    pub fn is_cpu_adapter(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// One-line description of the adapter for logs and frame.json.
    pub fn adapter_summary(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.device_type, self.info.backend
        )
    }

    /// Refuses, before anything is allocated, a set of `layers` square or
    /// rectangular 2D textures of `width × height` texels taking `bytes` in
    /// all, when a side or the layer count exceeds the device's limits or the
    /// bytes exceed the memory budget. `what` names the resource and the
    /// parameter that sets its size.
    pub fn check_allocation(
        &self,
        what: &str,
        (width, height, layers): (u32, u32, u32),
        bytes: u64,
    ) -> Result<()> {
        let limits = self.device.limits();
        let max = limits.max_texture_dimension_2d;
        if width > max || height > max {
            bail!(
                "{what}: {width}x{height} texels exceed the device's largest texture ({max}x{max})"
            );
        }
        if layers > limits.max_texture_array_layers {
            bail!(
                "{what}: {layers} layers exceed the device's limit of {}",
                limits.max_texture_array_layers
            );
        }
        if bytes > self.memory_budget {
            bail!(
                "{what}: needs {:.1} MiB, more than the memory budget of {} MiB (raise it with --memory-budget MIB, or choose a smaller size)",
                bytes as f64 / (1u64 << 20) as f64,
                self.memory_budget >> 20
            );
        }
        Ok(())
    }

    /// An error unless the adapter can render to `format` (`what` says what
    /// for): wgpu's GL backend, for one, cannot render to 32-bit float
    /// colour targets.
    pub fn require_renderable(&self, format: wgpu::TextureFormat, what: &str) -> Result<()> {
        let features = self.device.features();
        let usages = if features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
        {
            self.adapter.get_texture_format_features(format)
        } else {
            format.guaranteed_format_features(features)
        }
        .allowed_usages;
        if !usages.contains(wgpu::TextureUsages::RENDER_ATTACHMENT) {
            bail!(
                "the {:?} adapter '{}' cannot render to {format:?}, the format of {what}; choose another backend (--backend vulkan: Mesa's lavapipe runs on any machine)",
                self.info.backend,
                self.info.name
            );
        }
        Ok(())
    }

    /// Largest 2D texture side the device allows.
    pub fn max_texture_size(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// Copies one layer of a 2D texture into memory, rows tightly packed.
    pub fn read_texture(
        &self,
        texture: &wgpu::Texture,
        layer: u32,
        bytes_per_pixel: u32,
    ) -> Result<Vec<u8>> {
        self.read_texture_level(texture, layer, 0, bytes_per_pixel)
    }

    /// Copies one layer of one mip level of a 2D texture into memory, rows
    /// tightly packed.
    pub fn read_texture_level(
        &self,
        texture: &wgpu::Texture,
        layer: u32,
        level: u32,
        bytes_per_pixel: u32,
    ) -> Result<Vec<u8>> {
        let copy = self.copy_texture(texture, layer, level, bytes_per_pixel);
        Ok(copy.unpad(&self.read_buffer(&copy.buffer)?))
    }

    /// Submits the copy of one layer of one mip level of a 2D texture into
    /// a new `MAP_READ` buffer, its rows padded to wgpu's alignment.
    pub fn copy_texture(
        &self,
        texture: &wgpu::Texture,
        layer: u32,
        level: u32,
        bytes_per_pixel: u32,
    ) -> TextureCopy {
        let (w, h) = (
            (texture.width() >> level).max(1),
            (texture.height() >> level).max(1),
        );
        let unpadded = w * bytes_per_pixel;
        let padded = unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (padded * h) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: level,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([enc.finish()]);
        TextureCopy {
            buffer,
            padded_row: padded as usize,
            row: unpadded as usize,
        }
    }

    /// Waits for the GPU and returns the contents of a `MAP_READ` buffer.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait_idle()?;
        rx.recv()??;
        let out = slice.get_mapped_range()?.to_vec();
        buffer.unmap();
        Ok(out)
    }

    /// Waits until all submitted work has finished.
    pub fn wait_idle(&self) -> Result<()> {
        self.waits
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        Ok(())
    }

    /// How many times the CPU has waited for the GPU on this device (each
    /// [`Self::wait_idle`] and [`Self::read_buffer`]): a frame of a GPU
    /// technique waits once.
    pub fn waits(&self) -> u64 {
        self.waits.load(std::sync::atomic::Ordering::Relaxed)
    }
}
