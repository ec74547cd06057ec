//! `paging=virtual`: virtual shadow maps (the descendant of Fernando et
//! al.'s adaptive shadow maps that UE5 and EEVEE ship). Per frame: a
//! full-screen pass marks, from the G-buffer, the pages the visible pixels
//! need at the level where a texel covers at most one pixel
//! (`virtual_map.wgsl`); the marks come back to the CPU (this frame's,
//! waited for, in measurements; the latest arrived in the viewer, as SDSM's
//! depth bounds), where the pool allocates them ([`pages`]) — on the CPU
//! because wgpu has no portable indirect multi-draw to render a GPU-built
//! page list with per-page culling; new pages are rendered into the pool
//! (an atlas) with the casters that overlap them; cached pages stay until
//! the light or a caster that overlaps them moves; the lookup reads through
//! the page table. `paging=adaptive` (Fernando et al. 2001) marks in
//! passes instead, a level finer at a time and only at shadow edges,
//! rendering each pass's pages before the next marks.

mod atlas;
mod frame;
mod levels;
mod pages;
mod passes;
mod translucent;

pub use levels::{PageKey, VirtualLayout, VirtualParams};
pub use pages::PagePool;

use atlas::Atlas;

use super::gpu::pipelines::LookupKey;
use super::gpu::uniform::{MAX_FACES, STRIDE, ShadowMapUniform};
use super::projection::FrustumParams;
use super::{CullFace, MapState, ShadowMapConfig, ShadowMapTechnique};
use crate::gpu::{FrameFeedback, GpuContext, SectionTimer};
use crate::scene::Aabb;
use crate::technique::light_space::outside_clip_volume;
use crate::technique::params::CasterAlpha;
use crate::technique::{DebugImage, Feedback, MaskContext};
use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};
use std::collections::{BTreeSet, HashSet};

/// The header of the levels buffer (`VirtualMap` of shadow_map.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MapHeader {
    axis_u: [f32; 3],
    atlas_pages: u32,
    axis_v: [f32; 3],
    page_texels: u32,
    layer_pages: u32,
    view_levels: u32,
    slot_texels: u32,
    /// Levels finer than one texel per pixel that lookups take.
    oversample_levels: u32,
}

/// One level (`VirtualLevel` of shadow_map.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LevelGpu {
    origin: [f32; 2],
    eye_texel: [f32; 2],
    origin_page: [i32; 2],
    texel: f32,
    view: u32,
    pages: u32,
    table: u32,
    texel_world: f32,
    parent: u32,
}

/// What the cached pages were rendered with: when any of it changes,
/// every page is stale.
#[derive(Clone, Debug, PartialEq)]
struct CacheKey {
    views: Vec<[f64; 16]>,
    levels: Vec<(u32, f32, u32)>,
    depth_bias: i32,
    slope_bias: u32,
    cull: CullFace,
    caster_alpha: CasterAlpha,
}

/// The pages counted over the last frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct PageCounters {
    pub needed: usize,
    pub rendered: usize,
    pub cached: usize,
    pub degraded: usize,
    pub dropped: usize,
    pub resident: usize,
    pub capacity: u32,
    pub levels: usize,
    /// Marking passes this frame (adaptive maps: refinements).
    pub refine_passes: usize,
    /// Wall time from the marking pass to its marks on the CPU.
    pub feedback_ms: f64,
}

/// One light's virtual map across frames.
pub struct VirtualState {
    pool: PagePool,
    atlas: Option<Atlas>,
    marks: wgpu::Buffer,
    /// The marks read back.
    feedback: FrameFeedback,
    /// GPU time of the frame's first marking pass (counter
    /// `page_marking_ms`).
    mark_timer: SectionTimer,
    /// Adaptive maps without waiting: the marks of an earlier frame, for
    /// the next frame's allocation.
    carried_marks: Option<Vec<u32>>,
    table: wgpu::Buffer,
    levels: wgpu::Buffer,
    pixel_levels: wgpu::Buffer,
    uniforms: wgpu::Buffer,
    key: Option<CacheKey>,
    /// Caster bounds the cached pages were rendered with.
    casters: Vec<Aabb>,
    pub counters: PageCounters,
    /// The last frame's layout and marked entries (debug views).
    pub last_layout: Option<VirtualLayout>,
    pub last_marks: Vec<u32>,
}

fn buffer(gpu: &GpuContext, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage,
        mapped_at_creation: false,
    })
}

