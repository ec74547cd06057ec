//! The shadow-map family's parameter table and its typed reading
//! ([`ShadowMapConfig`]): the table names, ranges and documents every
//! parameter once; the enums carry the choices into Rust and, as generated
//! WGSL constants and pipeline-overridable constants, into the shaders.

pub mod bias;
pub mod filter;
pub mod paging;
pub mod partition;
pub(super) mod presets;

use crate::scene::{Light, LightType};
use crate::technique::params::{CasterAlpha, Condition, LightKinds, choice_enum};
use crate::technique::{ParamSpec, ParamValues};
use anyhow::Result;

use self::bias::{
    CREASE_ANGLE, DEPTH_BIAS, NORMAL_OFFSET_DIRECTIONAL, NORMAL_OFFSET_LOCAL, NORMAL_OFFSET_POWER,
    RECEIVER_PLANE, SLOPE_BIAS, SLOPE_BIAS_CLAMP, SLOPE_BIAS_CLAMP_LOCAL,
};
use self::filter::{
    BLEEDING_REDUCTION, BLOCKER_SEARCH, BLUR, ESM_EXPONENT, EXPONENT, EXPONENT_NEGATIVE,
    HARD_LIGHT_PENUMBRA, LIGHT_SIZE, MOMENT_BIAS, VARWIDTH_EXPONENT, VARWIDTH_SCALE,
};
use self::paging::{
    CLIPMAP_LEVELS, PAGE_SIZE, PAGING, POOL, REFINE_STEPS, TEXELS_PER_PIXEL, VIRTUAL_SIZE,
};
pub use self::paging::{Paging, PagingConfig};
use self::partition::{
    BLEND, CASCADES, FIT, LISPSM_N, MAX_DISTANCE, ROLL, SELECT, SPLIT_LAMBDA, STABILIZE, TSM_FOCUS,
    WARP,
};
pub use self::partition::{Cascades, Fit, Roll, Select, Warp, WarpParams};

choice_enum! {
    /// The lookup's filter.
    pub enum Filter {
        Hard = "hard",
        Pcf2x2 = "pcf2x2",
        Grid = "grid",
        Disk = "disk",
        Pcss = "pcss",
        Varwidth = "varwidth",
        Vsm = "vsm",
        Esm = "esm",
        Evsm2 = "evsm2",
        Evsm4 = "evsm4",
        Msm = "msm",
    }
}

impl Filter {
    /// Filters of moment maps (filtered before the lookup).
    pub fn is_moment(self) -> bool {
        matches!(
            self,
            Filter::Vsm | Filter::Esm | Filter::Evsm2 | Filter::Evsm4 | Filter::Msm
        )
    }

    /// Filters whose tap count is `samples` (the others ignore it).
    pub fn uses_taps(self) -> bool {
        matches!(
            self,
            Filter::Grid | Filter::Disk | Filter::Pcss | Filter::Varwidth
        )
    }
}

choice_enum! {
    /// How the map stores depth.
    pub enum DepthFormat { D16 = "d16", D24 = "d24", D32f = "d32f", R8 = "r8" }
}

impl DepthFormat {
    /// The depth attachment (the 8-bit map still depth-tests in 16 bits).
    pub fn depth_texture(self) -> wgpu::TextureFormat {
        match self {
            DepthFormat::D16 | DepthFormat::R8 => wgpu::TextureFormat::Depth16Unorm,
            DepthFormat::D24 => wgpu::TextureFormat::Depth24Plus,
            DepthFormat::D32f => wgpu::TextureFormat::Depth32Float,
        }
    }

    /// The depth of one of the format's smallest steps, the unit of the
    /// constant depth bias (Vulkan's r: 2^−24 for floats near 1).
    pub fn depth_step(self) -> f32 {
        match self {
            DepthFormat::D16 | DepthFormat::R8 => 1.0 / 65535.0,
            DepthFormat::D24 => 1.0 / 16_777_215.0,
            DepthFormat::D32f => 2f32.powi(-24),
        }
    }

    /// Bytes per texel of the depth attachment and the 8-bit copy.
    pub fn bytes_per_texel(self) -> u64 {
        match self {
            DepthFormat::D16 => 2,
            DepthFormat::D24 | DepthFormat::D32f => 4,
            DepthFormat::R8 => 2 + 1,
        }
    }
}

