// Planar projected shadows ([000] §2, [001] §2, [003]). common.wgsl and gbuffer.wgsl are prepended.

struct PlanarUniform {
    // M = (P·L)·I − L·Pᵀ
    shadow: mat4x4f,
    // receiver plane, oriented so that the light is on its positive side
    plane: vec4f,
    // x visibility inside the shadow (1 − darkening), y depth offset (NDC),
    // z plane tolerance (world units)
    params: vec4f,
};

@group(2) @binding(0) var<uniform> planar: PlanarUniform;

// Stencil tag: passes (and writes the plane's id) where the visible,
// shadow-receiving surface lies on the receiver plane.
@fragment
fn fs_tag(@builtin(position) p: vec4f) -> @location(0) vec4f {
    let g = textureLoad(gbuffer_position, vec2i(p.xy), 0);
    let n = textureLoad(gbuffer_normal, vec2i(p.xy), 0);
    if g.w < 0.5 || n.w < 0.5 || abs(dot(planar.plane, vec4f(g.xyz, 1.0))) > planar.params.z {
        discard;
    }
    return vec4f(1.0);
}

struct FlatOut {
    @builtin(position) clip: vec4f,
    // signed distance of the original caster point above the plane
    @location(0) height: f32,
    @location(1) uv: vec2f,
    @location(2) @interpolate(flat) object: u32,
    @location(3) @interpolate(flat) see_through: u32,
};

// Casters flattened onto the plane through M. Parts beyond the light
// (anti-shadows) get clip w < 0 and are clipped by the rasterizer.
@vertex
fn vs_flatten(v: VertexIn) -> FlatOut {
    let world = objects[v.object].model * vec4f(v.position, 1.0);
    var o: FlatOut;
    o.clip = frame.view_proj * (planar.shadow * world);
    // Towards the camera: up, in the frame's reversed depth.
    o.clip.z += planar.params.y * o.clip.w;
    o.height = dot(planar.plane, world);
    o.uv = v.uv;
    o.object = v.object;
    o.see_through = objects[v.object].alpha.x;
    return o;
}

@fragment
fn fs_flatten(i: FlatOut) -> @location(0) vec4f {
    // False shadows: caster parts behind (or on) the receiver plane. The
    // perspective-correct interpolation of `height` is exact in the caster's
    // own plane, so this clips each triangle at the receiver plane. Cut-out
// casters drop their holes.
    let solid = caster_is_solid(i.object, i.see_through != 0u, i.uv, dpdx(i.uv), dpdy(i.uv));
    if i.height <= planar.params.z || !solid {
        discard;
    }
    return vec4f(planar.params.x);
}