impl VirtualState {
    fn new(gpu: &GpuContext, capacity: u32) -> VirtualState {
        use wgpu::BufferUsages as U;
        VirtualState {
            pool: PagePool::new(capacity),
            atlas: None,
            marks: buffer(
                gpu,
                "virtual map marks",
                16,
                U::STORAGE | U::COPY_SRC | U::COPY_DST,
            ),
            feedback: FrameFeedback::new(&gpu.device, "virtual map marks read-back", 16),
            mark_timer: SectionTimer::new("virtual map marking timestamps"),
            carried_marks: None,
            table: buffer(gpu, "virtual map page table", 16, U::STORAGE | U::COPY_DST),
            levels: buffer(gpu, "virtual map levels", 16, U::STORAGE | U::COPY_DST),
            pixel_levels: buffer(gpu, "virtual map pixel levels", 16, U::STORAGE),
            uniforms: buffer(
                gpu,
                "virtual map uniforms",
                STRIDE,
                crate::gpu::uniform_usage(gpu),
            ),
            key: None,
            casters: vec![],
            counters: PageCounters::default(),
            last_layout: None,
            last_marks: vec![],
        }
    }

    /// The GPU time of the frame's first marking pass whose timestamps
    /// arrived, ms.
    pub fn marking_ms(&self) -> f64 {
        self.mark_timer.last_ms()
    }

    /// After the frame's submission: asks for the frame-late marks and the
    /// marking pass's timestamps.
    pub fn after_frame(&mut self, gpu: &GpuContext) -> Result<()> {
        self.feedback.after_frame();
        self.mark_timer.after_frame(gpu)
    }

    /// The page table of each view as an image: its levels side by side,
    /// finest first, each scaled to `CELL`² — green: needed this frame and
    /// resident, blue: resident from an earlier frame, red: needed but
    /// served by a coarser level (pool too small), dark: not in the pool.
    pub fn page_table_images(&self) -> Vec<DebugImage> {
        const CELL: usize = 128;
        let Some(layout) = &self.last_layout else {
            return vec![];
        };
        let needed: std::collections::HashSet<u32> = self.last_marks.iter().copied().collect();
        let mut resident = vec![false; layout.table_len as usize];
        for (k, _) in self.pool.resident() {
            if let Some(e) = layout.entry(k) {
                resident[e as usize] = true;
            }
        }
        let views = layout.levels.len() / layout.view_levels as usize;
        (0..views)
            .map(|v| {
                let levels = &layout.levels[v * layout.view_levels as usize..][..layout.view_levels as usize];
                let width = levels.len() * (CELL + 2);
                let mut rgba = vec![0u8; width * CELL * 4];
                for (i, l) in levels.iter().enumerate() {
                    let g = l.pages as usize;
                    for y in 0..CELL {
                        for x in 0..CELL {
                            let (px, py) = (x * g / CELL, y * g / CELL);
                            let e = l.table + (py * g + px) as u32;
                            let colour = match (needed.contains(&e), resident[e as usize]) {
                                (true, true) => [60, 200, 80, 255],
                                (false, true) => [60, 110, 230, 255],
                                (true, false) => [230, 50, 40, 255],
                                (false, false) => [25, 25, 25, 255],
                            };
                            let at = (y * width + i * (CELL + 2) + x) * 4;
                            rgba[at..at + 4].copy_from_slice(&colour);
                        }
                    }
                }
                DebugImage {
                    label: format!(
                        "virtual map page table, view {v}: levels finest to coarsest (green needed and resident, blue cached, red needed but coarser, dark empty)"
                    ),
                    width: width as u32,
                    height: CELL as u32,
                    rgba,
                }
            })
            .collect()
    }

    pub fn resource_bytes(&self) -> u64 {
        self.atlas.as_ref().map_or(0, |a| a.bytes)
            + self.table.size()
            + self.levels.size()
            + self.marks.size()
            + self.pixel_levels.size()
    }

    /// Drops the cached pages the changes since the last frame make stale:
    /// all when the views or the depth pass changed, else those a moved,
    /// added or removed caster overlaps (before or after).
    fn invalidate(&mut self, layout: &VirtualLayout, key: CacheKey, casters: Vec<Aabb>) {
        if self.key.as_ref() != Some(&key) {
            self.pool.invalidate(|_| true);
        } else if casters != self.casters {
            let n = casters.len().max(self.casters.len());
            let moved: Vec<Aabb> = (0..n)
                .filter(|&i| casters.get(i) != self.casters.get(i))
                .flat_map(|i| [casters.get(i), self.casters.get(i)])
                .flatten()
                .map(|b| Aabb {
                    min: b.min - layout.eye,
                    max: b.max - layout.eye,
                })
                .collect();
            self.pool.invalidate(|k| {
                let m = layout.page_view_proj(*k);
                moved.iter().any(|b| !outside_clip_volume(b, m))
            });
        }
        self.key = Some(key);
        self.casters = casters;
    }
}