choice_enum! {
    /// Faces culled in the depth pass; `Solids` culls by caster (see [`CULL`]).
    pub enum CullFace { Solids = "solids", Back = "back", Front = "front", None = "none" }
}

impl CullFace {
    /// The rasteriser's culling; `Solids` passes draw the casters that are
    /// not solids with both faces.
    pub fn face(self) -> Option<wgpu::Face> {
        match self {
            CullFace::Back => Some(wgpu::Face::Back),
            CullFace::Front => Some(wgpu::Face::Front),
            CullFace::None | CullFace::Solids => None,
        }
    }
}

choice_enum! {
    /// Point lights: six cube faces or two paraboloid hemispheres.
    pub enum Omni { Cube = "cube", DualParaboloid = "dual-paraboloid" }
}

choice_enum! {
    /// What the technique runs: everything, the maps alone, or the floor.
    pub enum Stage { Full = "full", Maps = "maps", Floor = "floor" }
}

pub const FILTER: ParamSpec = ParamSpec::choice_of::<Filter>(
    "filter",
    Filter::Grid as usize,
    "hard: nearest texel; pcf2x2: hardware bilinear comparison; grid: N×N 2×2-PCF taps; disk: N² taps on a rotated Vogel disk; pcss: blocker search + penumbra from the light size; varwidth: radius ∝ |d_blocker − d_receiver|^exponent (002); vsm: variance (Chebyshev) with light-bleeding reduction; esm: exponential; evsm2/evsm4: exponential variance, 2 or 4 moments; msm: 4-moment Hamburger (Peters & Klein 2015)",
);

pub const SAMPLES: ParamSpec = ParamSpec::int(
    "samples",
    3,
    1,
    16,
    "taps per side: grid N×N (up to 16×16), disk N²",
)
.when(Condition::Is(
    "filter",
    &["grid", "disk", "pcss", "varwidth"],
));

pub const RADIUS: ParamSpec = ParamSpec::float(
    "radius",
    1.5,
    0.0,
    32.0,
    0.25,
    "filter radius in texels (grid and disk)",
)
.when(Condition::Is("filter", &["grid", "disk"]));

pub const SIZE: ParamSpec = ParamSpec::int(
    "size",
    2048,
    64,
    16384,
    "map side in texels (per cube face for point lights, per cascade for directional ones, per sample of an area light); where cascades or area maps do not apply (cascades under a point or spot light, area maps under a light without an area), the light's one map takes their texels: side × √count",
);

pub const FORMAT: ParamSpec = ParamSpec::choice_of::<DepthFormat>(
    "format",
    DepthFormat::D32f as usize,
    "depth format; r8 stores depth in 8 bits and shows the low-precision failure",
);

pub const EDGE_MASK: ParamSpec = ParamSpec::boolean(
    "edge_mask",
    false,
    "grid, disk, pcss, varwidth: a chain of depth bounds of the map (per block, two planes that follow a flat or sloped surface, or its least and greatest depth) classifies each pixel as lit, shadowed or at a shadow edge from 4 texels covering its kernel, compared along the receiver plane with receiver_plane=true, with part_ids a cell of the receiver's own convex part counts as lit; where the chain finds an edge and the kernel reaches at most 2.5 texels, the texels it reads are compared one by one; only edge pixels run the kernel (PCF at shadow silhouettes, [000] §4.3); the mask is the full kernel's",
)
.when(Condition::IsNot("filter", &["vsm", "esm", "evsm2", "evsm4", "msm"]));

pub const EDGE_RAMP_PIXELS: ParamSpec = ParamSpec::float(
    "edge_ramp_pixels",
    2.0,
    0.0,
    64.0,
    0.5,
    "every filter but hard (pcss, varwidth and the moment filters only under a light without an area, where their ramp is the map's resolution and blur, not a penumbra): the widest a shadow edge's ramp may be on screen, in pixels; where the map's texels are magnified (a close-up, a receiver lit at a grazing angle), the kernel's ramp of 2·reach texels spans tens of pixels, and its visibility is steepened about ½ until it spans this many: a hard light's edge stays an anti-aliased line along the filtered contour instead of a blur, and no pixel changes side of ½; 0 = as filtered",
)
.when(Condition::IsNot("filter", &["hard"]));

