// common.wgsl is prepended; group 1 (objects) is unused here.
// Light icons: unlit meshes in the light's colour.
struct IconUniform {
    model: mat4x4f,
    color: vec4f,
};
@group(2) @binding(0) var<uniform> icon: IconUniform;

struct IconOut {
    @builtin(position) clip: vec4f,
    @location(0) shade: f32,
};

@vertex
fn vs_icon(@location(0) position: vec3f, @location(1) normal: vec3f) -> IconOut {
    var o: IconOut;
    o.clip = frame.view_proj * (icon.model * vec4f(position, 1.0));
    // A little headlight shading so the shape reads.
    let n = normalize((icon.model * vec4f(normal, 0.0)).xyz);
    let p = (icon.model * vec4f(position, 1.0)).xyz;
    o.shade = 0.6 + 0.4 * abs(dot(n, normalize(frame.camera_pos.xyz - p)));
    return o;
}

@fragment
fn fs_icon(i: IconOut) -> @location(0) vec4f {
    return vec4f(icon.color.rgb * i.shade, 1.0);
}
