//! The parameters of the soft and moment filters: PCSS's light size and
//! blocker search, variable-width PCF's scale and exponent, and the moment
//! maps' blur, light-bleeding reduction, exponents and bias.

use crate::technique::ParamSpec;
use crate::technique::params::Condition;

pub const LIGHT_SIZE: ParamSpec = ParamSpec::float(
    "light_size",
    24.0,
    0.0,
    400.0,
    1.0,
    "pcss under a light without an area, with hard_light_penumbra: the pretended light size, as the penumbra width in texels per unit of (d_receiver − d_blocker)/d_blocker",
)
.when(Condition::Is("filter", &["pcss"]));

pub const HARD_LIGHT_PENUMBRA: ParamSpec = ParamSpec::boolean(
    "hard_light_penumbra",
    false,
    "pcss and varwidth under a light without an area: false keeps the shadow as hard as that light casts it (a kernel of ½ texel, as the ray-traced truth has no penumbra there); true draws the filter's penumbra anyway, as if the light had the size light_size (pcss) or varwidth_scale (varwidth) gives; a light with an area always sets the penumbra itself (pcss) or lets the filter draw it (varwidth)",
)
.when(Condition::Is("filter", &["pcss", "varwidth"]));

pub const BLOCKER_SEARCH: ParamSpec = ParamSpec::float(
    "blocker_search",
    12.0,
    1.0,
    64.0,
    1.0,
    "pcss and varwidth: blocker-search radius in texels",
)
.when(Condition::Is("filter", &["pcss", "varwidth"]));

pub const VARWIDTH_SCALE: ParamSpec = ParamSpec::float(
    "varwidth_scale",
    8.0,
    0.0,
    200.0,
    0.5,
    "varwidth: texels of radius per unit of |d_blocker − d_receiver|^exponent",
)
.when(Condition::Is("filter", &["varwidth"]));

pub const VARWIDTH_EXPONENT: ParamSpec = ParamSpec::float(
    "varwidth_exponent",
    1.0,
    0.1,
    4.0,
    0.1,
    "varwidth: the exponent",
)
.when(Condition::Is("filter", &["varwidth"]));

pub const BLUR: ParamSpec = ParamSpec::int(
    "blur",
    2,
    0,
    16,
    "moment filters: separable box blur radius in texels (0 = none)",
)
.when(Condition::Is(
    "filter",
    &["vsm", "esm", "evsm2", "evsm4", "msm"],
));

pub const BLEEDING_REDUCTION: ParamSpec = ParamSpec::float(
    "bleeding_reduction",
    0.2,
    0.0,
    0.95,
    0.01,
    "vsm and evsm: light-bleeding reduction, the lower cut of the Chebyshev bound",
)
.when(Condition::Is("filter", &["vsm", "evsm2", "evsm4"]));

pub const EXPONENT: ParamSpec = ParamSpec::float(
    "exponent",
    40.0,
    1.0,
    80.0,
    1.0,
    "evsm: exponent c of the positive warp exp(c(z − 1)) (its square must fit a 32-bit float)",
)
.when(Condition::Is("filter", &["evsm2", "evsm4"]));

pub const ESM_EXPONENT: ParamSpec = ParamSpec::float(
    "esm_exponent",
    200.0,
    10.0,
    2000.0,
    10.0,
    "esm: exponent c of exp(c·z), with z over the depths the receivers span; the map holds z and its blur and lookup filter exp(c·z) in log space (Lauritzen 2007), so any c fits a 32-bit float; a larger c bleeds less light and gives a receiver nearer than its filter's occluders more acne",
)
.when(Condition::Is("filter", &["esm"]));

pub const EXPONENT_NEGATIVE: ParamSpec = ParamSpec::float(
    "exponent_negative",
    5.0,
    1.0,
    40.0,
    1.0,
    "evsm4: exponent of the negative warp −exp(−c z)",
)
.when(Condition::Is("filter", &["evsm4"]));

pub const MOMENT_BIAS: ParamSpec = ParamSpec::float(
    "moment_bias",
    3e-5,
    0.0,
    0.01,
    1e-5,
    "msm: moment bias α towards (0.5, 0.5, 0.5, 0.5)",
)
.when(Condition::Is("filter", &["msm"]));
