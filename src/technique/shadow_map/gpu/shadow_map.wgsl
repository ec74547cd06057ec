// Shadow maps ([000] §4, [001] §3, [002] §2): the uniform, bindings and projections shared by
// the depth pass (depth_pass.wgsl), the filters (filters.wgsl), the
// screen-space lookup that writes the visibility mask (lookup.wgsl) and the
// debug views (debug.wgsl), composed in that order after common.wgsl,
// gbuffer.wgsl and the `FILTER_*` constants generated from the `Filter`
// enum.

// Specialisation (pipeline-overridable constants, set per pipeline by
// pipelines.rs): the filter, taps per side, the 8-bit map, the
// receiver-plane bias and the maps' shape are constants of each pipeline.
override FILTER_KIND: u32 = FILTER_GRID;
override TAPS: u32 = 3u;
override BYTE_MAP: bool = false;
override RECEIVER_PLANE: bool = false;
// Edge-masked filtering: the kernel runs only where the bounds chain
// (binding 7) cannot tell the answer.
override EDGE_MASK: bool = false;
// A virtual map (virtual_map.wgsl): texels are read through the page table
// from the physical pool bound as `depth_map`.
override VIRTUAL: bool = false;
// A virtual map whose pages, as this frame's marks asked for them, are all
// resident: the lookup filters each pixel's marked level without looking
// for a coarser resident one.
override MARKED_RESIDENT: bool = false;
// A virtual map whose kernel can read more than 2×2 pages (its marked reach
// spans a page): taps beyond the pixel's first 2×2 read the page table.
override WIDE_KERNEL: bool = false;
// The maps' shape (`MapShape`): how the faces project (`PROJECTION_*`),
// whether they are cascades, whether they are warped. llvmpipe runs both
// sides of a branch on a uniform under a lane mask: as constants, a
// pipeline holds only its own shape's code.
override PROJECTION: u32 = PROJECTION_PERSPECTIVE;
override CASCADED: bool = false;
override WARPED: bool = false;
// `part_ids`: the maps store each texel's convex part (binding 12), and a
// receiver facing the light ignores its own part's texels.
override PART_IDS: bool = false;

struct ShadowMap {
    // world → light clip, one per face (1 for spot/directional, 6 for point,
    // one per cascade)
    faces: array<mat4x4f, 8>,
    // xyz light position, w 1 where receivers on solids take no normal
    // offset (`cull=solids`: their own surfaces are not in the map); the
    // faces' layout is `PROJECTION`: one,
    // six cube faces, or two paraboloid hemispheres whose `faces` are their
    // view matrices)
    light: vec4f,
    // x filter radius (texels), y normal offset (texels), z slope-scaled
    // bias of warped depth passes (per depth slope per pixel), w the power n
    // of the normal offset's sinⁿθ between normal and light
    kernel: vec4f,
    // x map size, y 1/size, z world size of a texel at unit distance
    // (perspective, paraboloid) or of any texel (orthographic), w the
    // filter's reach in texels (`ShadowMapConfig::kernel_reach`: how far
    // a lookup's taps spread)
    map: vec4f,
    // x light size (texels at unit depth ratio, pcss), y variable-width scale,
    // z variable-width exponent, w blocker-search radius (texels)
    soft: vec4f,
    // x near, y far (to linearise perspective depth), z area-light radius
    // for pcss (0 = use soft.x), w constant bias of warped depth passes
    depth: vec4f,
    // x face rendered by the depth pass (or blurred), y blur axis (0 x, 1 y),
    // z blur radius (texels), w unused
    face: vec4u,
    // moments: x light-bleeding reduction, y exponent c (esm in log space,
    // evsm +), z exponent c− (evsm), w moment bias (msm)
    moments: vec4f,
    // x cascades (0 when not `CASCADED`), y fraction of each cascade blended into
    // the next, z view depth where the first cascade starts, w 1 where the
    // maps choose the cascade (`select=map`), 0 where the view depth does
    cascade: vec4f,
    // view depth at which cascade i ends: [i / 4][i % 4]
    cascade_far: array<vec4f, 2>,
    // world size of a texel of cascade i: [i / 4][i % 4]
    cascade_texel: array<vec4f, 2>,
    // row z of the view matrix of the camera the cascades were fitted to
    cascade_view_z: vec4f,
    // xyz the direction the light travels, w unused (`WARPED`: the texel
    // size varies over the map)
    warp: vec4f,
    // Warped faces store depth linear along the light, 0 nearest it:
    // dot(row, (p, 1)) — a perspective's z/w would tilt every surface and
    // the slope bias with it.
    warp_depth: vec4f,
    // x the stored depth the moments take as 0, y the scale to 1 (one
    // directional map: the depths its seen receivers span; else 0, 1)
    moment_depth: vec4f,
    // x the widest a shadow edge's ramp may be on screen, in pixels
    // (`edge_ramp_pixels`; 0: as filtered), y the reach in texels of the
    // ramp it steepens (0: none, as under a penumbra), zw unused
    screen: vec4f,
};

