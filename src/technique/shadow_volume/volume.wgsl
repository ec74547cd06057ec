// Shadow volumes ([000] §3, [001] §4–5, [002] §3): the volume vertex shader that extrudes odd
// indices away from the light, the stencil-to-mask pass and the debug
// view. common.wgsl and gbuffer.wgsl are prepended.

struct Volume {
    // the light in world space: xyz position (w = 1) or the direction the
    // light travels (w = 0)
    light: vec4f,
    // x extrusion length in world units (0: to infinity, w = 0),
    // y mask value inside shadows (1 − darkening)
    extrusion: vec4f,
};

@group(2) @binding(0) var<uniform> volume: Volume;
// xyz object-space welded position, w the scene object id (bits)
@group(2) @binding(1) var<storage, read> positions: array<vec4f>;

// Index 2v: welded vertex v through the same @invariant transform as the
// prepass (so light caps on lit faces match the scene depth exactly);
// 2v + 1: extruded away from the light, to infinity as a direction
// (w = 0) or by `extrusion.x`.
@vertex
fn vs_volume(@builtin(vertex_index) i: u32) -> @invariant @builtin(position) vec4f {
    let p = positions[i >> 1u];
    let object = bitcast<u32>(p.w);
    if (i & 1u) == 0u {
        return clip_position(object, p.xyz);
    }
    let world = (objects[object].model * vec4f(p.xyz, 1.0)).xyz;
    var away = volume.light.xyz;
    if volume.light.w != 0.0 {
        away = world - volume.light.xyz;
    }
    if volume.extrusion.x <= 0.0 {
        return frame.view_proj * vec4f(away, 0.0);
    }
    return frame.view_proj * vec4f(world + normalize(away) * volume.extrusion.x, 1.0);
}

// No colour: the stencil counts. A fragment stage is present so that
// pipeline-statistics queries count the volumes' fragments.
@fragment
fn fs_volume() {
}

// Drawn where the stencil count is not 0: the shadow.
@fragment
fn fs_shadow() -> @location(0) vec4f {
    return vec4f(volume.extrusion.y);
}

// Debug view: the scene as grey N·V, then the volumes as translucent red.
@fragment
fn fs_debug_scene(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let n = textureLoad(gbuffer_normal, vec2i(frag.xy), 0).xyz;
    if dot(n, n) == 0.0 {
        return vec4f(0.05, 0.05, 0.08, 1.0);
    }
    return vec4f(vec3f(0.25 + 0.5 * abs(normalize(n).y)), 1.0);
}

@fragment
fn fs_debug_volume() -> @location(0) vec4f {
    return vec4f(1.0, 0.0, 0.0, 0.18);
}