pub const CULL: ParamSpec = ParamSpec::choice_of::<CullFace>(
    "cull",
    CullFace::Solids as usize,
    "faces culled in the depth pass — solids: casters that bound a solid (closed, wound outward) store their back faces without bias, so a lit surface is never compared against itself and takes no normal offset (a concave solid's takes half of it where solid_front_bias stores its front faces too), while its shadow edges stay where its silhouette puts them (second-depth shadow maps, Wang & Molnar 1994); other casters store both faces with the bias; back or front culling for every caster leaks light through open meshes (bunny, teapot)",
);

pub const SOLID_FRONT_BIAS: ParamSpec = ParamSpec::float(
    "solid_front_bias",
    4.0,
    0.0,
    64.0,
    0.5,
    "cull=solids, maps whose bias is capped (unwarped directional: one map, cascades, clipmap levels; spot maps and cube faces under slope_bias_clamp_local): concave solids (a convex one never shadows its own lit side) also store their front faces, with this many times the slope bias and its cap: where a back face lies too close before a receiver to shadow it (a smooth solid shadowing itself near its terminator), the pushed front face still does; at grazing light the capped push still meets the lit face it came from, so a concave solid's receivers then take half the normal offset; 0 = back faces only",
)
.when(Condition::Is("cull", &["solids"]));

pub const PART_IDS: ParamSpec = ParamSpec::boolean(
    "part_ids",
    true,
    "cull=solids, depth-compared filters (hard, pcf2x2, grid, disk, pcss, varwidth) of unwarped maps and cube faces: every texel also stores the convex part its depth came from (a closed, outward-wound piece of a mesh convex at every edge, or a flat one such as a floor, unless another mesh placed with it goes on from one of its edges level or falling away, as a glTF mesh's primitive of another material does), and a receiver facing the light ignores its own part's texels and takes no normal offset — a convex part never shadows its own lit side, so a lit wall is not compared against the back face that meets it at its corner (priority buffers, Hourcade & Nicolas 1985); 4 more bytes per texel",
)
.when(Condition::Is("cull", &["solids"]));

pub const ALPHA_TEST: ParamSpec = ParamSpec::boolean(
    "alpha_test",
    true,
    "cut-out (glTF MASK) and translucent casters are alpha-tested in the depth pass, their opacity map read at the mip level of the light's texel footprint; false draws every caster solid (what a shadow map without alpha testing shows, and what alpha testing costs)",
);

pub const OMNI: ParamSpec = ParamSpec::choice_of::<Omni>(
    "omni",
    Omni::Cube as usize,
    "point lights: six 90° faces (cube) or two paraboloid hemispheres (Brabec 2002; distorts large triangles)",
)
.for_lights(LightKinds::POINT);

pub const NEAR: ParamSpec = ParamSpec::float(
    "near",
    0.0,
    0.0,
    10000.0,
    0.01,
    "near plane of the light frustum (0 = fitted to the scene)",
);

pub const FAR: ParamSpec = ParamSpec::float(
    "far",
    0.0,
    0.0,
    100000.0,
    0.1,
    "far plane of the light frustum (0 = fitted to the scene)",
);

pub const FOV: ParamSpec = ParamSpec::float(
    "fov",
    0.0,
    0.0,
    170.0,
    1.0,
    "spot light frustum angle in degrees (0 = the cone plus 4°); precision degrades above 90°",
)
.for_lights(LightKinds::SPOT);

pub const AREA: ParamSpec = ParamSpec::boolean(
    "area",
    false,
    "lights with an area size: accumulate `area_maps` shadow maps rendered from stratified points of the area",
);

pub const AREA_MAPS: ParamSpec = ParamSpec::int(
    "area_maps",
    16,
    1,
    64,
    "area: number of shadow maps (the documents use the 4 corners)",
)
.when(Condition::Is("area", &["true"]));