@group(2) @binding(0) var<uniform> sm: ShadowMap;
@group(2) @binding(3) var depth_map: texture_depth_2d_array;
@group(2) @binding(4) var compare_sampler: sampler_comparison;
@group(2) @binding(5) var byte_map: texture_2d_array<f32>;
@group(2) @binding(6) var moment_map: texture_2d_array<f32>;
@group(2) @binding(7) var edge_bounds: texture_2d_array<f32>;
// Its part chain: each cell's one part, or MIXED_PART (edge_mask.rs).
@group(2) @binding(14) var edge_parts: texture_2d_array<u32>;
// `part_ids`: the convex part each texel's depth came from (0: none), and
// the nearest-texel sampler that gathers it (and the edge mask's depths).
@group(2) @binding(12) var part_map: texture_2d_array<u32>;
@group(2) @binding(13) var part_sampler: sampler;

// One level of a virtual map: a window of `pages`² pages over its view's
// uv square (see virtual_map.wgsl).
struct VirtualLevel {
    // uv of the window's first texel corner in the view
    origin: vec2f,
    // clipmaps: the camera's texel coordinates in the window
    eye_texel: vec2f,
    // absolute index of the window's first page
    origin_page: vec2i,
    // uv per texel
    texel: f32,
    // the view (face) the level belongs to
    view: u32,
    // pages per side of the window
    pages: u32,
    // first page-table entry of the level
    table: u32,
    // world size of a texel (orthographic) or of a texel at unit distance
    texel_world: f32,
    // the next coarser level of the same view (itself when none)
    parent: u32,
};

struct VirtualMap {
    // clipmaps: the world directions of the view's u and v axes
    axis_u: vec3f,
    // slots per row of one atlas layer
    atlas_pages: u32,
    axis_v: vec3f,
    // texels per page side
    page_texels: u32,
    // pages per atlas layer
    layer_pages: u32,
    // levels per view
    view_levels: u32,
    // texels per side of a pool slot: the page and its guard texels
    slot_texels: u32,
    // levels finer than one texel per pixel that lookups take
    oversample_levels: u32,
    levels: array<VirtualLevel>,
};

// Virtual maps: the pages the visible pixels need (bits), the page table
// (physical page + 1, 0 when none), the levels, each pixel's level.
@group(2) @binding(8) var<storage, read_write> vsm_marks: array<atomic<u32>>;
@group(2) @binding(9) var<storage, read> vsm_table: array<u32>;
@group(2) @binding(10) var<storage, read> vsm: VirtualMap;
@group(2) @binding(11) var<storage, read_write> vsm_pixel_level: array<u32>;


struct DepthOut {
    @builtin(position) clip: vec4f,
    // dual paraboloid: the cosine to the hemisphere's axis (< 0 behind it)
    @location(1) hemisphere: f32,
    // depth linear in distance, 0 at near and 1 at far (moment maps)
    @location(0) linear: f32,
    // the convex part drawn (`part_id`), 0: none
    @location(2) @interpolate(flat) part: u32,
    @location(3) uv: vec2f,
    @location(4) @interpolate(flat) object: u32,
};

// Linear depth in [0, 1] of a light-clip position.
// The depth a moment filter stores and compares: `linear` mapped from the
// window of stored depths the receivers span (`sm.moment_depth`) onto
// [0, 1], so that the filter's exponent or variance works on their depth
// range, not the scene's; casters nearer than the window store 0.
fn moment_depth_of(linear: f32) -> f32 {
    return clamp((linear - sm.moment_depth.x) * sm.moment_depth.y, 0.0, 1.0);
}

fn linear01(c: vec4f) -> f32 {
    if is_orthographic() || is_paraboloid() {
        return c.z; // orthographic, or the paraboloid's linear depth
    }
    return (c.w - sm.depth.x) / (sm.depth.y - sm.depth.x);
}

fn is_paraboloid() -> bool {
    return PROJECTION == PROJECTION_PARABOLOID;
}

fn is_orthographic() -> bool {
    return PROJECTION == PROJECTION_ORTHOGRAPHIC;
}

fn is_warped() -> bool {
    return WARPED;
}

// Dual-paraboloid projection (Brabec et al. 2002) of a world point for
// hemisphere `face`: xy = n.xy / (1 + n_forward), z = linear depth, w = 1;
// returns the forward cosine in `hemisphere`.
fn paraboloid(world: vec4f, face: u32) -> vec4f {
    let p = (sm.faces[face] * world).xyz;
    let d = length(p);
    let n = p / max(d, 1e-6);
    let forward = -n.z;
    return vec4f(n.xy / (1.0 + max(forward, -0.999)), (d - sm.depth.x) / (sm.depth.y - sm.depth.x), 1.0);
}
