// `blended_casters=transmit`: translucent (glTF BLEND) casters kept apart
// from the depth map, in two maps beside it per face — the nearest one's
// depth, and the product of 1 − opacity over those before the nearest
// opaque caster — which a receiver behind the nearest one takes as the
// share of the light that reaches it (the reference's transmittance, for
// translucent surfaces with no receiver between them).

override TRANSMIT: bool = false;

@group(2) @binding(15) var transmit_depth: texture_depth_2d_array;
@group(2) @binding(16) var transmittance: texture_2d_array<f32>;

struct TransmitOut {
    // 1 − this is what the blend state multiplies the texel by
    @location(0) opacity: vec4f,
    // the depth the opaque pass stored for this face (linear on warped faces)
    @builtin(frag_depth) depth: f32,
};

// The transmittance pass: a translucent caster's fragment in front of the
// opaque map multiplies its texel by 1 − its opacity (the blend state),
// the opacity map read at the mip level of the light's texel footprint. A
// double-sided surface is one surface, as the reference counts it: of its
// two coincident copies, the one facing the light.
@fragment
fn fs_transmittance(i: DepthOut, @builtin(front_facing) facing: bool) -> TransmitOut {
    let lod = opacity_lod_across(i.object, dpdx(i.uv), dpdy(i.uv));
    let other_side = objects[i.object].parts.z != 0u && !facing;
    if other_side || (is_paraboloid() && i.hemisphere < 0.0) {
        discard;
    }
    var o: TransmitOut;
    o.opacity = vec4f(opacity_at(i.object, i.uv, lod));
    o.depth = select(i.clip.z, i.linear, is_warped());
    return o;
}

// Clears a virtual map page's slot of the transmittance pool: all the
// light through.
@fragment
fn fs_clear_transmittance() -> @location(0) vec4f {
    return vec4f(1.0);
}

// The texel of the transmittance maps that holds map texel t of `face`
// (clamped to the map), and its layer: through the page table for a
// virtual map's level being filtered (layer −1 where no page is resident).
fn transmit_texel(t: vec2i, face: u32) -> vec3i {
    if VIRTUAL {
        return filtered_texel(t);
    }
    return vec3i(clamp(t, vec2i(0), vec2i(i32(sm.map.x) - 1)), i32(face));
}

// The share of the light the translucent casters let through to a receiver
// at map depth `z` at `uv` of `face`: their transmittance at each of the
// four texels around uv whose nearest translucent caster lies before the
// receiver (else 1), weighted as the 2×2 comparison weighs them.
fn transmitted(uv: vec2f, face: u32, z: f32) -> f32 {
    let base = vec2i(floor(uv * sm.map.x - 0.5));
    var corners = array(vec2i(0, 1), vec2i(1, 1), vec2i(1, 0), vec2i(0, 0));
    var t = vec4f(1.0);
    for (var k = 0; k < 4; k++) {
        let a = transmit_texel(base + corners[k], face);
        if a.z >= 0 && z > textureLoad(transmit_depth, a.xy, a.z, 0) {
            t[k] = textureLoad(transmittance, a.xy, a.z, 0).r;
        }
    }
    return bilinear_weighted(t, uv);
}
