// Edge-masked filtering's min/max chain: level 0 holds, per BLOCK×BLOCK
// block of map texels, the least and greatest stored depth (x, y); each
// further level halves again. The lookup reads 2×2 texels of the level
// whose texels cover the kernel's footprint and needs the full kernel only
// where the receiver depth lies between them (a shadow edge). Level 0 reads
// its block in one invocation: levels built in 2×2 steps from the map would
// store (and dispatch) 16× the texels, for levels that a kernel of radius 1
// or more never reads (edge_mask.rs).

@group(0) @binding(0) var source_depth: texture_depth_2d_array;
@group(0) @binding(1) var source_values: texture_2d_array<f32>;
@group(0) @binding(2) var destination: texture_storage_2d_array<rg32float, write>;
// Nearest, clamped to the edge (as the lookup's taps are).
@group(0) @binding(3) var nearest: sampler;

// Map texels per side of a level-0 texel (CHAIN_BLOCK_LOG2 from edge_mask.rs).
const BLOCK: u32 = 1u << CHAIN_BLOCK_LOG2;

fn range_of(d: vec4f) -> vec2f {
    return vec2f(min(min(d.x, d.y), min(d.z, d.w)), max(max(d.x, d.y), max(d.z, d.w)));
}

// The least and greatest of the source texels under destination texel `t`
// of `layer`: BLOCK×BLOCK texels of the depth map or the 8-bit map (kind 0,
// 1), or 2×2 texels of the level below (kind 2). A gather at the corner
// shared by four texels returns those four; the clamp repeats a map's last
// texels past its side.
fn source_range(t: vec2u, layer: u32, kind: u32) -> vec2f {
    if kind == 2u {
        let uv = (vec2f(t) * 2.0 + 1.0) / vec2f(textureDimensions(source_values));
        let lo = textureGather(0, source_values, nearest, uv, layer);
        let hi = textureGather(1, source_values, nearest, uv, layer);
        return vec2f(range_of(lo).x, range_of(hi).y);
    }
    var r = vec2f(3.4e38, -3.4e38);
    for (var j = 0u; j < BLOCK / 2u; j++) {
        for (var i = 0u; i < BLOCK / 2u; i++) {
            let corner = vec2f(t * BLOCK + 2u * vec2u(i, j)) + 1.0;
            var q: vec2f;
            if kind == 0u {
                q = range_of(textureGather(source_depth, nearest, corner / vec2f(textureDimensions(source_depth)), layer));
            } else {
                q = range_of(textureGather(0, source_values, nearest, corner / vec2f(textureDimensions(source_values)), layer));
            }
            r = vec2f(min(r.x, q.x), max(r.y, q.y));
        }
    }
    return r;
}

fn reduce(id: vec3u, kind: u32) {
    let size = textureDimensions(destination);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    textureStore(destination, id.xy, id.z, vec4f(source_range(id.xy, id.z, kind), 0.0, 0.0));
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
