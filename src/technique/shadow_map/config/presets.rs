//! The shadow-map family's presets: named sets of parameter values (the
//! table in [`crate::technique::shadow_map::config`]). Each value names its
//! parameter through the table's own constant, so a misspelt parameter
//! does not compile; the values are checked by `every_preset_is_valid_for_its_table`.

use super::bias::{NORMAL_OFFSET_DIRECTIONAL, SLOPE_BIAS_CLAMP};
use super::paging::PAGING;
use super::partition::{BLEND, CASCADES, FIT, SELECT, SPLIT_LAMBDA, STABILIZE, WARP};
use super::{AREA, FILTER, FORMAT, RADIUS, SAMPLES, SIZE};
use crate::technique::Preset;
use crate::technique::params::ParamSpec;

pub const PRESETS: &[Preset] = &[
    Preset {
        name: "pcf",
        summary: "3×3 grid of hardware 2×2 PCF taps over ±1.5 texels, 2048², d32f",
        values: &[],
    },
    Preset {
        name: "hard",
        summary: "nearest texel, no filtering: a failure demonstration of the texel staircase wherever one texel covers many pixels (unfiltered, its steps reach past any edge band)",
        values: &[(FILTER.name, "hard")],
    },
    Preset {
        name: "pcf2x2",
        summary: "one hardware bilinear comparison",
        values: &[(FILTER.name, "pcf2x2")],
    },
    Preset {
        name: "pcf-disk",
        summary: "16 taps on a per-pixel rotated Vogel disk of radius 1.75 texels",
        values: &[
            (FILTER.name, "disk"),
            (SAMPLES.name, "4"),
            (RADIUS.name, "1.75"),
        ],
    },
    Preset {
        name: "pcss",
        summary: "percentage-closer soft shadows",
        values: &[(FILTER.name, "pcss"), (SAMPLES.name, "5")],
    },
    Preset {
        name: "varwidth",
        summary: "the documents' variable-width PCF",
        values: &[(FILTER.name, "varwidth"), (SAMPLES.name, "4")],
    },
    Preset {
        name: "vsm",
        summary: "variance shadow map, 1024², blurred",
        values: &[(FILTER.name, "vsm"), (SIZE.name, "1024")],
    },
    Preset {
        name: "esm",
        summary: "exponential shadow map, 1024², blurred",
        values: &[(FILTER.name, "esm"), (SIZE.name, "1024")],
    },
    Preset {
        name: "evsm2",
        summary: "exponential variance shadow map, positive warp only",
        values: &[(FILTER.name, "evsm2"), (SIZE.name, "1024")],
    },
    Preset {
        name: "evsm4",
        summary: "exponential variance shadow map, both warps",
        values: &[(FILTER.name, "evsm4"), (SIZE.name, "1024")],
    },
    Preset {
        name: "msm",
        summary: "4-moment Hamburger shadow map",
        values: &[(FILTER.name, "msm"), (SIZE.name, "1024")],
    },
    Preset {
        name: "translucent",
        summary: "the pcf default, with translucent casters in transmittance maps beside the depth: glass lets its share of the light through",
        values: &[(ParamSpec::BLENDED_CASTERS.name, "transmit")],
    },
    Preset {
        name: "area",
        summary: "soft shadows: 16 maps from stratified points of the light's area, averaged",
        values: &[
            (AREA.name, "true"),
            (FILTER.name, "pcf2x2"),
            (SIZE.name, "1024"),
        ],
    },
    Preset {
        name: "csm",
        summary: "4 stabilised cascades of 1024² fitted to the view frustum (the memory of one 2048² map), λ 0.95 (Sascha Willems' sample), each pixel in the finest map that holds it (select=map), 5 % blended, normal offset ¾ texel of each cascade",
        values: &[
            (CASCADES.name, "4"),
            (SIZE.name, "1024"),
            (SPLIT_LAMBDA.name, "0.95"),
            (BLEND.name, "0.05"),
            (SELECT.name, "map"),
            (FIT.name, "frustum"),
            (NORMAL_OFFSET_DIRECTIONAL.name, "0.75"),
        ],
    },
    Preset {
        name: "psm",
        summary: "one 2048² map in the camera's post-perspective space (PSM, virtual camera behind the casters), normal offset 1 texel (warped maps have no bias cap)",
        values: &[(WARP.name, "psm"), (NORMAL_OFFSET_DIRECTIONAL.name, "1")],
    },
    Preset {
        name: "lispsm",
        summary: "one 2048² map warped by a light-space perspective (LiSPSM, n_opt), normal offset 1 texel",
        values: &[(WARP.name, "lispsm"), (NORMAL_OFFSET_DIRECTIONAL.name, "1")],
    },
    Preset {
        name: "tsm",
        summary: "one 2048² map warped by the trapezoid around the view (TSM, the 80 % rule, focus up to √(z_n·z_f)), normal offset 1 texel",
        values: &[(WARP.name, "tsm"), (NORMAL_OFFSET_DIRECTIONAL.name, "1")],
    },
    Preset {
        name: "pssm",
        summary: "parallel-split maps: 4 cascades of 1024² fitted to their slices, λ 0.6 (bgfx), normal offset ¾ texel",
        values: &[
            (CASCADES.name, "4"),
            (SIZE.name, "1024"),
            (SPLIT_LAMBDA.name, "0.6"),
            (STABILIZE.name, "false"),
            (FIT.name, "frustum"),
            (NORMAL_OFFSET_DIRECTIONAL.name, "0.75"),
        ],
    },
    Preset {
        name: "sdsm",
        summary: "sample distribution shadow maps: 4 cascades of 1024² split over the depths the camera sees and fitted to the pixels each shades (GPU reduction of the prepass), λ 0.95, 10 % blended, normal offset ½ texel",
        values: &[
            (CASCADES.name, "4"),
            (SIZE.name, "1024"),
            (SPLIT_LAMBDA.name, "0.95"),
            (BLEND.name, "0.1"),
            (FIT.name, "samples"),
        ],
    },
    Preset {
        name: "virtual",
        summary: "virtual shadow map: 16384² per clipmap level (directional) or view, 128² pages from a pool of 4096, cached across frames, 3×3 PCF grid, the family's slope bias capped at 20 texel widths of each clipmap level, normal offset ¾ texel of each level under a directional light",
        values: &[
            (PAGING.name, "virtual"),
            (SLOPE_BIAS_CLAMP.name, "20"),
            (NORMAL_OFFSET_DIRECTIONAL.name, "0.75"),
        ],
    },
    Preset {
        name: "adaptive",
        summary: "adaptive shadow map (Fernando et al. 2001) on the virtual map's pages: each pixel starts at its view's coarsest level and is refined a level at a time, up to the level the virtual map reads (`texels_per_pixel`), only where its kernel sees a shadow edge; 3×3 PCF grid, the family's slope bias capped at 20 texel widths of each level, normal offset ¾ texel of each level under a directional light",
        values: &[
            (PAGING.name, "adaptive"),
            (SLOPE_BIAS_CLAMP.name, "20"),
            (NORMAL_OFFSET_DIRECTIONAL.name, "0.75"),
        ],
    },
    Preset {
        name: "8bit",
        summary: "depth stored in 8 bits: acne everywhere",
        values: &[(FORMAT.name, "r8"), (FILTER.name, "hard")],
    },
];
