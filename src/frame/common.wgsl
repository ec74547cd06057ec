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

struct ObjectGpu {
    model: mat4x4f,
    normal_matrix: mat4x4f,
    // x material, y casts shadow, z receives shadow, w bounds a solid (closed,
    // wound outward: its back faces lie behind its front faces)
    info: vec4u,
    // x the global ID of the object's convex parts less one (IDs are unique
    // in the scene; 0 is no part), yzw unused
    parts: vec4u,
};

// The scene-wide ID of `object`'s convex part `part` (0: none).
fn part_id(object: u32, part: u32) -> u32 {
    return select(0u, objects[object].parts.x + part, part != 0u);
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(1) @binding(0) var<storage, read> objects: array<ObjectGpu>;

struct VertexIn {
    @location(0) position: vec3f,
    @location(1) normal: vec3f,
    @location(2) uv: vec2f,
    @location(3) tangent: vec4f,
    // the mesh's convex part (from 1), 0 for none: `part_id` makes it global
    @location(4) part: u32,
    @builtin(instance_index) object: u32,
};

// Clip-space position; every pass that depth-tests against the prepass uses
// this one function with an @invariant output so depths match exactly.
fn clip_position(object: u32, p: vec3f) -> vec4f {
    return frame.view_proj * (objects[object].model * vec4f(p, 1.0));
}

// A triangle covering the whole target (for screen-space passes).
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}
