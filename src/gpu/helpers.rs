//! Texture, bind-layout and shader-composition helpers.

use super::GpuContext;

/// A binding of one `T` at a dynamic offset of `buffer`.
pub fn dynamic_uniform<T>(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: wgpu::BufferSize::new(std::mem::size_of::<T>() as u64),
    })
}

/// Layout entry of a parameter block (a WGSL `var<uniform>`, optionally at
/// a dynamic offset), in the device's [`super::UniformSpace`].
pub fn uniform_entry(
    gpu: &GpuContext,
    binding: u32,
    visibility: wgpu::ShaderStages,
    dynamic: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: gpu.uniform_space.binding_type(dynamic),
        count: None,
    }
}

/// The usage of a parameter block's buffer that is written after creation.
pub fn uniform_usage(gpu: &GpuContext) -> wgpu::BufferUsages {
    gpu.uniform_space.usage() | wgpu::BufferUsages::COPY_DST
}

/// Layout entry of a storage buffer.
pub fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Layout entry of a float texture read in fragment shaders.
pub fn texture_entry(
    binding: u32,
    dim: wgpu::TextureViewDimension,
    filterable: bool,
) -> wgpu::BindGroupLayoutEntry {
    sampled_texture_entry(
        binding,
        wgpu::ShaderStages::FRAGMENT,
        wgpu::TextureSampleType::Float { filterable },
        dim,
    )
}

/// Layout entry of a single-sampled texture of any sample type.
pub fn sampled_texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    sample_type: wgpu::TextureSampleType,
    dim: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: dim,
            multisampled: false,
        },
        count: None,
    }
}

/// Builds one shader module from WGSL sources joined in order (the shared
/// declarations first), its parameter blocks in the device's
/// [`super::UniformSpace`].
pub fn compose_shader(gpu: &GpuContext, label: &str, sources: &[&str]) -> wgpu::ShaderModule {
    let source = sources.join("\n");
    gpu.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(gpu.uniform_space.wgsl(&source).into_owned().into()),
        })
}

/// Compute pipelines for `entries` of the WGSL `source`, all with one bind
/// group of `layout` (group 0), in the order given.
pub fn compute_pipelines<const N: usize>(
    gpu: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    source: &str,
    entries: [&str; N],
) -> [wgpu::ComputePipeline; N] {
    compute_pipelines_with(gpu, label, layout, source, entries, &[])
}

/// [`compute_pipelines`] with the shader's pipeline-overridable
/// `constants` set.
pub fn compute_pipelines_with<const N: usize>(
    gpu: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    source: &str,
    entries: [&str; N],
    constants: &[(&str, f64)],
) -> [wgpu::ComputePipeline; N] {
    let device = &gpu.device;
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let module = compose_shader(gpu, label, &[source]);
    entries.map(|entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        })
    })
}

/// Replaces `buffer` by an empty one of the same label and usage when it
/// holds fewer than `size` bytes (the next power of two, so that a growing
/// need reallocates rarely); contents are not kept.
pub fn grow_buffer(device: &wgpu::Device, buffer: &mut wgpu::Buffer, size: u64, label: &str) {
    if buffer.size() < size {
        *buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.next_power_of_two(),
            usage: buffer.usage(),
            mapped_at_creation: false,
        });
    }
}

/// A single-mip 2D texture (array when `layers` > 1).
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// Views of a 2D array texture's first `layers` layers, one each (to
/// render into), and of the whole array (to read).
pub fn layer_views(t: &wgpu::Texture, layers: u32) -> (Vec<wgpu::TextureView>, wgpu::TextureView) {
    let each = (0..layers)
        .map(|i| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: i,
                array_layer_count: Some(1),
                ..Default::default()
            })
        })
        .collect();
    let array = t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (each, array)
}
