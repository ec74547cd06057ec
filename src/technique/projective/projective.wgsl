// Projective shadow textures ([001] §3.5.3, [002] §1, [003] §2). common.wgsl and gbuffer.wgsl are prepended.

struct Projector {
    // light view-projection fitted around one caster
    view_proj: mat4x4f,
    // light view (for linear depth)
    view: mat4x4f,
    // bias · view_proj: world → (u, v, depth)
    texture: mat4x4f,
    // x near, y far, z alpha bias, w 1 = depth in alpha
    params: vec4f,
    // x caster object index, y texture size
    info: vec4u,
};

@group(2) @binding(0) var<uniform> projector: Projector;
@group(2) @binding(1) var shadow_texture: texture_2d<f32>;

// Linear depth in the projector's [near, far], 0 at the near plane.
fn linear_depth(world: vec3f) -> f32 {
    let z = -(projector.view * vec4f(world, 1.0)).z;
    return (z - projector.params.x) / (projector.params.y - projector.params.x);
}

struct CasterOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    @location(1) uv: vec2f,
    @location(2) @interpolate(flat) object: u32,
    @location(3) @interpolate(flat) see_through: u32,
};

@vertex
fn vs_caster(v: VertexIn) -> CasterOut {
    var o: CasterOut;
    let world = objects[v.object].model * vec4f(v.position, 1.0);
    o.clip = projector.view_proj * world;
    o.world = world.xyz;
    o.uv = v.uv;
    o.object = v.object;
    o.see_through = objects[v.object].alpha.x;
    return o;
}

// Black caster on white, or ([003] §4) its linear depth stored in 8 bits; a
// cut-out caster's holes stay white.
@fragment
fn fs_caster(i: CasterOut) -> @location(0) vec4f {
    if !caster_is_solid(i.object, i.see_through != 0u, i.uv, dpdx(i.uv), dpdy(i.uv)) {
        discard;
    }
    if projector.params.w > 0.5 {
        return vec4f(clamp(linear_depth(i.world), 0.0, 1.0));
    }
    return vec4f(0.0);
}

// Projects the texture onto the visible receivers (no depth test: the
// caster itself and anything nearer the light than the fitted near plane are
// left lit).
@fragment
fn fs_project(@builtin(position) p: vec4f) -> @location(0) vec4f {
    let g = textureLoad(gbuffer_position, vec2i(p.xy), 0);
    let n = textureLoad(gbuffer_normal, vec2i(p.xy), 0);
    if g.w < 0.5 || n.w < 0.5 {
        return vec4f(1.0);
    }
    let depth_mode = projector.params.w > 0.5;
    if !depth_mode && u32(g.w) - 1u == projector.info.x {
        return vec4f(1.0);
    }
    let t = projector.texture * vec4f(g.xyz, 1.0);
    if t.w <= 0.0 {
        return vec4f(1.0);
    }
    let uv = t.xy / t.w;
    let d = linear_depth(g.xyz);
    if any(uv < vec2f(0.0)) || any(uv >= vec2f(1.0)) || d < 0.0 {
        return vec4f(1.0);
    }
    let texel = textureLoad(shadow_texture, vec2i(uv * f32(projector.info.y)), 0).r;
    if depth_mode {
        // 1 (white) means no caster covered the texel.
        return vec4f(select(1.0, 0.0, texel < 1.0 && d > texel + projector.params.z));
    }
    return vec4f(texel);
}