pub const STAGE: ParamSpec = ParamSpec::choice_of::<Stage>(
    "stage",
    Stage::Full as usize,
    "full: maps and lookup; maps: the shadow-map pass alone (mask = 1); floor: a bare depth-only render of the same casters into the same map (position-only, no bias, no colour; mask = 1), what a shadow map cannot beat",
);

/// Every parameter, in table order.
pub const PARAMS: &[ParamSpec] = &[
    FILTER,
    SAMPLES,
    RADIUS,
    SIZE,
    FORMAT,
    DEPTH_BIAS,
    SLOPE_BIAS,
    SLOPE_BIAS_CLAMP,
    SLOPE_BIAS_CLAMP_LOCAL,
    NORMAL_OFFSET_DIRECTIONAL,
    NORMAL_OFFSET_LOCAL,
    NORMAL_OFFSET_POWER,
    RECEIVER_PLANE,
    CREASE_ANGLE,
    EDGE_RAMP_PIXELS,
    EDGE_MASK,
    CULL,
    SOLID_FRONT_BIAS,
    PART_IDS,
    ALPHA_TEST,
    ParamSpec::BLENDED_CASTERS,
    OMNI,
    NEAR,
    FAR,
    FOV,
    LIGHT_SIZE,
    HARD_LIGHT_PENUMBRA,
    BLOCKER_SEARCH,
    VARWIDTH_SCALE,
    VARWIDTH_EXPONENT,
    BLUR,
    AREA,
    AREA_MAPS,
    BLEEDING_REDUCTION,
    ESM_EXPONENT,
    EXPONENT,
    EXPONENT_NEGATIVE,
    MOMENT_BIAS,
    STAGE,
    CASCADES,
    SPLIT_LAMBDA,
    MAX_DISTANCE,
    STABILIZE,
    BLEND,
    SELECT,
    FIT,
    ROLL,
    WARP,
    LISPSM_N,
    TSM_FOCUS,
    PAGING,
    VIRTUAL_SIZE,
    PAGE_SIZE,
    POOL,
    CLIPMAP_LEVELS,
    REFINE_STEPS,
    TEXELS_PER_PIXEL,
];

/// The shadow-map family's parameters, parsed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMapConfig {
    pub filter: Filter,
    /// Taps per side (grid) or √taps (disk, pcss, varwidth).
    pub samples: u32,
    pub radius: f32,
    pub size: u32,
    pub format: DepthFormat,
    /// Constant depth bias in the format's smallest steps.
    pub depth_bias: i32,
    pub slope_bias: f32,
    /// Cap of the depth bias in texel widths of depth (directional maps).
    pub slope_bias_clamp: f32,
    pub slope_bias_clamp_local: f32,
    pub normal_offset_directional: f32,
    pub normal_offset_local: f32,
    /// Normal offset × sinⁿθ between normal and light, n this power.
    pub normal_offset_power: f32,
    pub receiver_plane: bool,
    /// Degrees a tap's compared depth may sink below the receiver plane
    /// per unit of distance (`crease_angle`).
    pub crease_angle: f32,
    /// The widest a shadow edge's ramp may be on screen (pixels; 0: off).
    pub edge_ramp_pixels: f32,
    /// The kernel only at shadow edges (the edge mask's bounds chain).
    pub edge_mask: bool,
    pub cull: CullFace,
    /// `cull=solids`: solids' front faces stored with this many times the
    /// slope bias and its cap (0: not stored).
    pub solid_front_bias: f32,
    /// Convex part IDs beside the depth (see [`ShadowMapConfig::uses_part_ids`]).
    pub part_ids: bool,
    /// How the depth passes treat see-through casters.
    pub caster_alpha: CasterAlpha,
    pub omni: Omni,
    pub near: f32,
    pub far: f32,
    pub fov_deg: f32,
    pub light_size: f32,
    /// Whether pcss and varwidth draw a penumbra under a light without an area.
    pub hard_light_penumbra: bool,
    pub blocker_search: f32,
    pub varwidth_scale: f32,
    pub varwidth_exponent: f32,
    pub blur: u32,
    pub area: bool,
    pub area_maps: u32,
    pub bleeding_reduction: f32,
    /// esm's exponent (log space).
    pub esm_exponent: f32,
    pub exponent: f32,
    pub exponent_negative: f32,
    pub moment_bias: f32,
    pub stage: Stage,
    pub cascades: Cascades,
    /// A directional light's single unwarped map: upright, or turned to
    /// the smallest square (`roll`).
    pub roll: Roll,
    pub warp: WarpParams,
    pub paging: PagingConfig,
}

