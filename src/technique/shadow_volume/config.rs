//! The shadow-volume family's parameter table and its typed reading
//! ([`VolumeConfig`]).

use crate::frame::Compose;
use crate::technique::params::{Condition, LightKinds, choice_enum};
use crate::technique::{ParamSpec, ParamValues, Preset};
use anyhow::Result;

choice_enum! {
    /// How the volumes are counted.
    pub enum Method { ZPass = "zpass", ZFail = "zfail", Auto = "auto" }
}
choice_enum! {
    /// Which volumes a caster extrudes.
    pub enum SilhouetteMode { Auto = "auto", Edges = "edges", Triangles = "triangles" }
}
choice_enum! {
    /// Where silhouettes are found and volumes extruded.
    pub enum Extrusion { Gpu = "gpu", Cpu = "cpu" }
}
choice_enum! {
    /// How volumes extruded to infinity escape far-plane clipping.
    pub enum FarPlane { Infinite = "infinite", DepthClamp = "depth-clamp", Clip = "clip" }
}
choice_enum! {
    /// One two-sided stencil draw or two single-sided ones.
    pub enum StencilMode { TwoSided = "two-sided", TwoPass = "two-pass" }
}

pub const METHOD: ParamSpec = ParamSpec::choice_of::<Method>(
    "method",
    Method::Auto as usize,
    "zpass: count volume faces in front of each pixel (fails when the camera is in a shadow); zfail: count those behind (Carmack's reverse; caps needed); auto: z-fail only for casters whose volume can contain part of the near-plane rectangle, or that the camera sees through (cut-out and translucent casters: a view ray through their holes enters the volume through its light cap, which z-pass does not count)",
);
pub const SILHOUETTE: ParamSpec = ParamSpec::choice_of::<SilhouetteMode>(
    "silhouette",
    SilhouetteMode::Auto as usize,
    "edges: side quads on silhouette edges (exact for closed meshes); triangles: every triangle extrudes its own closed volume (exact for any mesh, more fill); auto: edges for closed meshes, triangles for the others (reported in the log)",
);
pub const EXTRUSION: ParamSpec = ParamSpec::choice_of::<Extrusion>(
    "extrusion",
    Extrusion::Gpu as usize,
    "gpu: a compute shader finds silhouettes and writes the volumes into an index buffer drawn with draw-indirect; cpu: the same on the CPU (rayon), uploaded every frame",
);
pub const LENGTH: ParamSpec = ParamSpec::float(
    "length",
    0.0,
    0.0,
    100000.0,
    0.5,
    "extrusion length in world units; 0 extrudes to infinity (w = 0)",
);
pub const FAR_PLANE: ParamSpec = ParamSpec::choice_of::<FarPlane>(
    "far_plane",
    FarPlane::Infinite as usize,
    "how volumes extruded to infinity escape far-plane clipping: a projection with the far plane at infinity, or depth clamping (unclipped_depth; falls back to infinite where the adapter lacks it); clip: they do not — the camera's finite far plane cuts them, z-fail's documented failure",
)
.when(Condition::Is("length", &["0"]));

pub const CAPS: ParamSpec = ParamSpec::boolean(
    "caps",
    true,
    "close z-fail volumes with their light and dark caps; false leaves them open — z-fail's documented failure (counts go wrong wherever a cap was needed)",
);
pub const STENCIL: ParamSpec = ParamSpec::choice_of::<StencilMode>(
    "stencil",
    StencilMode::TwoSided as usize,
    "two-sided: both faces in one draw with wrapping increment/decrement; two-pass: front and back faces in two draws with saturating operations",
);
pub const SCISSOR: ParamSpec = ParamSpec::boolean(
    "scissor",
    true,
    "restrict the stencil work to the screen rectangle of an attenuated light's range",
)
.for_lights(LightKinds::LOCAL);
pub const CULL_CASTERS: ParamSpec = ParamSpec::boolean(
    "cull_casters",
    true,
    "skip casters whose volume cannot touch the view frustum",
);

/// The shadow-volume family's parameters, parsed.
#[derive(Clone, Copy, Debug)]
pub struct VolumeConfig {
    pub method: Method,
    pub silhouette: SilhouetteMode,
    pub extrusion: Extrusion,
    /// World units; 0 = to infinity.
    pub length: f32,
    pub far_plane: FarPlane,
    /// Light and dark caps on volumes that need them (false: the failure case).
    pub caps: bool,
    pub stencil: StencilMode,
    pub scissor: bool,
    pub cull_casters: bool,
    /// Mask value inside a shadow (1 − darkening).
    pub visibility: f32,
    pub compose: Compose,
}

impl VolumeConfig {
    pub fn parse(p: &ParamValues) -> Result<VolumeConfig> {
        Ok(VolumeConfig {
            method: p.choice(&METHOD)?,
            silhouette: p.choice(&SILHOUETTE)?,
            extrusion: p.choice(&EXTRUSION)?,
            length: p.float(&LENGTH)?,
            far_plane: p.choice(&FAR_PLANE)?,
            caps: p.flag(&CAPS)?,
            stencil: p.choice(&STENCIL)?,
            scissor: p.flag(&SCISSOR)?,
            cull_casters: p.flag(&CULL_CASTERS)?,
            visibility: 1.0 - p.float(&ParamSpec::DARKENING)?,
            compose: p.choice(&ParamSpec::COMPOSE)?,
        })
    }
}

/// Every parameter, in table order.
pub const PARAMS: &[ParamSpec] = &[
    METHOD,
    SILHOUETTE,
    EXTRUSION,
    LENGTH,
    FAR_PLANE,
    CAPS,
    STENCIL,
    SCISSOR,
    CULL_CASTERS,
    ParamSpec::DARKENING,
    ParamSpec::COMPOSE,
];

pub const PRESETS: &[Preset] = &[
    Preset {
        name: "auto",
        summary: "hybrid: z-fail only where a volume can contain the near plane or the camera sees through the caster; per-triangle volumes for meshes that are not closed; GPU extrusion",
        values: &[],
    },
    Preset {
        name: "zpass",
        summary: "z-pass counting (fails with the camera inside a shadow)",
        values: &[(METHOD.name, "zpass")],
    },
    Preset {
        name: "zfail",
        summary: "z-fail counting (Carmack's reverse) with caps",
        values: &[(METHOD.name, "zfail")],
    },
    Preset {
        name: "zfail-open",
        summary: "z-fail without caps: the documents' failure case for open volumes",
        values: &[(METHOD.name, "zfail"), (CAPS.name, "false")],
    },
    Preset {
        name: "zfail-far-clip",
        summary: "z-fail with the camera's far plane clipping the volumes: the documents' failure case for a finite far plane",
        values: &[(METHOD.name, "zfail"), (FAR_PLANE.name, "clip")],
    },
    Preset {
        name: "edges",
        summary: "silhouette volumes for every mesh, closed or not (z-fail): shows what open meshes get wrong",
        values: &[(METHOD.name, "zfail"), (SILHOUETTE.name, "edges")],
    },
    Preset {
        name: "triangles",
        summary: "every triangle extrudes its own volume: exact for open and non-manifold meshes",
        values: &[(SILHOUETTE.name, "triangles")],
    },
    Preset {
        name: "cpu",
        summary: "auto with CPU silhouettes and extrusion",
        values: &[(EXTRUSION.name, "cpu")],
    },
    Preset {
        name: "darken",
        summary: "the documents' look: one lit pass, shadows darkened to half",
        values: &[
            (ParamSpec::COMPOSE.name, "darken"),
            (ParamSpec::DARKENING.name, "0.5"),
        ],
    },
];
