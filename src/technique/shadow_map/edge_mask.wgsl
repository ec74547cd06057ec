// Edge-masked filtering's min/max chain: level 0 holds, per 2×2 block of
// map texels, the least and greatest stored depth (x, y); each further level
// halves again. The lookup reads 2×2 texels of the level whose texels cover
// the kernel's footprint and needs the full kernel only where the receiver
// depth lies between them (a shadow edge).

@group(0) @binding(0) var source_depth: texture_depth_2d_array;
@group(0) @binding(1) var source_values: texture_2d_array<f32>;
@group(0) @binding(2) var destination: texture_storage_2d_array<rg32float, write>;

// The source texel at t of `layer`, clamped to the source (as the lookup's
// taps are): from the depth map, the 8-bit map, or the level below.
fn source_range(t: vec2i, layer: i32, kind: u32) -> vec2f {
    if kind == 0u {
        let size = vec2i(textureDimensions(source_depth));
        let d = textureLoad(source_depth, clamp(t, vec2i(0), size - 1), layer, 0);
        return vec2f(d, d);
    }
    let size = vec2i(textureDimensions(source_values));
    let v = textureLoad(source_values, clamp(t, vec2i(0), size - 1), layer, 0);
    if kind == 1u {
        return vec2f(v.r, v.r);
    }
    return v.xy;
}

fn reduce(id: vec3u, kind: u32) {
    let size = textureDimensions(destination);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let base = vec2i(id.xy) * 2;
    let layer = i32(id.z);
    let a = source_range(base, layer, kind);
    let b = source_range(base + vec2i(1, 0), layer, kind);
    let c = source_range(base + vec2i(0, 1), layer, kind);
    let d = source_range(base + vec2i(1, 1), layer, kind);
    let range = vec2f(min(min(a.x, b.x), min(c.x, d.x)), max(max(a.y, b.y), max(c.y, d.y)));
    textureStore(destination, vec2i(id.xy), layer, vec4f(range, 0.0, 0.0));
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