/// The radius in texels of the disk pcss and varwidth draw where the light
/// casts no penumbra (the shader's least kernel): half a texel, the
/// resolution of the map, not a shadow's softness.
pub const HARD_LIGHT_DISK_RADIUS: f32 = 0.5;

/// The reach of a Vogel disk of `radius` texels and `samples`² taps: its
/// outermost tap, radius·√((N² − ½)/N²), plus the half texel of its 2×2
/// comparison.
fn disk_reach(radius: f32, samples: u32) -> f32 {
    let taps = (samples * samples) as f32;
    radius * ((taps - 0.5) / taps).sqrt() + 0.5
}

impl ShadowMapConfig {
    /// How far in texels from its centre a pixel's kernel reads (the
    /// lookup's `kernel_reach()`, `sm.map.w`): none (hard), its farthest
    /// tap (grid: N taps a side at (i + ½)/N·2 − 1 of the radius, so
    /// radius·(1 − 1/N); disk: the Vogel disk's outermost of N² taps,
    /// radius·√((N² − ½)/N²)) or the widest blocker search and penumbra
    /// (pcss, varwidth, both capped at 64 texels), plus the half texel of a
    /// 2×2 tap (pcf2x2, the filters of taps, and a moment filter's bilinear
    /// read).
    pub fn kernel_reach(&self) -> f32 {
        let n = self.samples as f32;
        match self.filter {
            Filter::Hard => 0.0,
            Filter::Grid => self.radius * (1.0 - 1.0 / n) + 0.5,
            Filter::Disk => disk_reach(self.radius, self.samples),
            Filter::Pcss | Filter::Varwidth => self.blocker_search.max(64.0) + 0.5,
            _ => 0.5,
        }
    }

    /// The depth a tap may lie below the receiver's plane per unit of
    /// its distance from the lookup point, as a slope (the lookup's
    /// `sm.screen.z`): tan `crease_angle` with the receiver plane, else 0.
    pub fn crease_slope(&self) -> f32 {
        if self.receiver_plane {
            self.crease_angle.to_radians().tan()
        } else {
            0.0
        }
    }

    /// The reach in texels of the ramp `edge_ramp_pixels` steepens (the
    /// lookup's `sm.screen.y`): the kernel's for grid, disk and pcf2x2; for
    /// pcss and varwidth under a light without an area (and no
    /// `hard_light_penumbra`), the disk of [`HARD_LIGHT_DISK_RADIUS`] they
    /// draw there, whose ramp is resolution, not penumbra; for the moment
    /// filters under such a light, their blur's (`blur` + ½ texels: the
    /// ramp a box of 2·blur + 1 texels draws across an edge, which a hard
    /// light's truth does not have). 0 where nothing is steepened: a
    /// penumbra the light's area (or a pretended size) draws, the hard
    /// filter, or `edge_ramp_pixels` = 0.
    pub fn ramp_reach(&self, light_has_area: bool) -> f32 {
        if self.edge_ramp_pixels <= 0.0 {
            return 0.0;
        }
        match self.filter {
            Filter::Grid | Filter::Disk | Filter::Pcf2x2 => self.kernel_reach(),
            Filter::Pcss | Filter::Varwidth if !light_has_area && !self.hard_light_penumbra => {
                disk_reach(HARD_LIGHT_DISK_RADIUS, self.samples)
            }
            Filter::Vsm | Filter::Esm | Filter::Evsm2 | Filter::Evsm4 | Filter::Msm
                if !light_has_area =>
            {
                self.blur as f32 + 0.5
            }
            _ => 0.0,
        }
    }

