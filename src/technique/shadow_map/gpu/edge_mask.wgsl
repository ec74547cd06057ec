// Edge-masked filtering's bounding chain. Each level-0 texel bounds the
// stored depths of a BLOCK×BLOCK block of map texels between two parallel
// planes, and each further level bounds 2×2 texels of the level below. A
// texel holds (lo, hi, gx, gy): every map texel of the cell stores a depth
// within lo + g·u .. hi + g·u, u its centre's offset from the cell's centre
// in cell sides (|u| ≤ ½) and g in depth per cell side. Where the cell holds
// one flat or sloped surface the planes follow it (lo = hi but for
// rounding), so a receiver on that surface is told lit although its depth
// lies between the cell's least and greatest; elsewhere g = 0 and lo, hi
// are the least and greatest depth (a min/max chain), whichever pair lies
// closer together. The lookup reads 2×2 texels of the level whose texels
// cover the kernel's span (`edge_class` in filters.wgsl). Level 0 reads its
// block in one invocation: levels built in 2×2 steps from the map would
// store (and dispatch) 16× the texels, for levels that a kernel of radius 1
// or more never reads (edge_mask.rs).
//
// The part chain beside it holds, per cell, the one convex part that all
// its texels came from (`part_ids`; 0: none), or MIXED_PART.

@group(0) @binding(0) var source_depth: texture_depth_2d_array;
@group(0) @binding(1) var source_values: texture_2d_array<f32>;
@group(0) @binding(2) var destination: texture_storage_2d_array<rgba32float, write>;
// Nearest, clamped to the edge (as the lookup's taps are).
@group(0) @binding(3) var nearest: sampler;
// The map's parts (level 0; a 1×1 part 0 without part ids) or the level
// below's, and the level's part cells.
@group(0) @binding(4) var source_parts: texture_2d_array<u32>;
@group(0) @binding(5) var destination_parts: texture_storage_2d_array<r32uint, write>;

// Map texels per side of a level-0 texel (CHAIN_BLOCK_LOG2 from edge_mask.rs).
const BLOCK: u32 = 1u << CHAIN_BLOCK_LOG2;
// 2×2 gathers per side of a level-0 block.
const GATHERS: u32 = BLOCK / 2u;

// The narrower of two bounds of one cell, (lo, hi, g) and a flat (lo, hi),
// compared at a point: the lookup reads the bound over a part of the cell,
// where a plane that follows the surface holds it tightest.
fn narrower(sloped: vec4f, flat: vec2f) -> vec4f {
    if sloped.y - sloped.x < flat.y - flat.x {
        return sloped;
    }
    return vec4f(flat, 0.0, 0.0);
}

// The map texel corner shared by gather (i, j) of block t.
fn gather_corner(t: vec2u, i: u32, j: u32) -> vec2f {
    return vec2f(t * BLOCK + 2u * vec2u(i, j)) + 1.0;
}

// The 2×2 map texels whose shared corner is gather (i, j) of block t:
// x (2i, 2j+1), y (2i+1, 2j+1), z (2i+1, 2j), w (2i, 2j) of the block (the
// gather order). The clamp repeats a map's last texels past its side.
fn block_gather(t: vec2u, i: u32, j: u32, layer: u32, from_depth: bool) -> vec4f {
    let corner = gather_corner(t, i, j);
    if from_depth {
        return textureGather(source_depth, nearest, corner / vec2f(textureDimensions(source_depth)), layer);
    }
    return textureGather(0, source_values, nearest, corner / vec2f(textureDimensions(source_values)), layer);
}

// The one part of four, or MIXED_PART.
fn common_part(p: vec4u) -> u32 {
    return select(MIXED_PART, p.x, all(p == vec4u(p.x)));
}

// Level 0's part: the block's one part, from its first texel and BLOCK²/4
// gathers (clamped as the depths are).
fn block_part(t: vec2u, layer: u32) -> u32 {
    let size = textureDimensions(source_parts);
    var part = textureLoad(source_parts, min(t * BLOCK, size - 1u), layer, 0).r;
    for (var j = 0u; j < GATHERS; j++) {
        for (var i = 0u; i < GATHERS; i++) {
            let p = textureGather(0, source_parts, nearest, gather_corner(t, i, j) / vec2f(size), layer);
            part = select(MIXED_PART, part, all(p == vec4u(part)));
        }
    }
    return part;
}

// A further level's part: its four children's one part.
fn level_part(t: vec2u, layer: u32) -> u32 {
    return common_part(vec4u(child_part(t, vec2u(0u, 0u), layer), child_part(t, vec2u(1u, 0u), layer),
        child_part(t, vec2u(0u, 1u), layer), child_part(t, vec2u(1u, 1u), layer)));
}

