//! The physical pool of a virtual map as a texture: layers of square
//! rows of slots of d32f texels, and where each slot lies in it. A slot
//! holds its page and a guard of the texels just past its right and bottom
//! edges (the next pages' first), so that every 2×2 comparison whose first
//! texel lies in a page reads one slot: one page-table read and one
//! hardware comparison per tap, with no case for taps across page borders.
//! With `blended_casters=transmit`, two more pools of the same layout hold
//! each page's translucent casters (`gpu::transmittance`).

use crate::gpu::GpuContext;
use crate::technique::shadow_map::gpu::TRANSMITTANCE_FORMAT;
use crate::technique::shadow_map::gpu::maps::TransmitMaps;
use anyhow::Result;

/// Texels past a page's right and bottom edges that its slot also holds.
pub const GUARD_TEXELS: u32 = 1;

/// The physical pool: layers of rows of slots, each `page` + [`GUARD_TEXELS`]
/// texels square.
pub struct Atlas {
    pub page: u32,
    pub capacity: u32,
    /// Pages per row of a layer, and per layer.
    pub row_pages: u32,
    pub layer_pages: u32,
    pub layer_views: Vec<wgpu::TextureView>,
    pub array: wgpu::TextureView,
    /// The pages' translucent casters (`blended_casters=transmit`).
    pub transmit: Option<TransmitMaps>,
    pub bytes: u64,
}

impl Atlas {
    pub fn new(gpu: &GpuContext, page: u32, capacity: u32, transmit: bool) -> Result<Atlas> {
        let max = gpu.max_texture_size();
        // Rows of a power of two slots (the shader masks and shifts).
        let slot = page + GUARD_TEXELS;
        let row_pages = (max / slot)
            .min((capacity as f64).sqrt().ceil() as u32)
            .max(1)
            .next_power_of_two()
            .min(prev_power_of_two(max / slot).max(1));
        let layer_pages = row_pages * row_pages;
        let layers = capacity.div_ceil(layer_pages);
        let side = row_pages * slot;
        let bytes = side as u64 * side as u64 * layers as u64 * if transmit { 9 } else { 4 };
        gpu.check_allocation(
            &format!(
                "shadow-map: a pool of {capacity} pages of {page}² ({layers} layer(s) of {side}²; --set pool=N)"
            ),
            (side, side, layers),
            bytes,
        )?;
        gpu.checked("allocating the virtual map's pool", || {
            let pool = |format| {
                let t = crate::gpu::texture_2d(
                    &gpu.device,
                    "virtual shadow map pool",
                    side,
                    side,
                    layers,
                    format,
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                );
                crate::gpu::layer_views(&t, layers)
            };
            let (layer_views, array) = pool(wgpu::TextureFormat::Depth32Float);
            let transmit = transmit.then(|| TransmitMaps {
                depth: pool(wgpu::TextureFormat::Depth32Float),
                transmittance: pool(TRANSMITTANCE_FORMAT),
            });
            Ok(Atlas {
                page,
                capacity,
                row_pages,
                layer_pages,
                layer_views,
                array,
                transmit,
                bytes,
            })
        })
    }

    /// Texels per side of a slot: its page and the guard.
    pub fn slot_texels(&self) -> u32 {
        self.page + GUARD_TEXELS
    }

    /// Layer and texel origin of a slot.
    pub fn place(&self, slot: u32) -> (usize, u32, u32) {
        let k = slot % self.layer_pages;
        (
            (slot / self.layer_pages) as usize,
            (k % self.row_pages) * self.slot_texels(),
            (k / self.row_pages) * self.slot_texels(),
        )
    }
}

fn prev_power_of_two(v: u32) -> u32 {
    if v == 0 {
        0
    } else {
        1 << (31 - v.leading_zeros())
    }
}
