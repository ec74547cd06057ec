//! The parameters of virtual (paged) shadow maps: whether a light's map is
//! one texture per face or a huge virtual map in pages (all of them that
//! the view needs, or only those at shadow edges), and the sizes of
//! the virtual map, its pages and the physical pool.

use crate::technique::params::{Condition, LightKinds, choice_enum};
use crate::technique::{ParamSpec, ParamValues};
use anyhow::{Result, bail};

choice_enum! {
    /// How a light's map is stored.
    pub enum Paging { Off = "off", Virtual = "virtual", Adaptive = "adaptive" }
}

pub const PAGING: ParamSpec = ParamSpec::choice_of::<Paging>(
    "paging",
    Paging::Off as usize,
    "off: one `size`² map per face; virtual: a `virtual_size`² virtual map per view in `page_size`² pages (directional lights: a clipmap of `clipmap_levels` windows whose side doubles per level, centred on the camera; spot: one view, point: six cube faces, each a mip chain) — the pages the visible pixels need at the level where a texel covers at most one pixel (`texels_per_pixel` per pixel side for point and spot lights) are marked on the GPU, allocated from a pool of `pool` pages (least recently used first), rendered when new and kept across frames until the light or a caster moves; depth is d32f and the filters are the PCF family; adaptive: the same pages, levels and pool, refined as Fernando et al. 2001 (adaptive shadow maps) refine their hierarchy — a pixel starts at its view's coarsest level and asks for the next finer page only where the level it has shows a shadow edge under its kernel (the stored depths it reads do not all lie on one side of the receiver) and is coarser than the pixel needs; up to `refine_steps` refinements a frame, each marked on the GPU and read back",
);

pub const VIRTUAL_SIZE: ParamSpec = ParamSpec::int(
    "virtual_size",
    16384,
    1024,
    65536,
    "paging=virtual or adaptive: texels per side of each clipmap window, or of level 0 of a local light's view (a power of two)",
)
.when(Condition::IsNot("paging", &["off"]));

pub const PAGE_SIZE: ParamSpec = ParamSpec::int(
    "page_size",
    128,
    32,
    512,
    "paging=virtual or adaptive: texels per page side (a power of two)",
)
.when(Condition::IsNot("paging", &["off"]));

pub const POOL: ParamSpec = ParamSpec::int(
    "pool",
    4096,
    16,
    65536,
    "paging=virtual or adaptive: physical pages (each page_size² of d32f); when the view needs more, the finest levels give way to coarser ones (counter pages_degraded)",
)
.when(Condition::IsNot("paging", &["off"]));

pub const CLIPMAP_LEVELS: ParamSpec = ParamSpec::int(
    "clipmap_levels",
    10,
    2,
    14,
    "paging=virtual or adaptive, directional lights: clipmap levels; the coarsest window is twice the scene's width and each finer one half the last",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::IsNot("paging", &["off"]));

pub const REFINE_STEPS: ParamSpec = ParamSpec::int(
    "refine_steps",
    16,
    1,
    32,
    "paging=adaptive: the most refinements per frame (each a marking pass and its read-back, one level finer at shadow edges); it stops earlier when no pixel asks for a new page; the viewer refines once a frame (the marks arrive a frame late)",
)
.when(Condition::Is("paging", &["adaptive"]));

pub const TEXELS_PER_PIXEL: ParamSpec = ParamSpec::int(
    "texels_per_pixel",
    4,
    1,
    4,
    "paging=virtual or adaptive, point and spot lights: texels per pixel side at the level each pixel looks up (1, 2 or 4); 1 takes the coarsest level whose texels span at most a pixel, which leaves a pixel of staircase along every shadow edge; each doubling goes a level finer for about twice the pages (a directional light's clipmap keeps 1: its windows are centred on the camera, and finer levels would outgrow the pool)",
)
.for_lights(LightKinds::LOCAL)
.when(Condition::IsNot("paging", &["off"]));

/// A light's paging and the virtual map's sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PagingConfig {
    pub paging: Paging,
    pub virtual_size: u32,
    pub page_size: u32,
    pub pool: u32,
    pub clipmap_levels: u32,
    pub refine_steps: u32,
    /// Levels finer than one texel per pixel (log2 of `texels_per_pixel`).
    pub oversample_levels: u32,
}

impl PagingConfig {
    pub fn parse(p: &ParamValues) -> Result<PagingConfig> {
        let c = PagingConfig {
            paging: p.choice(&PAGING)?,
            virtual_size: p.int(&VIRTUAL_SIZE)?,
            page_size: p.int(&PAGE_SIZE)?,
            pool: p.int(&POOL)?,
            clipmap_levels: p.int(&CLIPMAP_LEVELS)?,
            refine_steps: p.int(&REFINE_STEPS)?,
            oversample_levels: {
                let t = p.int(&TEXELS_PER_PIXEL)?;
                if !t.is_power_of_two() {
                    bail!("shadow-map: texels_per_pixel={t} is not 1, 2 or 4");
                }
                t.trailing_zeros()
            },
        };
        for (name, v) in [("virtual_size", c.virtual_size), ("page_size", c.page_size)] {
            if !v.is_power_of_two() {
                bail!("shadow-map: {name}={v} is not a power of two");
            }
        }
        if c.page_size > c.virtual_size {
            bail!(
                "shadow-map: page_size={} is larger than virtual_size={}",
                c.page_size,
                c.virtual_size
            );
        }
        Ok(c)
    }

    /// Whether the map is stored in pages (virtual or adaptive).
    pub fn is_paged(&self) -> bool {
        self.paging != Paging::Off
    }

    /// Whether pages are refined only at shadow edges.
    pub fn is_adaptive(&self) -> bool {
        self.paging == Paging::Adaptive
    }
}
