//! The shadow-map family's depth-bias parameters: the constant and
//! slope-scaled bias of the depth pass and its caps, the lookup's normal
//! offset and the receiver plane (the guide's shadow-map page gives the
//! measured reasons for each default).

use crate::technique::ParamSpec;
use crate::technique::params::{Condition, LightKinds};

pub const DEPTH_BIAS: ParamSpec = ParamSpec::float(
    "depth_bias",
    2.0,
    0.0,
    100000.0,
    1.0,
    "constant depth bias of the depth pass, in the format's smallest steps",
);

pub const SLOPE_BIAS: ParamSpec = ParamSpec::float(
    "slope_bias",
    2.0,
    0.0,
    20.0,
    0.1,
    "slope-scaled depth bias (polygon offset factor)",
);

pub const SLOPE_BIAS_CLAMP: ParamSpec = ParamSpec::float(
    "slope_bias_clamp",
    5.0,
    0.0,
    64.0,
    0.25,
    "directional maps (one map, cascades or a virtual clipmap, unwarped): the depth bias is capped at this many texel widths of depth (the depth step across one texel of a 45° surface, per cascade or clipmap level), so that casters lit at grazing angles do not push their stored depth far behind them and leak light onto what they shade; 0 = no cap",
)
.for_lights(LightKinds::DIRECTIONAL);

pub const SLOPE_BIAS_CLAMP_LOCAL: ParamSpec = ParamSpec::float(
    "slope_bias_clamp_local",
    10.0,
    0.0,
    64.0,
    0.25,
    "spot lights and cube faces: the depth bias is capped at this many texel widths of depth at the map's mean distance √(near·far) (fewer nearer the light, more beyond it: one cap per map in perspective depth), so that casters lit at grazing angles do not push their stored depth behind what they shade (a concave surface shadowing itself near its terminator); a lower cap brings back acne on surfaces lit at grazing angles; 0 = no cap",
)
.for_lights(LightKinds::LOCAL);

pub const NORMAL_OFFSET_DIRECTIONAL: ParamSpec = ParamSpec::float(
    "normal_offset_directional",
    0.5,
    0.0,
    10.0,
    0.05,
    "directional lights: lookup point moved along the geometric normal, in shadow-map texels, × sinⁿθ (`normal_offset_power`); near a concave surface's terminator a receiver lies within a texel of its own silhouette in the map, where a 2×2 comparison straddles it and reads the ground past it as lit: the offset moves the lookup to the surface's side; more moves shadow edges on receivers lit at grazing angles; none on receivers with a part (part_ids) and, under cull=solids, on solids whose lit faces the map does not store (convex ones; every one with solid_front_bias=0), half on concave solids whose front faces it stores",
)
.for_lights(LightKinds::DIRECTIONAL);

pub const NORMAL_OFFSET_POWER: ParamSpec = ParamSpec::float(
    "normal_offset_power",
    8.0,
    0.0,
    16.0,
    1.0,
    "the normal offset scaled by sinⁿθ between the normal and the light, n this power (full at grazing light, none facing it): 0 moves every receiver by the whole offset, 1 is Holbert's normal-offset shadows (sin θ); a higher power keeps the offset where a receiver lies within a texel of its own silhouette in the map (grazing light) and away from the shadow edges on receivers lit at moderate angles",
);

pub const NORMAL_OFFSET_LOCAL: ParamSpec = ParamSpec::float(
    "normal_offset_local",
    0.5,
    0.0,
    10.0,
    0.1,
    "point and spot lights: lookup point moved along the geometric normal, in shadow-map texels at the point's distance, × sinⁿθ (`normal_offset_power`; see normal_offset_directional); none on receivers with a part (part_ids) and, under cull=solids, on solids whose lit faces the map does not store (convex ones; every one with solid_front_bias=0), half on concave solids whose front faces it stores",
)
.for_lights(LightKinds::LOCAL);

pub const RECEIVER_PLANE: ParamSpec = ParamSpec::boolean(
    "receiver_plane",
    true,
    "receiver-plane depth bias (Isidoro 2006) on receivers without a convex part (part_ids): each kernel tap is compared against the receiver's plane (from its geometric normal) at the tap's centre, not against one depth, so that a kernel wider than the slope bias covers does not reach the receiver's own curved surface (grid, disk, pcss, varwidth); pcf2x2 and hard compare each texel at its centre; a receiver with a part ignores its own texels instead, and keeps one depth, which a plane carried past its edge would pass under a surface that meets it there; the plane passes in front of a caster that touches the receiver at a steep angle (a trunk under its canopy); every map takes the plane from the surface's normal over the kernel's reach",
)
.when(Condition::IsNot("filter", &["vsm", "esm", "evsm2", "evsm4", "msm"]));

pub const CREASE_ANGLE: ParamSpec = ParamSpec::float(
    "crease_angle",
    30.0,
    0.0,
    45.0,
    0.5,
    "receiver_plane: the angle, in degrees, that a surface may rise out of the receiver's plane (a concave crease between facets) before a kernel tap reads it as a caster: each tap's compared depth sinks below the plane by what such a rise over the tap's distance from the lookup point comes to along the light's ray (1/(N·L) as much as along the normal, at most 5 times); a faceted surface (a terrain mesh, a tessellated body) rises out of its own facet's plane within the kernel's reach, where taps read it as a caster and speckle the surface with partial shadow; the wall of a boss or dome rising from a lit receiver (a concave crease between surfaces) no longer rings its base with partial shadow; the taps are forgiven only where the receiver's own texel is lit, so a low caster whose shadow covers that texel (raised lettering under grazing light, stored by its back faces close above the receiver) still shadows it; 0 = the plane alone",
)
.when(Condition::Is("receiver_plane", &["true"]));
