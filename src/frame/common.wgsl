// Shared declarations: the per-frame uniform (group 0) and the object table
// (group 1). Technique shaders are compiled with this file prepended.

const MAX_LIGHTS: u32 = 4u;
const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;

// A light; its kind and compose mode are the lighting pipeline's constants.
struct LightGpu {
    // xyz world position, w range (0 = no falloff)
    position: vec4f,
    // xyz unit direction the light travels, w cos(outer cone)
    direction: vec4f,
    // rgb colour × intensity, w cos(inner cone)
    color: vec4f,
};

struct Frame {
    view_proj: mat4x4f,
    inv_view_proj: mat4x4f,
    view: mat4x4f,
    proj: mat4x4f,
    camera_pos: vec4f,
    ambient: vec4f,
    // width, height, 1/width, 1/height
    size: vec4f,
    lights: array<LightGpu, 4>,
};

// `ObjectGpu::info.w`: what an object's mesh encloses (`SolidKind`).
const SOLID_NONE: u32 = 0u;
const SOLID_CONCAVE: u32 = 2u;

struct ObjectGpu {
    model: mat4x4f,
    normal_matrix: mat4x4f,
    // x material, y casts shadow, z receives shadow, w bounds a solid (closed,
    // wound outward: its back faces lie behind its front faces): 0 no, 1 a
    // convex one, 2 a concave one (SOLID_*)
    info: vec4u,
    // x the global ID of the object's convex parts less one (IDs are unique
    // in the scene; 0 is no part), y 1 where they are not used (a part goes
    // on in another mesh placed with the same transform), z 1 where half its
    // triangles are the back faces a double-sided material added, w unused
    parts: vec4u,
    // x alpha mode (ALPHA_*), y cutoff, z opacity factor, w uv scale (f32 bits)
    alpha: vec4u,
    // x first byte of the opacity map in `opacity_texels` (its mip levels
    // follow, each half the last), y width, z height, w levels (0: no map)
    // in bits 0..8 and the wrap modes along u and v (WRAP_*) in bits 8..10
    // and 10..12
    opacity_map: vec4u,
};

const ALPHA_OPAQUE: u32 = 0u;
const ALPHA_MASK: u32 = 1u;
const ALPHA_BLEND: u32 = 2u;