    pub fn parse(p: &ParamValues) -> Result<ShadowMapConfig> {
        Ok(ShadowMapConfig {
            filter: p.choice(&FILTER)?,
            samples: p.int(&SAMPLES)?,
            radius: p.float(&RADIUS)?,
            size: p.int(&SIZE)?,
            format: p.choice(&FORMAT)?,
            depth_bias: p.float(&DEPTH_BIAS)?.round().min(i32::MAX as f32) as i32,
            slope_bias: p.float(&SLOPE_BIAS)?,
            slope_bias_clamp: p.float(&SLOPE_BIAS_CLAMP)?,
            slope_bias_clamp_local: p.float(&SLOPE_BIAS_CLAMP_LOCAL)?,
            normal_offset_directional: p.float(&NORMAL_OFFSET_DIRECTIONAL)?,
            normal_offset_local: p.float(&NORMAL_OFFSET_LOCAL)?,
            normal_offset_power: p.float(&NORMAL_OFFSET_POWER)?,
            receiver_plane: p.flag(&RECEIVER_PLANE)?,
            crease_angle: p.float(&CREASE_ANGLE)?,
            edge_ramp_pixels: p.float(&EDGE_RAMP_PIXELS)?,
            edge_mask: p.flag(&EDGE_MASK)?,
            cull: p.choice(&CULL)?,
            solid_front_bias: p.float(&SOLID_FRONT_BIAS)?,
            part_ids: p.flag(&PART_IDS)?,
            caster_alpha: CasterAlpha {
                alpha_test: p.flag(&ALPHA_TEST)?,
                blended: p.choice(&ParamSpec::BLENDED_CASTERS)?,
            },
            omni: p.choice(&OMNI)?,
            near: p.float(&NEAR)?,
            far: p.float(&FAR)?,
            fov_deg: p.float(&FOV)?,
            light_size: p.float(&LIGHT_SIZE)?,
            hard_light_penumbra: p.flag(&HARD_LIGHT_PENUMBRA)?,
            blocker_search: p.float(&BLOCKER_SEARCH)?,
            varwidth_scale: p.float(&VARWIDTH_SCALE)?,
            varwidth_exponent: p.float(&VARWIDTH_EXPONENT)?,
            blur: p.int(&BLUR)?,
            area: p.flag(&AREA)?,
            area_maps: p.int(&AREA_MAPS)?,
            bleeding_reduction: p.float(&BLEEDING_REDUCTION)?,
            esm_exponent: p.float(&ESM_EXPONENT)?,
            exponent: p.float(&EXPONENT)?,
            exponent_negative: p.float(&EXPONENT_NEGATIVE)?,
            moment_bias: p.float(&MOMENT_BIAS)?,
            stage: p.choice(&STAGE)?,
            cascades: Cascades::parse(p)?,
            roll: p.choice(&ROLL)?,
            warp: WarpParams::parse(p)?,
            paging: PagingConfig::parse(p)?,
        })
        .and_then(|c: ShadowMapConfig| {
            if c.paging.is_paged()
                && (c.filter.is_moment() || c.area || c.format != DepthFormat::D32f)
            {
                anyhow::bail!(
                    "shadow-map: paging=virtual and adaptive store d32f, filters with the PCF family (hard, pcf2x2, grid, disk, pcss, varwidth) and renders one map per light (area=false)"
                );
            }
            Ok(c)
        })
    }

    /// The lookup's normal offset in texels for a light of this type.
    pub fn normal_offset(&self, kind: LightType) -> f32 {
        match kind {
            LightType::Directional => self.normal_offset_directional,
            _ => self.normal_offset_local,
        }
    }

    /// The side of the maps rendered for `light`, at most `max` (the
    /// device's largest texture): `size`, except where a partition does not
    /// apply to the light and its one map takes the partition's texels:
    /// cascades split only a directional light's view, so a local light gets
    /// one map of the cascades' memory, side × √cascades (4 cascades of
    /// 1024²: one 2048² map per face); `area` maps sample only a light with
    /// an area, so a light without one gets the samples' texels in one map,
    /// side × √area_maps (16 of 1024²: one 4096² map).
    pub fn map_side(&self, light: &Light, max: u32) -> u32 {
        let count = if self.area && light.area.is_none() {
            self.area_maps
        } else if light.kind != LightType::Directional {
            self.cascades.count
        } else {
            1
        };
        let side = (self.size as f32 * (count.max(1) as f32).sqrt()) as u32;
        side.min(max).max(self.size)
    }