// Level 0: the plane through three corner texels of the block (exact
// where the block is one plane), then the least and greatest depth about
// it in one pass, against the block's least and greatest depth.
fn block_bounds(t: vec2u, layer: u32, from_depth: bool) -> vec4f {
    let last = GATHERS - 1u;
    let origin = block_gather(t, 0u, 0u, layer, from_depth).w;
    let across = block_gather(t, last, 0u, layer, from_depth).z;
    let down = block_gather(t, 0u, last, layer, from_depth).x;
    // Depth per texel, and the first texel centre's offset from the
    // block's centre.
    let g = vec2f(across - origin, down - origin) / f32(BLOCK - 1u);
    let first = 0.5 - f32(BLOCK) * 0.5;
    var band = vec2f(3.4e38, -3.4e38);
    var flat = vec2f(3.4e38, -3.4e38);
    for (var j = 0u; j < GATHERS; j++) {
        for (var i = 0u; i < GATHERS; i++) {
            let v = block_gather(t, i, j, layer, from_depth);
            let o = vec2f(2.0 * f32(i), 2.0 * f32(j)) + first;
            let w = dot(g, o);
            let r = v - vec4f(w + g.y, w + g.x + g.y, w + g.x, w);
            band = vec2f(min(band.x, min(min(r.x, r.y), min(r.z, r.w))), max(band.y, max(max(r.x, r.y), max(r.z, r.w))));
            flat = vec2f(min(flat.x, min(min(v.x, v.y), min(v.z, v.w))), max(flat.y, max(max(v.x, v.y), max(v.z, v.w))));
        }
    }
    return narrower(vec4f(band, g * f32(BLOCK)), flat);
}

// A further level: 2×2 cells of the level below under one plane of their
// mean slope (each child's slope doubles in the parent's larger sides),
// each child's band moved to the parent's centre and widened by how far
// its slope departs from that one over its cell (a quarter of a parent
// side each way); against the children's least and greatest depth.
fn level_bounds(t: vec2u, layer: u32) -> vec4f {
    let c00 = child_cell(t, vec2u(0u, 0u), layer);
    let c10 = child_cell(t, vec2u(1u, 0u), layer);
    let c01 = child_cell(t, vec2u(0u, 1u), layer);
    let c11 = child_cell(t, vec2u(1u, 1u), layer);
    let g = (c00.zw + c10.zw + c01.zw + c11.zw) * 0.5;
    // Each child's (band, flat) ranges; its centre in parent sides.
    let r00 = child_ranges(c00, vec2f(-0.25, -0.25), g);
    let r10 = child_ranges(c10, vec2f(0.25, -0.25), g);
    let r01 = child_ranges(c01, vec2f(-0.25, 0.25), g);
    let r11 = child_ranges(c11, vec2f(0.25, 0.25), g);
    let lo = min(min(r00.xz, r10.xz), min(r01.xz, r11.xz));
    let hi = max(max(r00.yw, r10.yw), max(r01.yw, r11.yw));
    return narrower(vec4f(lo.x, hi.x, g), vec2f(lo.y, hi.y));
}

// Child `k` of level texel t (the clamp repeats a level's last texel).
fn child_cell(t: vec2u, k: vec2u, layer: u32) -> vec4f {
    let top = vec2i(textureDimensions(source_values)) - 1;
    return textureLoad(source_values, min(vec2i(t * 2u + k), top), layer, 0);
}

// Child `k`'s part, clamped as `child_cell`.
fn child_part(t: vec2u, k: vec2u, layer: u32) -> u32 {
    let top = vec2i(textureDimensions(source_parts)) - 1;
    return textureLoad(source_parts, min(vec2i(t * 2u + k), top), layer, 0).r;
}

// A child cell c centred at o (parent sides) under the parent's slope g:
// its band about that plane (x, y) and its flat least and greatest (z, w).
fn child_ranges(c: vec4f, o: vec2f, g: vec2f) -> vec4f {
    let departs = 0.25 * dot(abs(2.0 * c.zw - g), vec2f(1.0));
    let shift = -dot(g, o);
    let sway = 0.5 * dot(abs(c.zw), vec2f(1.0));
    return vec4f(c.x + shift - departs, c.y + shift + departs, c.x - sway, c.y + sway);
}

// Destination texel id's bounds from the depth map, the 8-bit map (kind 0,
// 1) or the level below (kind 2).
fn reduce(id: vec3u, kind: u32) {
    let size = textureDimensions(destination);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    var bounds: vec4f;
    var part: u32;
    if kind == 2u {
        bounds = level_bounds(id.xy, id.z);
        part = level_part(id.xy, id.z);
    } else {
        bounds = block_bounds(id.xy, id.z, kind == 0u);
        part = block_part(id.xy, id.z);
    }
    textureStore(destination, id.xy, id.z, bounds);
    textureStore(destination_parts, id.xy, id.z, vec4u(part));
}

@compute @workgroup_size(8, 8, 1)
fn from_depth(@builtin(global_invocation_id) id: vec3u) {
    reduce(id, 0u);
}

@compute @workgroup_size(8, 8, 1)
fn from_bytes(@builtin(global_invocation_id) id: vec3u) {
    reduce(id, 1u);
}

@compute @workgroup_size(8, 8, 1)
fn from_level(@builtin(global_invocation_id) id: vec3u) {
    reduce(id, 2u);
}
