// Debug views: face 0 of the map, the map projected onto the scene
// (tinted per cascade), texels per pixel, and the numbers `compare` reads.

// Debug view: face 0 of the map as grey (near dark, far light), in linear depth.
@fragment
fn fs_debug_map(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let uv = frag.xy / 256.0;
    if VIRTUAL {
        // The physical pool's first layer: every page, as rendered.
        let side = f32(vsm.atlas_pages * vsm.slot_texels);
        return vec4f(vec3f(textureLoad(depth_map, vec2i(uv * side), 0, 0)), 1.0);
    }
    let t = vec2i(uv * sm.map.x);
    var d: f32;
    if FILTER_KIND >= FILTER_VSM {
        d = moment_texel(t, 0u).x;
        if FILTER_KIND == FILTER_EVSM2 || FILTER_KIND == FILTER_EVSM4 {
            d = 1.0 + log(max(d, 1e-30)) / sm.moments.y;
        }
    } else {
        let z = stored(t, 0u);
        d = (linear_depth(z) - sm.depth.x) / (sm.depth.y - sm.depth.x);
        if is_orthographic() || is_paraboloid() {
            d = z;
        }
    }
    return vec4f(vec3f(clamp(d, 0.0, 1.0)), 1.0);
}

struct DebugFrame {
    // The map's stored depth where each pixel projects (grey, tinted by
    // cascade: red, green, blue, yellow, …; dark red outside the map).
    @location(0) projection: vec4f,
    // Shadow-map texels per screen pixel (the aliasing measure of [001] §3
    // d = ds·rs/ri·cosα/cosβ, measured with screen derivatives), log2-coloured:
    // blue < 1/4 (undersampled: aliasing), green 1, red > 4 (oversampled).
    @location(1) texels: vec4f,
    // Numbers for `compare`: x the screen pixels one map texel spans along
    // its longer axis (> 1: a texel covers more than a pixel), y the face or
    // cascade looked up + 1; both 0 where nothing is looked up.
    @location(2) lookup: vec2f,
};

// A colour per cascade for the debug view.
fn cascade_tint(i: u32) -> vec3f {
    let tints = array<vec3f, 8>(
        vec3f(1.0, 0.45, 0.45), vec3f(0.45, 1.0, 0.45), vec3f(0.5, 0.6, 1.0), vec3f(1.0, 1.0, 0.4),
        vec3f(1.0, 0.5, 1.0), vec3f(0.4, 1.0, 1.0), vec3f(1.0, 0.75, 0.4), vec3f(0.8, 0.8, 0.8),
    );
    return tints[min(i, 7u)];
}

// Screen pixels a texel spans along its longer axis: the longer column of
// the inverse of J = ∂(texel)/∂(pixel), at most the frame's diagonal (a
// texel seen edge-on spans the whole view).
fn texel_footprint(dx: vec2f, dy: vec2f) -> f32 {
    let diagonal = length(frame.size.xy);
    let det = dx.x * dy.y - dy.x * dx.y;
    let span = max(length(vec2f(dy.y, dx.y)), length(vec2f(dy.x, dx.x)));
    if abs(det) * diagonal <= span {
        return diagonal;
    }
    return span / abs(det);
}

@fragment
fn fs_debug_frame(@builtin(position) frag: vec4f) -> DebugFrame {
    if VIRTUAL {
        return virtual_debug_frame(frag);
    }
    let g = textureLoad(gbuffer_position, vec2i(frag.xy), 0);
    // Derivatives first, in uniform control flow: of the surface point
    // (a texture load), mapped through the face's projection by finite
    // difference. Derivatives of values read from the parameter block
    // itself come out wrong on lavapipe when it is a storage buffer.
    let gx = dpdx(g.xyz);
    let gy = dpdy(g.xyz);
    let face = face_of(g.xyz);
    let c = clip_of(face, g.xyz);
    let uv = map_point(face, g.xyz).xy;
    let texel = uv * sm.map.x;
    let dx = (map_point(face, g.xyz + gx).xy - uv) * sm.map.x;
    let dy = (map_point(face, g.xyz + gy).xy - uv) * sm.map.x;
    let footprint = max(length(dx), length(dy));
    let pixels_per_texel = texel_footprint(dx, dy);
    var o: DebugFrame;
    let inside = g.w > 0.5 && c.w > 0.0 && all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0));
    var d = stored(vec2i(floor(texel)), face);
    if !is_orthographic() && !is_paraboloid() {
        d = (linear_depth(d) - sm.depth.x) / (sm.depth.y - sm.depth.x);
    }
    var tint = vec3f(1.0);
    if CASCADED {
        tint = cascade_tint(face);
    }
    o.projection = select(vec4f(0.5, 0.0, 0.0, 1.0), vec4f(tint * (0.35 + 0.65 * d), 1.0), inside);
    let t = clamp(log2(max(footprint, 1e-6)) / 2.0, -1.0, 1.0);
    let colour = select(mix(vec3f(0.0, 1.0, 0.0), vec3f(1.0, 0.0, 0.0), t), mix(vec3f(0.0, 1.0, 0.0), vec3f(0.0, 0.2, 1.0), -t), t < 0.0);
    o.texels = select(vec4f(0.0, 0.0, 0.0, 1.0), vec4f(colour, 1.0), inside);
    o.lookup = select(vec2f(0.0), vec2f(pixels_per_texel, f32(face + 1u)), inside);
    return o;
}
