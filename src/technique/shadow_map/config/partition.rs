//! The parameters that partition and warp a directional light's map:
//! cascades (count, split scheme, reach, stabilisation, blending), what
//! they are fitted to (SDSM), and the warps (PSM, LiSPSM, TSM).

use crate::technique::params::{Condition, LightKinds, choice_enum};
use crate::technique::{ParamSpec, ParamValues};
use anyhow::Result;

choice_enum! {
    /// Warping of a directional light's maps.
    pub enum Warp { None = "none", Psm = "psm", Lispsm = "lispsm", Tsm = "tsm" }
}

choice_enum! {
    /// How a directional light's single map is turned about the light.
    pub enum Roll { Up = "up", Square = "square" }
}

choice_enum! {
    /// How a pixel's cascade is chosen.
    pub enum Select { Depth = "depth", Map = "map" }
}

choice_enum! {
    /// What a directional light's cascades are fitted to.
    pub enum Fit { Frustum = "frustum", Depth = "depth", Samples = "samples" }
}

pub const CASCADES: ParamSpec = ParamSpec::int(
    "cascades",
    1,
    1,
    8,
    "directional lights: maps partitioning the view depth (cascaded / parallel-split maps, Zhang et al. 2006), each `size`²",
)
.for_lights(LightKinds::DIRECTIONAL);

pub const SPLIT_LAMBDA: ParamSpec = ParamSpec::float(
    "split_lambda",
    0.5,
    0.0,
    1.0,
    0.05,
    "cascade split scheme: z_i = λ·n·(f/n)^(i/N) + (1−λ)·(n + (f−n)·i/N); 1 logarithmic, 0 uniform",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::IsNot("cascades", &["1"]));

pub const MAX_DISTANCE: ParamSpec = ParamSpec::float(
    "max_distance",
    0.0,
    0.0,
    100000.0,
    1.0,
    "cascades: view distance the last cascade ends at (0 = where the camera's view of the scene ends); beyond it the lookup is lit",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::IsNot("cascades", &["1"]));

pub const STABILIZE: ParamSpec = ParamSpec::boolean(
    "stabilize",
    true,
    "directional lights: texel edges stay in place when the camera moves or turns — cascades are bounding spheres snapped to whole texels (or, on an axis where that square is wider than the scene seen from the light, the scene's box); one map's fitted window has each side rounded up to eighths of an octave and its centre snapped, and keeps last frame's side while it holds the view and is at most a quarter octave larger",
)
.for_lights(LightKinds::DIRECTIONAL);

pub const BLEND: ParamSpec = ParamSpec::float(
    "blend",
    0.0,
    0.0,
    0.5,
    0.05,
    "cascades: fraction of each cascade's depth range, at its far end, blended into the next cascade",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::IsNot("cascades", &["1"]));

pub const SELECT: ParamSpec = ParamSpec::choice_of::<Select>(
    "select",
    Select::Depth as usize,
    "cascades: how a pixel's cascade is chosen — depth: by its view depth against the split distances, the blend band the far `blend` fraction of each cascade's depth range; map: the finest cascade whose map holds it (kernel's reach and a texel inside the border, within the depth range; Microsoft's map-based selection), the blend band the outer `blend` fraction of that map. Split distances move with the camera, so depth selection moves pixels between cascades on a dolly; stabilised maps move only in whole texels",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::IsNot("cascades", &["1"]));

/// Fits and turns of a map that directional lights and focused spot
/// lights have.
const DIRECTIONAL_AND_SPOT: LightKinds = LightKinds {
    point: false,
    spot: true,
    directional: true,
};

pub const FIT: ParamSpec = ParamSpec::choice_of::<Fit>(
    "fit",
    Fit::Samples as usize,
    "what the map, or each cascade, is fitted to — frustum: the view frustum up to max_distance (one map: up to where the view of the scene ends), clipped to the scene; unstabilised cascades split the view depths where the frustum meets the scene's clusters (a camera on a floor sees nothing before the floor meets the frustum's lower plane); depth: the view depths the camera sees (SDSM, Lauritzen, Salvi & Lefohn 2011: min/max of a GPU reduction of the prepass depth); samples: those depths and the light-view box of the pixels the map shades. One directional map fitted to samples is stabilised with hysteresis: a fresh fit takes a quarter octave of room and is kept through a quarter-octave jump either way, up to 2^(5/8) times what it needs (the pixels' box jumps when a far feature comes into view); cascades fitted so are not stabilised; one warped map (psm, lispsm, tsm) warps the view between the depths the camera sees under depth and samples (under samples only its part inside the prism along the light around the pixels it shades: Wimmer's body B cut to them), the whole view under frustum. Spot lights (one map, no area sampling): samples focuses the map on the pixels the spot reaches, a stabilised, turned square of its image inside the cone's; frustum focuses it alike on what the view frustum can hold of the cone (up to where the view leaves the scene, inside the scene); depth keeps the whole cone. Measurements wait for the reduction; the viewer uses the previous frame's, widened",
)
.for_lights(DIRECTIONAL_AND_SPOT);

