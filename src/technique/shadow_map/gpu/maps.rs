//! The shadow maps of one light: a depth array (one layer per face or
//! cascade), the 8-bit copy of `format=r8`, the two moment arrays of the
//! moment filters (result and blur scratch), the convex part IDs of
//! `part_ids` and the transmittance maps of `blended_casters=transmit`,
//! with per-layer views to render into and array views to look up.

use super::{MOMENT_FORMAT, PART_FORMAT, TRANSMITTANCE_FORMAT};
use crate::gpu::GpuContext;
use crate::technique::shadow_map::config::DepthFormat;
use anyhow::Result;

/// Per-layer views and the array view of one texture array.
pub type LayeredViews = (Vec<wgpu::TextureView>, wgpu::TextureView);

/// What a light's maps hold besides their depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapContents {
    pub format: DepthFormat,
    /// The moment filters' two arrays.
    pub moments: bool,
    /// Convex part IDs (`part_ids`).
    pub parts: bool,
    /// The translucent casters' transmittance and nearest depth
    /// (`blended_casters=transmit`, where the scene has such casters).
    pub transmit: bool,
}

impl MapContents {
    /// Bytes per texel of every array these contents allocate.
    fn bytes_per_texel(self) -> u64 {
        self.format.bytes_per_texel()
            + if self.moments { 32 } else { 0 }
            + if self.parts { 4 } else { 0 }
            + if self.transmit { 5 } else { 0 }
    }
}

/// The translucent casters' maps (`blended_casters=transmit`): the depth of
/// the nearest one per texel, and the product of 1 − opacity over those
/// before the nearest opaque caster.
pub struct TransmitMaps {
    pub depth: LayeredViews,
    pub transmittance: LayeredViews,
}

pub struct Maps {
    pub size: u32,
    pub layers: u32,
    pub contents: MapContents,
    pub depth_layer_views: Vec<wgpu::TextureView>,
    pub depth_array: wgpu::TextureView,
    /// The 8-bit map.
    pub byte: Option<LayeredViews>,
    /// Moment maps A (result) and B (blur scratch).
    pub moment: Option<[LayeredViews; 2]>,
    /// The convex part each texel's depth came from (0: none).
    pub part: Option<LayeredViews>,
    pub transmit: Option<TransmitMaps>,
    pub bytes: u64,
}

impl Maps {
    pub fn matches(&self, size: u32, layers: u32, contents: MapContents) -> bool {
        (self.size, self.layers, self.contents) == (size, layers, contents)
    }

    /// Allocates `layers` maps of `size`² holding `contents`, refused before
    /// anything is created when past the device's limits or the memory
    /// budget.
    pub fn allocate(
        gpu: &GpuContext,
        size: u32,
        layers: u32,
        contents: MapContents,
    ) -> Result<Maps> {
        let texels = size as u64 * size as u64 * layers as u64;
        let bytes = texels * contents.bytes_per_texel();
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
            let (depth_layer_views, depth_array) = views(&make(contents.format.depth_texture()));
            let byte = (contents.format == DepthFormat::R8)
                .then(|| views(&make(wgpu::TextureFormat::R8Unorm)));
            let moment = contents
                .moments
                .then(|| [views(&make(MOMENT_FORMAT)), views(&make(MOMENT_FORMAT))]);
            let part = contents.parts.then(|| views(&make(PART_FORMAT)));
            let transmit = contents.transmit.then(|| TransmitMaps {
                depth: views(&make(wgpu::TextureFormat::Depth32Float)),
                transmittance: views(&make(TRANSMITTANCE_FORMAT)),
            });
            Ok(Maps {
                size,
                layers,
                contents,
                depth_layer_views,
                depth_array,
                byte,
                moment,
                part,
                transmit,
                bytes,
            })
        })
    }
}