impl ShadowMapTechnique {
    /// The frame of a light with `paging=virtual`.
    pub(in crate::technique::shadow_map) fn render_virtual(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        let c = self.config;
        let gpu = ctx.gpu;
        let p = c.paging;
        let layout = VirtualLayout::new(
            ctx.light,
            &ctx.scene_gpu.bounds,
            ctx.fit_camera,
            ctx.camera.eye,
            &FrustumParams {
                near: c.near,
                far: c.far,
                fov_deg: c.fov_deg,
                paraboloid: false,
                stabilize_size: None,
                previous_half: None,
                view_fit: Default::default(),
                turn: Default::default(),
            },
            VirtualParams {
                size: p.virtual_size,
                page: p.page_size,
                clipmap_levels: p.clipmap_levels,
            },
        );
        // A dense map's textures are freed before the pool is made.
        let mut state = match std::mem::replace(&mut self.state, MapState::Empty) {
            MapState::Virtual(state) => state,
            _ => Box::new(VirtualState::new(gpu, p.pool)),
        };
        let done = self.render_pages(ctx, encoder, &mut state, layout);
        self.state = MapState::Virtual(state);
        done
    }

    /// [`Self::render_virtual`] with the light's state and layout.
    fn render_pages(
        &mut self,
        ctx: &MaskContext,
        encoder: &mut wgpu::CommandEncoder,
        state: &mut VirtualState,
        layout: VirtualLayout,
    ) -> Result<()> {
        let c = self.config;
        let gpu = ctx.gpu;
        let shared = self.shared.clone();
        let p = c.paging;
        let words = state.prepare(ctx, &c, &layout)?;
        // Uniforms: slot 0 marking and lookup, then one per page rendered.
        let (base, lookup_key) = page_terms(&c, ctx, &layout);
        // Adaptive maps refine a level per pass; a pass's pages are rendered
        // and submitted before the next pass marks (its edge test reads
        // them). Without waiting (the viewer) one pass a frame, marked
        // after the frame's pages and allocated from in the next frame.
        let refine = p.is_adaptive();
        let wait = ctx.feedback == Feedback::ThisFrame;
        let mut passes = 0;
        let mut feedback_ms = 0.0;
        let mut map_triangles = 0;
        let mut rendered: HashSet<PageKey> = HashSet::new();
        let allocation = loop {
            passes += 1;
            let marks = if refine && !wait {
                state.carried_marks.take().unwrap_or_default()
            } else {
                let start = crate::clock::Instant::now();
                let first = passes == 1;
                let marks =
                    self.mark_pages(ctx, encoder, state, &base, lookup_key, words, wait, first)?;
                feedback_ms += start.elapsed().as_secs_f64() * 1e3;
                marks.unwrap_or_default()
            };
            let marked: Vec<u32> = marked_entries(&marks, layout.table_len).collect();
            let needed: BTreeSet<PageKey> =
                marked.iter().map(|&e| layout.key_of_entry(e)).collect();
            let allocation = state.pool.allocate(
                needed,
                |k| layout.parent(k),
                |level| level % layout.view_levels,
            );
            let mut table = vec![0u32; layout.table_len as usize];
            for (k, slot) in state.pool.resident() {
                if let Some(e) = layout.entry(k) {
                    table[e as usize] = slot + 1;
                }
            }
            gpu.queue
                .write_buffer(&state.table, 0, bytemuck::cast_slice(&table));
            if refine && wait {
                let mut own = gpu.device.create_command_encoder(&Default::default());
                map_triangles += self.render_new_pages(
                    ctx,
                    &mut own,
                    state,
                    &layout,
                    &allocation,
                    &base,
                    lookup_key,
                );
                gpu.queue.submit([own.finish()]);
            } else {
                map_triangles += self.render_new_pages(
                    ctx,
                    encoder,
                    state,
                    &layout,
                    &allocation,
                    &base,
                    lookup_key,
                );
            }
            rendered.extend(allocation.render.iter().map(|(k, _)| *k));
            state.last_marks = marked;
            if !(refine && wait) || allocation.render.is_empty() || passes >= p.refine_steps {
                break allocation;
            }
        };
        if refine && !wait {
            let start = crate::clock::Instant::now();
            state.carried_marks =
                self.mark_pages(ctx, encoder, state, &base, lookup_key, words, false, true)?;
            feedback_ms += start.elapsed().as_secs_f64() * 1e3;
        }
        // The lookup through the page table. Where the marks were this
        // frame's, of each pixel's own level (not an adaptive map's), and all
        // made resident, that level is the one to filter.
        let lookup_key = LookupKey {
            marked_resident: wait && !refine && allocation.degraded == 0 && allocation.dropped == 0,
            ..lookup_key
        };
        let atlas = state.atlas.as_ref().expect("made above");
        let lookup_group = self.page_group(ctx, state, Some(atlas));
        self.lookup_timer.time(gpu, encoder, |encoder| {
            let mut pass = crate::technique::mask_pass(encoder, ctx, "virtual shadow map lookup");
            pass.set_pipeline(&shared.lookup(gpu, lookup_key));
            ctx.bind_frame_groups(&mut pass);
            pass.set_bind_group(crate::frame::OWN_GROUP, &lookup_group, &[0]);
            pass.draw(0..3, 0..1);
        });
        state.counters =
            PageCounters::of(&allocation, &rendered, state, &layout, passes, feedback_ms);
        self.render_debug(ctx, encoder, &lookup_group, lookup_key, 0);
        self.map_triangles = map_triangles;
        self.samples = 1;
        self.last_faces = layout.views.iter().map(|v| v.as_mat4()).collect();
        self.last_paraboloid = false;
        state.last_layout = Some(layout);
        Ok(())
    }
}

