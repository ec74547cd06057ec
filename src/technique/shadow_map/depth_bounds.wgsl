// SDSM's reduction (Lauritzen, Salvi & Lefohn 2011) over the prepass's
// G-buffer: the least and greatest view depth of the pixels that receive
// shadows (`depth_range`), then, with the cascade splits those depths give,
// each cascade's light-view x/y bounds over the pixels it shades
// (`cascade_bounds`). Workgroups reduce in shared memory, then one
// invocation merges into the result with atomics on order-preserving bits.

struct ReduceParams {
    // Row z of the fitted camera's view matrix: a point's view depth is
    // −dot(row, (p, 1)).
    view_z: vec4f,
    // The light's view (world → light view space).
    light_view: mat4x4f,
    // x cascade count, y split λ, z camera near, w the farthest split allowed.
    split: vec4f,
};

@group(0) @binding(0) var positions: texture_2d<f32>;
@group(0) @binding(1) var normals: texture_2d<f32>;
@group(0) @binding(2) var<uniform> params: ReduceParams;
// [0] least depth, [1] greatest depth, then per cascade i at 2 + 4i: least
// x, least y, greatest x, greatest y — all as `ordered` bits.
@group(0) @binding(3) var<storage, read_write> bounds: array<atomic<u32>>;

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

var<workgroup> group_bounds: array<atomic<u32>, 32>;

// Each invocation reduces a TILE×TILE block of pixels in registers, so
// that a workgroup of 8×8 invocations makes 64 shared atomics for 32×32
// pixels, and one global atomic per value.
const TILE: u32 = 4u;

@compute @workgroup_size(8, 8)
fn depth_range(@builtin(global_invocation_id) id: vec3u, @builtin(local_invocation_index) li: u32) {
    if li < 2u {
        atomicStore(&group_bounds[li], select(0u, EMPTY_LOW, li == 0u));
    }
    workgroupBarrier();
    var low = 3.0e38;
    var high = 0.0;
    for (var k = 0u; k < TILE * TILE; k++) {
        let d = seen_point(id.xy * TILE + vec2u(k % TILE, k / TILE)).w;
        if d > 0.0 {
            low = min(low, d);
            high = max(high, d);
        }
    }
    if high > 0.0 {
        atomicMin(&group_bounds[0], ordered(low));
        atomicMax(&group_bounds[1], ordered(high));
    }
    workgroupBarrier();
    if li == 0u {
        let group_low = atomicLoad(&group_bounds[0]);
        if group_low != EMPTY_LOW {
            atomicMin(&bounds[0], group_low);
            atomicMax(&bounds[1], atomicLoad(&group_bounds[1]));
        }
    }
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
    // Rows x and y of the light's view.
    let light_x = vec4f(params.light_view[0].x, params.light_view[1].x, params.light_view[2].x, params.light_view[3].x);
    let light_y = vec4f(params.light_view[0].y, params.light_view[1].y, params.light_view[2].y, params.light_view[3].y);
    // Where each cascade but the last ends (one variable each: an indexed
    // local array costs lavapipe more than the rest of the loop).
    let e0 = split_end(0u, count, near, far);
    let e1 = split_end(1u, count, near, far);
    let e2 = split_end(2u, count, near, far);
    let e3 = split_end(3u, count, near, far);
    let e4 = split_end(4u, count, near, far);
    let e5 = split_end(5u, count, near, far);
    let e6 = split_end(6u, count, near, far);
    // The block's pixels mostly share a cascade: one box per run of a
    // cascade, merged when the cascade changes and at the end.
    var current = MAX_CASCADES;
    var low = vec2f(FAR_AWAY);
    var high = vec2f(-FAR_AWAY);
    for (var k = 0u; k < TILE * TILE; k++) {
        let px = id.xy * TILE + vec2u(k % TILE, k / TILE);
        let seen = seen_point(px);
        let d = seen.w;
        if d > 0.0 {
            let cascade = u32(d > e0) + u32(d > e1) + u32(d > e2) + u32(d > e3) + u32(d > e4) + u32(d > e5) + u32(d > e6);
            if cascade != current {
                if current < MAX_CASCADES {
                    merge_box(current, low, high);
                }
                current = cascade;
                low = vec2f(FAR_AWAY);
                high = vec2f(-FAR_AWAY);
            }
            let p = vec4f(seen.xyz, 1.0);
            let l = vec2f(dot(light_x, p), dot(light_y, p));
            low = min(low, l);
            high = max(high, l);
        }
    }
    if current < MAX_CASCADES {
        merge_box(current, low, high);
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