    /// These parameters as a frame for `light` renders them: `size` is
    /// [`Self::map_side`], so the fit, the stabilisation, the bias cap and
    /// the maps all take the side the map has.
    pub fn for_light(&self, light: &Light, max: u32) -> ShadowMapConfig {
        ShadowMapConfig {
            size: self.map_side(light, max),
            ..*self
        }
    }

    /// Whether the lookup is edge-masked: asked for, with a filter of taps.
    pub fn edge_masked(&self) -> bool {
        self.edge_mask && self.filter.uses_taps()
    }

    /// Whether the maps store convex part IDs: asked for, with `cull`
    /// (as the maps' shape makes it) storing solids' back faces, a filter
    /// that compares depths, a depth format (not `r8`), no paging and not the
    /// `floor` stage.
    pub fn uses_part_ids(&self, cull: CullFace) -> bool {
        self.part_ids
            && cull == CullFace::Solids
            && !self.filter.is_moment()
            && self.format != DepthFormat::R8
            && !self.paging.is_paged()
            && self.stage != Stage::Floor
    }

    /// The box-blur radius of moment maps (0 for depth maps).
    pub fn moment_blur(&self) -> u32 {
        if self.filter.is_moment() {
            self.blur
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn reach(settings: &[(&str, &str)]) -> f32 {
        config(settings).kernel_reach()
    }

    fn config(settings: &[(&str, &str)]) -> ShadowMapConfig {
        let mut p = ParamValues::defaults(PARAMS);
        for (k, v) in settings {
            p.set(k, v).unwrap();
        }
        ShadowMapConfig::parse(&p).unwrap()
    }

    /// Cascades keep their side under the sun; a local light gets one map
    /// of their memory (4 × 1024² = 2048², 2 × 1024² ≈ 1448²), at most the
    /// device's side; one cascade changes nothing; area maps under a light
    /// without an area become one map of their texels (16 × 1024² = 4096²).
    #[test]
    fn a_partition_that_does_not_apply_gives_its_texels_to_one_map() {
        let sun = Light::directional(Vec3::NEG_Y, 1.0);
        let spot = Light::spot(Vec3::Y, Vec3::ZERO, 1.0, 20.0, 30.0);
        let point = Light::point(Vec3::Y, 1.0);
        let csm = config(&[("cascades", "4"), ("size", "1024")]);
        assert_eq!(csm.map_side(&sun, 16384), 1024);
        assert_eq!(csm.map_side(&spot, 16384), 2048);
        assert_eq!(csm.map_side(&point, 16384), 2048);
        assert_eq!(csm.map_side(&point, 1536), 1536);
        let two = config(&[("cascades", "2"), ("size", "1024")]);
        assert_eq!(two.map_side(&spot, 16384), 1448);
        let one = config(&[("size", "1024")]);
        assert_eq!(one.map_side(&spot, 16384), 1024);
        let area = config(&[("area", "true"), ("size", "1024")]);
        assert_eq!(area.map_side(&spot, 16384), 4096);
        let soft = Light {
            area: Some(crate::scene::LightArea::Sphere { radius: 0.2 }),
            ..spot
        };
        assert_eq!(area.map_side(&soft, 16384), 1024);
    }

    /// The reach is the farthest tap plus a 2×2 tap's half texel, by hand:
    /// a 5×5 grid of radius 1.5 has its outer taps at ±0.8 · 1.5 = 1.2; a
    /// 4² Vogel disk of radius 2.5 its last at √(15.5/16) · 2.5 = 2.46063.
    #[test]
    fn the_kernel_reach_is_the_farthest_tap_and_half_a_texel() {
        let close = |a: f32, b: f32| (a - b).abs() < 1e-4;
        assert!(close(
            reach(&[("filter", "grid"), ("samples", "5"), ("radius", "1.5")]),
            1.7
        ));
        assert!(close(reach(&[("filter", "grid"), ("samples", "1")]), 0.5));
        assert!(close(
            reach(&[("filter", "disk"), ("samples", "4"), ("radius", "2.5")]),
            2.96063
        ));
        assert!(close(reach(&[("filter", "hard")]), 0.0));
        assert!(close(reach(&[("filter", "vsm")]), 0.5));
    }
}
