// SDSM's reduction (Lauritzen, Salvi & Lefohn 2011) over the prepass's
// G-buffer: the least and greatest view depth of the pixels that receive
// shadows (`depth_range`), then, with the cascade splits those depths give,
// each cascade's light-view x/y bounds over the pixels it shades
// (`cascade_bounds`). Each invocation reduces a block of pixels and keeps
// the block's depth range and light-view box in `blocks`, so that the
// second pass reads one record per block and goes back to the pixels only
// for blocks that cross a split. Workgroups reduce in shared memory, then
// one invocation merges into the result with atomics on order-preserving
// bits.

struct ReduceParams {
    // Row z of the fitted camera's view matrix: a point's view depth is
    // −dot(row, (p, 1)).
    view_z: vec4f,
    // The light's view (world → light view space).
    light_view: mat4x4f,
    // x cascade count, y split λ, z camera near, w the farthest split allowed.
    split: vec4f,
    // x, y: blocks of TILE×TILE pixels along x and y (the frame's, rounded
    // up); z, w unused.
    blocks: vec4u,
    // A spot light (x > 0): x the tangent of its cone's half-angle, yzw its
    // position; `light_view` is its view, and the supports are taken in its
    // image (x/−z, y/−z) over the pixels it reaches.
    spot: vec4f,
};

@group(0) @binding(0) var positions: texture_2d<f32>;
@group(0) @binding(1) var normals: texture_2d<f32>;
@group(0) @binding(2) var<uniform> params: ReduceParams;
// [0] least depth, [1] greatest depth, then per cascade i at 2 + 4i: least
// x, least y, greatest x, greatest y, then at SUPPORT_WORD + 2k the least
// and greatest extent along support direction k — all as `ordered` bits.
@group(0) @binding(3) var<storage, read_write> bounds: array<atomic<u32>>;
// Per block of TILE×TILE pixels, row-major over the dispatch: its least and
// greatest view depth (FAR_AWAY and 0 for a block that receives nothing),
// then its light-view box (least x, y; greatest x, y).
@group(0) @binding(4) var<storage, read_write> blocks: array<BlockBounds>;

struct BlockBounds {
    depth: vec2f,
    light_box: vec4f,
};

const MAX_CASCADES: u32 = 8u;
const EMPTY_LOW: u32 = 0xffffffffu;

// Float bits whose unsigned order is the floats' order.
fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b ^ 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u ^ 0x80000000u, (u & 0x80000000u) != 0u));
}

// The receiving surface at `px`: xyz its position, w its view depth; w 0
// where none is.
fn seen_point(px: vec2u) -> vec4f {
    let size = textureDimensions(positions);
    if any(px >= size) {
        return vec4f(0.0);
    }
    let g = textureLoad(positions, vec2i(px), 0);
    let receives = textureLoad(normals, vec2i(px), 0).w > 0.5;
    if g.w < 0.5 || !receives {
        return vec4f(0.0);
    }
    return vec4f(g.xyz, max(-dot(params.view_z, vec4f(g.xyz, 1.0)), 0.0));
}

// Workgroup bounds: `depth_range`'s depths at 0, 1 and support extents at
// 2 + 2k, 3 + 2k; `cascade_bounds`' boxes at 4i.
var<workgroup> group_bounds: array<atomic<u32>, 34>;

// `depth_range` also takes the extents along the support directions (a
// single map fitted to the samples; its own pipeline, so that the
// cascades' reduction does not carry that code).
override SUPPORTS: bool = false;

// Where the support extents start in `bounds` (after 2 + 4·MAX_CASCADES).
const SUPPORT_WORD: u32 = 34u;
// Workgroup words of the depth range and the 16 support extents.
const RANGE_WORDS: u32 = 34u;

