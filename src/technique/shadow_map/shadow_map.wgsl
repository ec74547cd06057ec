// Shadow maps (SEEDS §5): the depth pass from the light and the
// screen-space lookup that writes the visibility mask. common.wgsl is
// prepended.

struct ShadowMap {
    // world → light clip, one per face (1 for spot/directional, 6 for point)
    faces: array<mat4x4f, 6>,
    // xyz light position, w face count (1 or 6)
    light: vec4f,
    // x filter (0 hard, 1 pcf 2×2, 2 pcf grid, 3 pcf disk, 4 pcss, 5 variable width),
    // y samples per side (grid) or count (disk), z filter radius (texels),
    // w normal offset (texels)
    kernel: vec4f,
    // x map size, y 1/size, z world size of a texel at unit distance
    // (perspective) or of any texel (orthographic), w 1 = orthographic
    map: vec4f,
    // x light size (texels at unit depth ratio, pcss), y variable-width scale,
    // z variable-width exponent, w blocker-search radius (texels)
    soft: vec4f,
    // x near, y far (to linearise perspective depth), z 1 = 8-bit map
    depth: vec4f,
    // the face being rendered by the depth pass
    face: vec4u,
};

@group(2) @binding(0) var<uniform> sm: ShadowMap;
@group(2) @binding(1) var gbuffer_position: texture_2d<f32>;
@group(2) @binding(2) var gbuffer_normal: texture_2d<f32>;
@group(2) @binding(3) var depth_map: texture_depth_2d_array;
@group(2) @binding(4) var compare_sampler: sampler_comparison;
@group(2) @binding(5) var byte_map: texture_2d_array<f32>;

// ---- depth pass

struct DepthOut {
    @builtin(position) clip: vec4f,
};

@vertex
fn vs_depth(v: VertexIn) -> DepthOut {
    var o: DepthOut;
    o.clip = sm.faces[sm.face.x] * (objects[v.object].model * vec4f(v.position, 1.0));
    return o;
}

// The 8-bit preset stores the depth in an R8 colour target.
@fragment
fn fs_depth_byte(i: DepthOut) -> @location(0) vec4f {
    return vec4f(i.clip.z);
}

// ---- lookup