pub const ROLL: ParamSpec = ParamSpec::choice_of::<Roll>(
    "roll",
    Roll::Square as usize,
    "how one unwarped directional map, or a spot map focused with fit=samples, is turned about the light — up: the world's up along the map's y axis (every vertical edge then lies along a texel column, where no filter recovers its sub-texel place); square: the turn, in steps of 11.25°, with the smallest square around what the map covers among those that keep the world's vertical 15° and its x and z axes 8° off the texel axes, last frame's kept while at most an eighth of an octave larger; the map then covers that turn's box, so texels along its shorter side are finer; a spot's perspective turns the world's axes across its image, so they are kept clear at the corners and centre of the box of the pixels seen",
)
.for_lights(DIRECTIONAL_AND_SPOT);

pub const WARP: ParamSpec = ParamSpec::choice_of::<Warp>(
    "warp",
    Warp::None as usize,
    "directional lights: none; psm — the map in the camera's post-perspective space, where the light becomes a point (Stamminger & Drettakis 2002), from a virtual camera moved back behind every caster; lispsm — a perspective inside the light's view along the view direction (Wimmer, Scherzer & Purgathofer 2004) that gives the surfaces near the camera more of the map; tsm — the trapezoid around the view in the light's image mapped onto the square (Martin & Tan 2004); one per cascade with cascades > 1, over the part of the view inside the scene; warped maps store depth linear along the light (biased in the depth pass's fragment stage) and are not stabilised",
)
.for_lights(LightKinds::DIRECTIONAL);

pub const LISPSM_N: ParamSpec = ParamSpec::float(
    "lispsm_n",
    0.0,
    0.0,
    100000.0,
    0.5,
    "lispsm: distance of the projection centre before the view (0 = n_opt = (z_n + √(z_n·z_f)) / sin γ); larger is closer to the uniform map",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::Is("warp", &["lispsm"]));

pub const TSM_FOCUS: ParamSpec = ParamSpec::float(
    "tsm_focus",
    0.0,
    0.0,
    1.0,
    0.01,
    "tsm: where the focus region that the trapezoid maps onto 80 % of the map (Martin & Tan's 80 % rule) ends, as a fraction of the view's depth range inside the scene; 0 = at √(z_n·z_f), the depth LiSPSM's n_opt balances around, whatever the scene's scale",
)
.for_lights(LightKinds::DIRECTIONAL)
.when(Condition::Is("warp", &["tsm"]));

/// A directional light's warp and its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarpParams {
    pub kind: Warp,
    /// LiSPSM's projection-centre distance (0: n_opt).
    pub lispsm_n: f32,
    /// TSM's focus region (fraction of the view's depth range; 0: √(z_n·z_f)).
    pub tsm_focus: f32,
}

impl WarpParams {
    pub fn parse(p: &ParamValues) -> Result<WarpParams> {
        Ok(WarpParams {
            kind: p.choice(&WARP)?,
            lispsm_n: p.float(&LISPSM_N)?,
            tsm_focus: p.float(&TSM_FOCUS)?,
        })
    }
}

/// How a directional light's map is partitioned along the view depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cascades {
    /// Number of maps (1: one map fitted to the view of the scene).
    pub count: u32,
    /// Logarithmic (1) to uniform (0) split distances.
    pub split_lambda: f32,
    /// View distance of the last split (0: the camera's reach).
    pub max_distance: f32,
    /// Bounding-sphere maps snapped to whole texels.
    pub stabilize: bool,
    /// Fraction of each cascade blended into the next.
    pub blend: f32,
    /// How a pixel's cascade is chosen.
    pub select: Select,
    /// The view frustum, or what the camera sees (SDSM).
    pub fit: Fit,
}

impl Cascades {
    /// The farthest view depth a split may take: `max_distance` when set,
    /// else the camera's far plane (SDSM's reduction on the GPU and the
    /// split on the CPU must agree on it).
    pub fn far_limit(&self, camera_far: f32) -> f32 {
        if self.max_distance > 0.0 {
            self.max_distance.min(camera_far)
        } else {
            camera_far
        }
    }

    pub fn parse(p: &ParamValues) -> Result<Cascades> {
        Ok(Cascades {
            count: p.int(&CASCADES)?,
            split_lambda: p.float(&SPLIT_LAMBDA)?,
            max_distance: p.float(&MAX_DISTANCE)?,
            stabilize: p.flag(&STABILIZE)?,
            blend: p.float(&BLEND)?,
            select: p.choice(&SELECT)?,
            fit: p.choice(&FIT)?,
        })
    }
}