// The support directions k·180°/16 (roll.rs's `Supports`), four per
// vector: their x components in SUPPORT_COS_i, y in SUPPORT_SIN_i.
const SUPPORT_COS_0 = vec4f(1.0, 0.98078528, 0.92387953, 0.83146961);
const SUPPORT_SIN_0 = vec4f(0.0, 0.19509032, 0.38268343, 0.55557023);
const SUPPORT_COS_1 = vec4f(0.70710678, 0.55557023, 0.38268343, 0.19509032);
const SUPPORT_SIN_1 = vec4f(0.70710678, 0.83146961, 0.92387953, 0.98078528);
const SUPPORT_COS_2 = vec4f(0.0, -0.19509032, -0.38268343, -0.55557023);
const SUPPORT_SIN_2 = vec4f(1.0, 0.98078528, 0.92387953, 0.83146961);
const SUPPORT_COS_3 = vec4f(-0.70710678, -0.83146961, -0.92387953, -0.98078528);
const SUPPORT_SIN_3 = vec4f(0.70710678, 0.55557023, 0.38268343, 0.19509032);

// Merges the extents along four support directions (from `first`) into
// the workgroup's.
fn merge_supports(first: u32, low: vec4f, high: vec4f) {
    for (var i = 0u; i < 4u; i++) {
        atomicMin(&group_bounds[2u + 2u * (first + i)], ordered(low[i]));
        atomicMax(&group_bounds[3u + 2u * (first + i)], ordered(high[i]));
    }
}

// Each invocation reduces a TILE×TILE block of pixels in registers, so
// that a workgroup of 8×8 invocations makes 64 shared atomics for 64×64
// pixels, and one global atomic per value (depth_bounds.rs's `TILE`).
const TILE: u32 = 8u;

// The record of the block of invocation `id`.
fn block_index(id: vec2u) -> u32 {
    return id.y * params.blocks.x + id.x;
}

@compute @workgroup_size(8, 8)
fn depth_range(@builtin(global_invocation_id) id: vec3u, @builtin(local_invocation_index) li: u32) {
    let words = select(2u, RANGE_WORDS, SUPPORTS);
    if li < words {
        // Least values (even words) start at the top of the order.
        atomicStore(&group_bounds[li], select(0u, EMPTY_LOW, (li & 1u) == 0u));
    }
    workgroupBarrier();
    let light_x = light_row(0u);
    let light_y = light_row(1u);
    var low = FAR_AWAY;
    var high = 0.0;
    var box_low = vec2f(FAR_AWAY);
    var box_high = vec2f(-FAR_AWAY);
    // Extents along the support directions, four per vector (one variable
    // each: lavapipe keeps them in registers).
    var s_low0 = vec4f(FAR_AWAY);
    var s_low1 = vec4f(FAR_AWAY);
    var s_low2 = vec4f(FAR_AWAY);
    var s_low3 = vec4f(FAR_AWAY);
    var s_high0 = vec4f(-FAR_AWAY);
    var s_high1 = vec4f(-FAR_AWAY);
    var s_high2 = vec4f(-FAR_AWAY);
    var s_high3 = vec4f(-FAR_AWAY);
    for (var k = 0u; k < TILE * TILE; k++) {
        let px = id.xy * TILE + vec2u(k % TILE, k / TILE);
        let seen = seen_point(px);
        var receives = seen.w > 0.0;
        var l = light_xy(seen, light_x, light_y);
        if SUPPORTS && params.spot.x > 0.0 {
            let image = spot_image(px, seen, l);
            receives = receives && image.z > 0.0;
            l = image.xy;
        }
        low = select(low, min(low, seen.w), receives);
        high = select(high, max(high, seen.w), receives);
        box_low = select(box_low, min(box_low, l), receives);
        box_high = select(box_high, max(box_high, l), receives);
        if SUPPORTS {
            let a0 = SUPPORT_COS_0 * l.x + SUPPORT_SIN_0 * l.y;
            let a1 = SUPPORT_COS_1 * l.x + SUPPORT_SIN_1 * l.y;
            let a2 = SUPPORT_COS_2 * l.x + SUPPORT_SIN_2 * l.y;
            let a3 = SUPPORT_COS_3 * l.x + SUPPORT_SIN_3 * l.y;
            s_low0 = select(s_low0, min(s_low0, a0), receives);
            s_low1 = select(s_low1, min(s_low1, a1), receives);
            s_low2 = select(s_low2, min(s_low2, a2), receives);
            s_low3 = select(s_low3, min(s_low3, a3), receives);
            s_high0 = select(s_high0, max(s_high0, a0), receives);
            s_high1 = select(s_high1, max(s_high1, a1), receives);
            s_high2 = select(s_high2, max(s_high2, a2), receives);
            s_high3 = select(s_high3, max(s_high3, a3), receives);
        }
    }
    // Only `cascade_bounds` reads the records, and it does not run after
    // the extents are taken.
    if !SUPPORTS && all(id.xy < params.blocks.xy) {
        blocks[block_index(id.xy)] = BlockBounds(vec2f(low, high), vec4f(box_low, box_high));
    }
    if high > 0.0 {
        atomicMin(&group_bounds[0], ordered(low));
        atomicMax(&group_bounds[1], ordered(high));
        if SUPPORTS {
            merge_supports(0u, s_low0, s_high0);
            merge_supports(4u, s_low1, s_high1);
            merge_supports(8u, s_low2, s_high2);
            merge_supports(12u, s_low3, s_high3);
        }
    }
    workgroupBarrier();
    let group_low = atomicLoad(&group_bounds[0]);
    if li < words && group_low != EMPTY_LOW {
        let v = atomicLoad(&group_bounds[li]);
        let word = select(li, SUPPORT_WORD - 2u + li, li >= 2u);
        if (li & 1u) == 0u {
            atomicMin(&bounds[word], v);
        } else {
            atomicMax(&bounds[word], v);
        }
    }
}

