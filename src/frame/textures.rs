//! Texture upload with a full mip chain built on the CPU (each level a
//! triangle-filtered half of the one above).

use crate::gpu::GpuContext;
use crate::scene::Texture;
use wgpu::util::DeviceExt;

pub fn upload(gpu: &GpuContext, t: &Texture) -> wgpu::TextureView {
    let mut levels = vec![t.image.clone()];
    while let Some(last) = levels.last().filter(|l| l.width() > 1 || l.height() > 1) {
        let (w, h) = ((last.width() / 2).max(1), (last.height() / 2).max(1));
        let next = image::imageops::resize(last, w, h, image::imageops::FilterType::Triangle);
        levels.push(next);
    }
    let data: Vec<u8> = levels
        .iter()
        .flat_map(|l| l.as_raw().iter().copied())
        .collect();
    let format = if t.srgb {
        wgpu::TextureFormat::Rgba8UnormSrgb
    } else {
        wgpu::TextureFormat::Rgba8Unorm
    };
    let texture = gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(&t.name),
            size: wgpu::Extent3d {
                width: t.image.width(),
                height: t.image.height(),
                depth_or_array_layers: 1,
            },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::MipMajor,
        &data,
    );
    texture.create_view(&Default::default())
}

/// A 1×1 texture of one colour (stand-in when a material has none).
pub fn solid(gpu: &GpuContext, rgba: [u8; 4], srgb: bool) -> wgpu::TextureView {
    upload(
        gpu,
        &Texture {
            name: "solid".into(),
            image: image::RgbaImage::from_pixel(1, 1, image::Rgba(rgba)),
            srgb,
            source: None,
            wrap: Default::default(),
        },
    )
}