// Face of a point light's six 90° frusta: the major axis of p − light.
fn face_of(p: vec3f) -> u32 {
    if sm.light.w < 1.5 {
        return 0u;
    }
    let d = p - sm.light.xyz;
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x > 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

fn linear_depth(z: f32) -> f32 {
    if sm.map.w > 0.5 {
        return z;
    }
    let n = sm.depth.x;
    let f = sm.depth.y;
    return n * f / (f - z * (f - n));
}

// Stored depth at a texel (nearest), from the depth map or the 8-bit map.
fn stored(texel: vec2i, face: u32) -> f32 {
    let size = i32(sm.map.x);
    let t = clamp(texel, vec2i(0), vec2i(size - 1));
    if sm.depth.z > 0.5 {
        return textureLoad(byte_map, t, i32(face), 0).r;
    }
    return textureLoad(depth_map, t, i32(face), 0);
}

// 1 where the receiver depth z is not behind the stored depth.
fn lit_at(texel: vec2i, face: u32, z: f32) -> f32 {
    return select(0.0, 1.0, z <= stored(texel, face));
}

// Bilinear (hardware-style 2×2) comparison at uv.
fn pcf2x2(uv: vec2f, face: u32, z: f32) -> f32 {
    if sm.depth.z < 0.5 {
        return textureSampleCompareLevel(depth_map, compare_sampler, uv, i32(face), z);
    }
    let p = uv * sm.map.x - 0.5;
    let b = vec2i(floor(p));
    let f = fract(p);
    let a = mix(lit_at(b, face, z), lit_at(b + vec2i(1, 0), face, z), f.x);
    let c = mix(lit_at(b + vec2i(0, 1), face, z), lit_at(b + vec2i(1, 1), face, z), f.x);
    return mix(a, c, f.y);
}

// Interleaved gradient noise (Jimenez 2014): a per-pixel rotation.
fn ign(p: vec2f) -> f32 {
    return fract(52.9829189 * fract(dot(p, vec2f(0.06711056, 0.00583715))));
}

// Vogel disk sample i of n, rotated by phi, radius ≤ 1.
fn vogel(i: u32, n: u32, phi: f32) -> vec2f {
    let r = sqrt((f32(i) + 0.5) / f32(n));
    let theta = f32(i) * 2.4 + phi;
    return r * vec2f(cos(theta), sin(theta));
}

fn pcf_disk(uv: vec2f, face: u32, z: f32, radius_texels: f32, n: u32, phi: f32) -> f32 {
    var sum = 0.0;
    for (var i = 0u; i < n; i++) {
        sum += pcf2x2(uv + vogel(i, n, phi) * radius_texels * sm.map.y, face, z);
    }
    return sum / f32(n);
}

fn pcf_grid(uv: vec2f, face: u32, z: f32, radius_texels: f32, k: u32) -> f32 {
    var sum = 0.0;
    for (var y = 0u; y < k; y++) {
        for (var x = 0u; x < k; x++) {
            let o = (vec2f(f32(x), f32(y)) + 0.5) / f32(k) * 2.0 - 1.0;
            sum += pcf2x2(uv + o * radius_texels * sm.map.y, face, z);
        }
    }
    return sum / f32(k * k);
}

// Mean linear depth of the blockers (stored < z) in a disk, and their count.
fn blockers(uv: vec2f, face: u32, z: f32, radius_texels: f32, n: u32, phi: f32) -> vec2f {
    var sum = 0.0;
    var count = 0.0;
    for (var i = 0u; i < n; i++) {
        let t = vec2i(floor((uv + vogel(i, n, phi) * radius_texels * sm.map.y) * sm.map.x));
        let d = stored(t, face);
        if d < z {
            sum += linear_depth(d);
            count += 1.0;
        }
    }
    return vec2f(sum / max(count, 1.0), count);
}

@fragment
fn fs_lookup(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let g = textureLoad(gbuffer_position, vec2i(frag.xy), 0);
    if g.w < 0.5 {
        return vec4f(1.0);
    }
    let n = normalize(textureLoad(gbuffer_normal, vec2i(frag.xy), 0).xyz);
    let face = face_of(g.xyz);
    // Normal offset: move the lookup point along the geometric normal by a
    // number of shadow-map texels (their world size grows with distance for
    // perspective maps).
    var texel_world = sm.map.z;
    if sm.map.w < 0.5 {
        texel_world = sm.map.z * length(g.xyz - sm.light.xyz);
    }
    let p = g.xyz + n * sm.kernel.w * texel_world;
    let c = sm.faces[face] * vec4f(p, 1.0);
    if c.w <= 0.0 {
        return vec4f(1.0);
    }
    let ndc = c.xyz / c.w;
    let uv = vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if any(uv < vec2f(0.0)) || any(uv > vec2f(1.0)) || ndc.z > 1.0 || ndc.z < 0.0 {
        return vec4f(1.0); // outside the map counts as lit
    }
    let z = ndc.z;
    let kind = u32(sm.kernel.x);
    let count = max(u32(sm.kernel.y), 1u);
    let radius = sm.kernel.z;
    let phi = ign(frag.xy) * 6.2831853;
    var v = 1.0;
    switch kind {
        case 0u: {
            v = lit_at(vec2i(floor(uv * sm.map.x)), face, z);
        }
        case 1u: {
            v = pcf2x2(uv, face, z);
        }
        case 2u: {
            v = pcf_grid(uv, face, z, radius, count);
        }
        case 3u: {
            v = pcf_disk(uv, face, z, radius, count * count, phi);
        }
        case 4u: {
            // PCSS (Fernando 2005): blocker search, then a penumbra
            // w = (d_receiver − d_blocker) / d_blocker · light size.
            let b = blockers(uv, face, z, sm.soft.w, 16u, phi);
            if b.y > 0.0 {
                let dr = linear_depth(z);
                let w = max((dr - b.x) / max(b.x, 1e-4) * sm.soft.x, 0.5);
                v = pcf_disk(uv, face, z, min(w, 64.0), count * count, phi);
            }
        }
        default: {
            // Variable-width PCF (002): radius ∝ |d_blocker − d_receiver|^exponent.
            let b = blockers(uv, face, z, sm.soft.w, 16u, phi);
            if b.y > 0.0 {
                let w = sm.soft.y * pow(abs(linear_depth(z) - b.x), sm.soft.z);
                v = pcf_disk(uv, face, z, clamp(w, 0.5, 64.0), count * count, phi);
            }
        }
    }
    return vec4f(v);
}
