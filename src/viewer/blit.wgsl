// Copies (and, with supersampling, filters down) the rendered frame, or shows
// one light's visibility mask in grey, onto the window's target; blends
// egui's cached layer over it.

struct Blit {
    // x mode (0 colour, filtered down from a supersampled frame; 1 mask;
    // 2 a premultiplied layer of the target's size, with its alpha; 3 colour
    // of the viewport's size), y mask layer
    mode: vec4u,
};

@group(0) @binding(0) var<uniform> blit: Blit;
@group(0) @binding(1) var source: texture_2d<f32>;
@group(0) @binding(2) var masks: texture_2d_array<f32>;
@group(0) @binding(3) var linear_sampler: sampler;

struct Out {
    @builtin(position) clip: vec4f,
    @location(0) uv: vec2f,
};

@vertex
fn vs_blit(@builtin(vertex_index) i: u32) -> Out {
    let uv = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    var o: Out;
    o.clip = vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
    o.uv = vec2f(uv.x, 1.0 - uv.y);
    return o;
}

@fragment
fn fs_blit(i: Out) -> @location(0) vec4f {
    if blit.mode.x == 1u {
        let size = vec2f(textureDimensions(masks));
        let v = textureLoad(masks, vec2i(i.uv * size), i32(blit.mode.y), 0).r;
        return vec4f(vec3f(v), 1.0);
    }
    if blit.mode.x >= 2u {
        // The source has the viewport's size: one texel per pixel, no filter.
        let size = vec2f(textureDimensions(source));
        let c = textureLoad(source, vec2i(i.uv * size), 0);
        return select(vec4f(c.rgb, 1.0), c, blit.mode.x == 2u);
    }
    return vec4f(textureSample(source, linear_sampler, i.uv).rgb, 1.0);
}
