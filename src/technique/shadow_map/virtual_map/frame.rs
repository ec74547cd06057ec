//! A paged frame's set-up: the pool's atlas, the cache's stale pages and
//! the buffers the marking and lookup passes read, sized and written.

use super::atlas::Atlas;
use super::levels::VirtualLayout;
use super::pages::PagePool;
use super::{CacheKey, LevelGpu, MapHeader, VirtualState};
use crate::gpu::FrameFeedback;
use crate::technique::MaskContext;
use crate::technique::shadow_map::ShadowMapConfig;
use anyhow::Result;

impl VirtualState {
    /// Readies this frame's pool, caches and buffers for `layout`: a new
    /// atlas where the page size or pool changed, stale pages dropped, the
    /// marks, table, pixel levels and level headers sized and written.
    /// Returns the marks' length in 32-bit words.
    pub(super) fn prepare(
        &mut self,
        ctx: &MaskContext,
        c: &ShadowMapConfig,
        layout: &VirtualLayout,
    ) -> Result<u64> {
        let gpu = ctx.gpu;
        let p = c.paging;
        let transmit = crate::technique::shadow_map::transmits(c, ctx);
        if self.atlas.as_ref().is_none_or(|a| {
            (a.page, a.capacity, a.transmit.is_some()) != (p.page_size, p.pool, transmit)
        }) {
            self.atlas = None;
            self.atlas = Some(Atlas::new(gpu, p.page_size, p.pool, transmit)?);
            self.pool = PagePool::new(p.pool);
        }
        // Stale pages.
        let key = CacheKey {
            views: layout.views.iter().map(|v| v.to_cols_array()).collect(),
            levels: layout
                .levels
                .iter()
                .map(|l| (l.view, l.texel, l.pages))
                .collect(),
            depth_bias: c.depth_bias,
            slope_bias: c.slope_bias.to_bits(),
            cull: c.cull,
            caster_alpha: c.caster_alpha,
        };
        let casters = ctx
            .scene_gpu
            .draws
            .iter()
            .filter(|d| d.casts_shadow && !d.shadow_plane)
            .map(|d| d.bounds)
            .collect();
        self.invalidate(layout, key, casters);
        let atlas = self.atlas.as_ref().expect("made above");
        // Buffers of this layout and frame size.
        let words = layout.table_len.div_ceil(32) as u64;
        crate::gpu::grow_buffer(&gpu.device, &mut self.marks, words * 4, "virtual map marks");
        if self.feedback.size() < words * 4 {
            self.feedback =
                FrameFeedback::new(&gpu.device, "virtual map marks read-back", words * 4);
        }
        crate::gpu::grow_buffer(
            &gpu.device,
            &mut self.table,
            layout.table_len as u64 * 4,
            "virtual map page table",
        );
        let pixels = ctx.frame.width() as u64 * ctx.frame.height() as u64;
        crate::gpu::grow_buffer(
            &gpu.device,
            &mut self.pixel_levels,
            pixels * 4,
            "virtual map pixel levels",
        );
        let mut level_bytes = bytemuck::bytes_of(&MapHeader {
            axis_u: layout.axis_u.to_array(),
            atlas_pages: atlas.row_pages,
            axis_v: layout.axis_v.to_array(),
            page_texels: layout.page,
            layer_pages: atlas.layer_pages,
            view_levels: layout.view_levels,
            slot_texels: atlas.slot_texels(),
            oversample_levels: c.paging.oversample_levels,
        })
        .to_vec();
        for l in &layout.levels {
            level_bytes.extend_from_slice(bytemuck::bytes_of(&LevelGpu {
                origin: l.origin.to_array(),
                eye_texel: l.eye_texel.to_array(),
                origin_page: l.origin_page.to_array(),
                texel: l.texel,
                view: l.view,
                pages: l.pages,
                table: l.table,
                texel_world: l.texel_world,
                parent: l.parent,
            }));
        }
        crate::gpu::grow_buffer(
            &gpu.device,
            &mut self.levels,
            level_bytes.len() as u64,
            "virtual map levels",
        );
        gpu.queue.write_buffer(&self.levels, 0, &level_bytes);
        Ok(words)
    }
}