// A spot light's image of the receiving point `seen` at `px`, whose
// light-view x, y are `l`: (x/−z, y/−z, 1) where the light reaches it —
// before the light, inside its cone, on the side its normal faces
// (compare.rs's considered pixels) — else z = 0.
fn spot_image(px: vec2u, seen: vec4f, l: vec2f) -> vec3f {
    let depth = -dot(light_row(2u), vec4f(seen.xyz, 1.0));
    let n = textureLoad(normals, vec2i(px), 0).xyz;
    let faces = dot(n, params.spot.yzw - seen.xyz) > 0.0;
    let image = l / max(depth, 1e-12);
    let inside = depth > 0.0 && length(image) <= params.spot.x;
    return vec3f(image, select(0.0, 1.0, faces && inside));
}

// Row `i` of the light's view.
fn light_row(i: u32) -> vec4f {
    let m = params.light_view;
    return vec4f(m[0][i], m[1][i], m[2][i], m[3][i]);
}

// Far end of cascade i between `near` and `far`: z_{i+1} of
// λ·n·(f/n)^(s) + (1−λ)·(n + (f−n)·s), s = (i+1)/N (cascades.rs's
// `split_distances`).
fn split_far(i: u32, near: f32, far: f32) -> f32 {
    let s = f32(i + 1u) / params.split.x;
    let lambda = params.split.y;
    return lambda * near * pow(far / near, s) + (1.0 - lambda) * (near + (far - near) * s);
}

// Where cascade i ends; beyond every depth for the last of `count`.
fn split_end(i: u32, count: u32, near: f32, far: f32) -> f32 {
    return select(FAR_AWAY, split_far(i, near, far), i + 1u < count);
}

// Merges one cascade's box (least x, y; greatest x, y) into the workgroup's.
fn merge_box(cascade: u32, low: vec2f, high: vec2f) {
    atomicMin(&group_bounds[4u * cascade], ordered(low.x));
    atomicMin(&group_bounds[4u * cascade + 1u], ordered(low.y));
    atomicMax(&group_bounds[4u * cascade + 2u], ordered(high.x));
    atomicMax(&group_bounds[4u * cascade + 3u], ordered(high.y));
}

