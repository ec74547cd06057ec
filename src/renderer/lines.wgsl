// Debug lines (light frusta, silhouettes) in world space. common.wgsl is prepended.

struct LineOut {
    @builtin(position) clip: vec4f,
    @location(0) color: vec4f,
};

@vertex
fn vs_line(@location(0) position: vec3f, @location(1) color: vec4f) -> LineOut {
    var o: LineOut;
    o.clip = frame.view_proj * vec4f(position, 1.0);
    o.color = color;
    return o;
}

@fragment
fn fs_line(i: LineOut) -> @location(0) vec4f {
    return i.color;
}