impl PageCounters {
    /// This frame's page counts after `passes` marking passes.
    fn of(
        allocation: &pages::Allocation,
        rendered: &HashSet<PageKey>,
        state: &VirtualState,
        layout: &VirtualLayout,
        passes: u32,
        feedback_ms: f64,
    ) -> PageCounters {
        PageCounters {
            needed: allocation.needed,
            rendered: rendered.len(),
            cached: allocation
                .kept
                .iter()
                .filter(|k| !rendered.contains(k))
                .count(),
            degraded: allocation.degraded,
            dropped: allocation.dropped,
            resident: state.pool.resident_count(),
            capacity: state.pool.capacity(),
            levels: layout.levels.len(),
            refine_passes: passes as usize,
            feedback_ms,
        }
    }
}

/// A paged frame's uniform (slot 0: marking and lookup; each page's slot
/// starts from it) and its lookup's pipeline key.
fn page_terms(
    c: &ShadowMapConfig,
    ctx: &MaskContext,
    layout: &VirtualLayout,
) -> (ShadowMapUniform, LookupKey) {
    let p = c.paging;
    let mut faces = [Mat4::IDENTITY; MAX_FACES];
    for (i, f) in faces.iter_mut().zip(0..layout.views.len()) {
        *i = layout.view_relative(f);
    }
    let normal_offset = c.normal_offset(ctx.light.kind);
    let base = ShadowMapUniform {
        faces,
        map: Vec4::new(
            p.virtual_size as f32,
            1.0 / p.virtual_size as f32,
            layout.levels[0].texel_world,
            c.kernel_reach(),
        ),
        depth: Vec4::new(layout.near, layout.far, 0.0, 0.0),
        warp: ctx.light.direction.normalize_or_zero().extend(0.0),
        cascade_view_z: ctx.fit_camera.view().row(2),
        ..ShadowMapUniform::with_filter(
            c,
            normal_offset,
            ctx.light,
            c.cull.for_shape(layout.shape()),
        )
    };
    let lookup_key = LookupKey {
        filter: c.filter,
        taps: if c.filter.uses_taps() { c.samples } else { 0 },
        byte_map: false,
        receiver_plane: c.receiver_plane,
        accumulate: false,
        edge_mask: false,
        virtual_map: true,
        marked_resident: false,
        // The marked reach (`marked_reach()` of virtual_map.wgsl: the
        // kernel's and half a texel) spans a page.
        wide_kernel: 2.0 * (c.kernel_reach() + 0.5) >= p.page_size as f32,
        parts: false,
        transmit: crate::technique::shadow_map::transmits(c, ctx),
        shape: layout.shape(),
    };
    (base, lookup_key)
}

/// The page-table entries whose bit is set in `marks`.
fn marked_entries(marks: &[u32], len: u32) -> impl Iterator<Item = u32> + '_ {
    marks.iter().enumerate().flat_map(move |(w, &bits)| {
        (0..32)
            .filter(move |b| bits & (1 << b) != 0)
            .map(move |b| w as u32 * 32 + b)
            .filter(move |&e| e < len)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marked_entries_are_the_set_bits() {
        let marks = [0b1001u32, 0, 1 << 31];
        let e: Vec<u32> = marked_entries(&marks, 96).collect();
        assert_eq!(e, vec![0, 3, 95]);
        assert_eq!(marked_entries(&marks, 90).count(), 2);
    }
}