const FAR_AWAY: f32 = 3.0e38;

// The cascade of view depth `d` among ends `e0`…`e6`.
fn cascade_at(d: f32, e0: f32, e1: f32, e2: f32, e3: f32, e4: f32, e5: f32, e6: f32) -> u32 {
    return u32(d > e0) + u32(d > e1) + u32(d > e2) + u32(d > e3) + u32(d > e4) + u32(d > e5) + u32(d > e6);
}

// A seen point's light-view x and y, from rows x and y of the light's view.
fn light_xy(seen: vec4f, light_x: vec4f, light_y: vec4f) -> vec2f {
    let p = vec4f(seen.xyz, 1.0);
    return vec2f(dot(light_x, p), dot(light_y, p));
}

@compute @workgroup_size(8, 8)
fn cascade_bounds(@builtin(global_invocation_id) id: vec3u, @builtin(local_invocation_index) li: u32) {
    let count = min(u32(params.split.x), MAX_CASCADES);
    if li < 4u * MAX_CASCADES {
        atomicStore(&group_bounds[li], select(0u, EMPTY_LOW, (li & 3u) < 2u));
    }
    workgroupBarrier();
    // The splits of the depths `depth_range` found, as the CPU computes them.
    let seen_low = atomicLoad(&bounds[0]);
    let near = max(from_ordered(seen_low), params.split.z);
    let far = max(min(from_ordered(atomicLoad(&bounds[1])), params.split.w), near * 1.01);
    // Where each cascade but the last ends (one variable each: an indexed
    // local array costs lavapipe more than the rest of the loop).
    let e0 = split_end(0u, count, near, far);
    let e1 = split_end(1u, count, near, far);
    let e2 = split_end(2u, count, near, far);
    let e3 = split_end(3u, count, near, far);
    let e4 = split_end(4u, count, near, far);
    let e5 = split_end(5u, count, near, far);
    let e6 = split_end(6u, count, near, far);
    // A block's pixels mostly share a cascade: its record's box is merged
    // whole. A block across a split (rare) goes back to its pixels for a
    // box per cascade, in a one-trip loop, which llvmpipe skips when no lane
    // of its SIMD group needs it (a branch runs under a lane mask whichever
    // way it goes).
    let inside = all(id.xy < params.blocks.xy);
    let record = blocks[select(0u, block_index(id.xy), inside)];
    let receives = inside && record.depth.y > 0.0;
    let first = cascade_at(record.depth.x, e0, e1, e2, e3, e4, e5, e6);
    let last = cascade_at(record.depth.y, e0, e1, e2, e3, e4, e5, e6);
    if receives && first == last {
        merge_box(first, record.light_box.xy, record.light_box.zw);
    }
    let light_x = light_row(0u);
    let light_y = light_row(1u);
    for (var across = receives && first < last; across; across = false) {
        for (var c = first; c <= last; c++) {
            var low = vec2f(FAR_AWAY);
            var high = vec2f(-FAR_AWAY);
            for (var k = 0u; k < TILE * TILE; k++) {
                let seen = seen_point(id.xy * TILE + vec2u(k % TILE, k / TILE));
                let l = light_xy(seen, light_x, light_y);
                let mine = seen.w > 0.0 && cascade_at(seen.w, e0, e1, e2, e3, e4, e5, e6) == c;
                low = select(low, min(low, l), mine);
                high = select(high, max(high, l), mine);
            }
            if low.x <= high.x {
                merge_box(c, low, high);
            }
        }
    }
    workgroupBarrier();
    if li < 4u * count && seen_low != EMPTY_LOW {
        let v = atomicLoad(&group_bounds[li]);
        if (li & 3u) < 2u {
            atomicMin(&bounds[2u + li], v);
        } else {
            atomicMax(&bounds[2u + li], v);
        }
    }
}

// ONLYDEPTH
