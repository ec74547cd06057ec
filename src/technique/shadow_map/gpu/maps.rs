//! The shadow maps of one light: a depth array (one layer per face or
//! cascade), the 8-bit copy of `format=r8`, the two moment arrays of the
//! moment filters (result and blur scratch) and the convex part IDs of
//! `part_ids`, with per-layer views to render into and array views to look
//! up.

use super::{MOMENT_FORMAT, PART_FORMAT};
use crate::gpu::GpuContext;
use crate::technique::shadow_map::config::DepthFormat;
use anyhow::Result;

/// Per-layer views and the array view of one texture array.
pub type LayeredViews = (Vec<wgpu::TextureView>, wgpu::TextureView);

pub struct Maps {
    pub size: u32,
    pub layers: u32,
    pub format: DepthFormat,
    pub moments: bool,
    pub depth_layer_views: Vec<wgpu::TextureView>,
    pub depth_array: wgpu::TextureView,
    /// The 8-bit map.
    pub byte: Option<LayeredViews>,
    /// Moment maps A (result) and B (blur scratch).
    pub moment: Option<[LayeredViews; 2]>,
    /// The convex part each texel's depth came from (0: none).
    pub part: Option<LayeredViews>,
    pub bytes: u64,
}

impl Maps {
    pub fn matches(
        &self,
        size: u32,
        layers: u32,
        format: DepthFormat,
        moments: bool,
        parts: bool,
    ) -> bool {
        (
            self.size,
            self.layers,
            self.format,
            self.moments,
            self.part.is_some(),
        ) == (size, layers, format, moments, parts)
    }

    /// Allocates `layers` maps of `size`², refused before anything is
    /// created when past the device's limits or the memory budget.
    pub fn allocate(
        gpu: &GpuContext,
        size: u32,
        layers: u32,
        format: DepthFormat,
        moments: bool,
        parts: bool,
    ) -> Result<Maps> {
        let texels = size as u64 * size as u64 * layers as u64;
        let bytes = texels
            * (format.bytes_per_texel() + if moments { 32 } else { 0 } + if parts { 4 } else { 0 });
        gpu.check_allocation(
            &format!(
                "shadow-map: {layers} map(s) of {size}x{size} (--set size=N; largest texture {})",
                gpu.max_texture_size()
            ),
            (size, size, layers),
            bytes,
        )?;
        let make = |f: wgpu::TextureFormat| {
            crate::gpu::texture_2d(
                &gpu.device,
                "shadow map",
                size,
                size,
                layers,
                f,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            )
        };
        let views = |t: &wgpu::Texture| crate::gpu::layer_views(t, layers);
        gpu.checked("allocating the shadow maps", || {
            let (depth_layer_views, depth_array) = views(&make(format.depth_texture()));
            let byte =
                (format == DepthFormat::R8).then(|| views(&make(wgpu::TextureFormat::R8Unorm)));
            let moment =
                moments.then(|| [views(&make(MOMENT_FORMAT)), views(&make(MOMENT_FORMAT))]);
            let part = parts.then(|| views(&make(PART_FORMAT)));
            Ok(Maps {
                size,
                layers,
                format,
                moments,
                depth_layer_views,
                depth_array,
                byte,
                moment,
                part,
                bytes,
            })
        })
    }
}
