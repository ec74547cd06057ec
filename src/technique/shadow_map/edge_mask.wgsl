// Edge-masked filtering's min/max chain: level 0 holds, per 2×2 block of
// map texels, the least and greatest stored depth (x, y); each further level
// halves again. The lookup reads 2×2 texels of the level whose texels cover
// the kernel's footprint and needs the full kernel only where the receiver
// depth lies between them (a shadow edge).

@group(0) @binding(0) var source_depth: texture_depth_2d_array;
@group(0) @binding(1) var source_values: texture_2d_array<f32>;
@group(0) @binding(2) var destination: texture_storage_2d_array<rg32float, write>;
// Nearest, clamped to the edge (as the lookup's taps are): a gather at the
// corner shared by four source texels returns those four.
@group(0) @binding(3) var nearest: sampler;

// The least and greatest of the 2×2 source texels under destination texel
// `t` of `layer`: from the depth map, the 8-bit map, or the level below.
fn source_range(t: vec2u, layer: u32, kind: u32) -> vec2f {
    if kind == 0u {
        let uv = (vec2f(t) * 2.0 + 1.0) / vec2f(textureDimensions(source_depth));
        let d = textureGather(source_depth, nearest, uv, layer);
        return vec2f(min(min(d.x, d.y), min(d.z, d.w)), max(max(d.x, d.y), max(d.z, d.w)));
    }
    let uv = (vec2f(t) * 2.0 + 1.0) / vec2f(textureDimensions(source_values));
    let lo = textureGather(0, source_values, nearest, uv, layer);
    var hi = lo;
    if kind == 2u {
        hi = textureGather(1, source_values, nearest, uv, layer);
    }
    return vec2f(min(min(lo.x, lo.y), min(lo.z, lo.w)), max(max(hi.x, hi.y), max(hi.z, hi.w)));
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