// Where the camera ray through screen point `at` (pixels) meets the plane
// through p with unit normal n; p itself where the ray runs along the plane.
fn camera_ray_on_plane(at: vec2f, p: vec3f, n: vec3f) -> vec3f {
    let uv = at / frame.size.xy;
    let ndc = vec2f(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    // On the near plane (reversed depth 1, the Rust side's NEAR_PLANE_DEPTH)
    // and farther along.
    let a = frame.inv_view_proj * vec4f(ndc, 1.0, 1.0);
    let b = frame.inv_view_proj * vec4f(ndc, 0.5, 1.0);
    let near = a.xyz / a.w;
    let d = normalize(b.xyz / b.w - near);
    let along = dot(d, n);
    if abs(along) < 1e-6 {
        return p;
    }
    let to_near = near - p;
    return p + to_near - d * (dot(to_near, n) / along);
}

// The scene-wide ID of `object`'s convex part `part` (0: none, and where
// the object's parts are not used).
fn part_id(object: u32, part: u32) -> u32 {
    let parts = objects[object].parts;
    return select(0u, parts.x + part, part != 0u && parts.y == 0u);
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var<storage, read> objects: array<ObjectGpu>;
// Every opacity map's mip chain, four one-byte texels per word.
@group(1) @binding(1) var<storage, read> opacity_texels: array<u32>;

// A texture's wrap modes (scene::TextureWrap's indices).
const WRAP_REPEAT: u32 = 0u;
const WRAP_CLAMP: u32 = 1u;
const WRAP_MIRROR: u32 = 2u;

// The texel a tap at integer coordinate `i` reads on an axis of `n` texels
// wrapped by `mode` (TextureWrap::texel's twin).
fn wrap_texel(i: i32, n: i32, mode: u32) -> i32 {
    switch mode {
        case WRAP_CLAMP: {
            return clamp(i, 0, n - 1);
        }
        case WRAP_MIRROR: {
            let k = ((i % (2 * n)) + 2 * n) % (2 * n);
            return select(k, 2 * n - 1 - k, k >= n);
        }
        default: {
            return ((i % n) + n) % n;
        }
    }
}

// One texel of an opacity level (`base` its first byte, `size` its extent),
// wrapped along u and v as `wrap` says.
fn opacity_texel(base: u32, size: vec2i, t: vec2i, wrap: vec2u) -> f32 {
    let w = vec2i(wrap_texel(t.x, size.x, wrap.x), wrap_texel(t.y, size.y, wrap.y));
    let i = base + u32(w.y * size.x + w.x);
    return f32((opacity_texels[i >> 2u] >> (8u * (i & 3u))) & 255u) / 255.0;
}

// The lengths, in texels of `object`'s opacity map, of the pixel
// footprint's two axes `duv_dx`, `duv_dy` (the derivatives of the unscaled
// uv).
fn opacity_footprint(object: u32, duv_dx: vec2f, duv_dy: vec2f) -> vec2f {
    let m = objects[object].opacity_map;
    let texels = vec2f(f32(m.y), f32(m.z)) * bitcast<f32>(objects[object].alpha.w);
    return vec2f(length(duv_dx * texels), length(duv_dy * texels));
}

// The mip level whose texels are the size of a footprint axis `texels` long.
fn lod_of(texels: f32) -> f32 {
    return max(log2(max(texels, 1e-8)), 0.0);
}

// The mip level of `object`'s opacity map whose texels are the size of the
// pixel footprint's longer axis (the camera's view, filtered as a sampler
// without anisotropy would).
fn opacity_lod(object: u32, duv_dx: vec2f, duv_dy: vec2f) -> f32 {
    let f = opacity_footprint(object, duv_dx, duv_dy);
    return lod_of(max(f.x, f.y));
}

// The mip level of a shadow map texel's footprint's shorter axis: the depth
// pass point-samples each caster at the map's texel centres, and a card
// seen obliquely from the light, read at its longer axis's level, would
// lose across the shorter one the holes the texels resolve.
fn opacity_lod_across(object: u32, duv_dx: vec2f, duv_dy: vec2f) -> f32 {
    let f = opacity_footprint(object, duv_dx, duv_dy);
    return lod_of(min(f.x, f.y));
}

// The opacity of `object` at `uv` (unscaled): the material's factor times
// its map's bilinear value at mip level `lod`.
fn opacity_at(object: u32, uv: vec2f, lod: f32) -> f32 {
    let a = objects[object].alpha;
    let m = objects[object].opacity_map;
    let factor = bitcast<f32>(a.z);
    let levels = m.w & 255u;
    if levels == 0u {
        return factor;
    }
    let wrap = vec2u((m.w >> 8u) & 3u, (m.w >> 10u) & 3u);
    let level = u32(min(round(lod), f32(levels - 1u)));
    var base = m.x;
    var size = vec2u(m.y, m.z);
    for (var l = 0u; l < level; l++) {
        base += size.x * size.y;
        size = max(size / 2u, vec2u(1u));
    }
    let s = vec2i(size);
    let p = uv * bitcast<f32>(a.w) * vec2f(size) - 0.5;
    let p0 = floor(p);
    let f = p - p0;
    let t = vec2i(p0);
    let top = mix(opacity_texel(base, s, t, wrap), opacity_texel(base, s, t + vec2i(1, 0), wrap), f.x);
    let bottom = mix(opacity_texel(base, s, t + vec2i(0, 1), wrap), opacity_texel(base, s, t + vec2i(1, 1), wrap), f.x);
    return factor * mix(top, bottom, f.y);
}

// Whether `object` is solid at `uv` for a pass that draws it as a cut-out:
// a mask material where its opacity reaches the cutoff, a blended one
// where it reaches `blend_cutoff`, an opaque one everywhere.
fn is_solid_at(object: u32, uv: vec2f, lod: f32, blend_cutoff: f32) -> bool {
    if objects[object].alpha.x == ALPHA_OPAQUE {
        return true;
    }
    return reaches_cutoff(object, opacity_at(object, uv, lod), blend_cutoff);
}

// Whether `opacity`, read on a mask or blended `object`, reaches the cutoff
// that makes it solid: the material's for a mask, `blend_cutoff` for a
// blended one.
fn reaches_cutoff(object: u32, opacity: f32, blend_cutoff: f32) -> bool {
    let a = objects[object].alpha;
    return opacity >= select(blend_cutoff, bitcast<f32>(a.y), a.x == ALPHA_MASK);
}

struct VertexIn {
    @location(0) position: vec3f,
    @location(1) normal: vec3f,
    @location(2) uv: vec2f,
    @location(3) tangent: vec4f,
    // the mesh's convex part (from 1), 0 for none: `part_id` makes it global
    @location(4) part: u32,
    // the colour multiplying the material's (glTF COLOR_0), sRGB-encoded
    // (`vertex_color` decodes it)
    @location(5) color: vec4f,
    @builtin(instance_index) object: u32,
};

// Clip-space position; every pass that depth-tests against the prepass uses
// this one function with an @invariant output so depths match exactly.
fn clip_position(object: u32, p: vec3f) -> vec4f {
    return frame.view_proj * (objects[object].model * vec4f(p, 1.0));
}

// Whether a caster's fragment at `uv` is solid, for caster passes that draw
// every caster with one pipeline: `see_through` (a flat varying: the
// object's alpha mode is not opaque) spares opaque casters the object read;
// the derivatives are the caller's, taken in uniform control flow.
fn caster_is_solid(object: u32, see_through: bool, uv: vec2f, duv_dx: vec2f, duv_dy: vec2f) -> bool {
    if !see_through {
        return true;
    }
    return is_solid_at(object, uv, opacity_lod(object, duv_dx, duv_dy), 0.5);
}

// The cube face a direction `d` from a light falls in: +x, −x, +y, −y, +z,
// −z (the major axis, as cube-map lookups choose it).
fn cube_face(d: vec3f) -> u32 {
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x > 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

// A triangle covering the whole target (for screen-space passes).
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}
