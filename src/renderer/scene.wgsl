// Scene passes: the depth + G-buffer prepass, the lighting pass that
// composes ambient + Σ visibility × (diffuse + specular), and light icons.
// common.wgsl and procedural.wgsl are prepended.

struct MaterialGpu {
    // rgb ka, w uv scale
    ka: vec4f,
    // rgb kd, w 1 if a diffuse texture is bound
    kd: vec4f,
    // rgb ks, w shininess
    ks: vec4f,
    // rgb procedural colour a, w procedural kind (0 none)
    proc_a: vec4f,
    // rgb procedural colour b, w procedural scale
    proc_b: vec4f,
    // x 1 if a normal map is bound, y procedural octaves, z opacity factor,
    // w the wrap modes (WRAP_*) of the diffuse texture along u, v and of the
    // normal map along u, v, in base 4
    flags: vec4f,
};

@group(2) @binding(0) var<uniform> material: MaterialGpu;
@group(2) @binding(1) var diffuse_tex: texture_2d<f32>;
@group(2) @binding(2) var normal_tex: texture_2d<f32>;
@group(3) @binding(0) var masks: texture_2d_array<f32>;
@group(3) @binding(1) var tex_sampler: sampler;

// Per-object values reach the fragment stage as flat varyings: one object
// table read per vertex instead of one per pixel (a storage-buffer read per
// pixel costs lavapipe more than the whole face normal).
struct GOut {
    @invariant @builtin(position) clip: vec4f,
    @location(0) world_pos: vec3f,
    @location(1) @interpolate(flat) object: u32,
    @location(2) @interpolate(flat) receives: u32,
    @location(3) @interpolate(flat) part: u32,
    @location(4) uv: vec2f,
};

@vertex
fn vs_gbuffer(v: VertexIn) -> GOut {
    var o: GOut;
    o.uv = v.uv;
    o.clip = clip_position(v.object, v.position);
    o.world_pos = (objects[v.object].model * vec4f(v.position, 1.0)).xyz;
    o.object = v.object;
    o.receives = objects[v.object].info.z;
    o.part = part_id(v.object, v.part);
    return o;
}

// Geometric (face) normal from screen derivatives, turned towards the eye.
fn face_normal(world_pos: vec3f) -> vec3f {
    var n = normalize(cross(dpdx(world_pos), dpdy(world_pos)));
    if dot(n, frame.camera_pos.xyz - world_pos) < 0.0 {
        n = -n;
    }
    return n;
}

struct GBuffer {
    // xyz world position, w object index + 1 where geometry was drawn (0: background)
    @location(0) position: vec4f,
    // xyz geometric normal facing the camera, w 1 if the surface receives shadows
    @location(1) normal: vec4f,
    // the convex part drawn (`part_id`), 0: none
    @location(2) part: u32,
};

fn gbuffer_of(i: GOut) -> GBuffer {
    var g: GBuffer;
    g.position = vec4f(i.world_pos, f32(i.object + 1u));
    g.normal = vec4f(face_normal(i.world_pos), f32(i.receives));
    g.part = i.part;
    return g;
}

@fragment
fn fs_gbuffer(i: GOut) -> GBuffer {
    return gbuffer_of(i);
}

// Cut-out surfaces: no G-buffer sample where the opacity map has a hole, at
// the mip level of the pixel's footprint.
@fragment
fn fs_gbuffer_cutout(i: GOut) -> GBuffer {
    let g = gbuffer_of(i);
    let lod = opacity_lod(i.object, dpdx(i.uv), dpdy(i.uv));
    if !is_solid_at(i.object, i.uv, lod, 0.5) {
        discard;
    }
    return g;
}

// The lighting pass is specialised per pipeline (pipeline-overridable
// constants, set by `LitKey` in lighting.rs): the light count bounds every
// loop, and the shading mode, specular model and material features are
// constants, so no pipeline branches on them per pixel.
override LIGHT_COUNT: u32 = 1u;
// Per light i, four bits from bit 4i (`LitLight::spec_bits`): the kind
// (LIGHT_*, two bits), 4 if its range window applies, 8 if its mask darkens
// the lit colour instead of removing the light.
override LIGHT_SPECS: u32 = 0u;
// Shading mode: 0 flat, 1 Gouraud, 2 per-pixel (entry points differ for Gouraud).
override SHADING: u32 = 2u;
// 0 Phong (V·R)^n, 1 Blinn-Phong (N·H)^n.
override SPECULAR: u32 = 1u;
override DIFFUSE_TEXTURE: bool = false;
override NORMAL_MAP: bool = false;
// 0 none, else the kind of `procedural_factor`.
override PROCEDURAL: u32 = 0u;
// A translucent surface, blended over the opaque image: not in the G-buffer,
// so the masks (which belong to what lies behind it) do not apply to it.
override TRANSLUCENT: bool = false;

const SHADING_FLAT: u32 = 0u;
const SHADING_PIXEL: u32 = 2u;
const SPECULAR_PHONG: u32 = 0u;

const SPEC_WINDOWED: u32 = 4u;
const SPEC_DARKEN: u32 = 8u;

fn light_spec(i: u32) -> u32 {
    return (LIGHT_SPECS >> (4u * i)) & 15u;
}

struct LitOut {
    @invariant @builtin(position) clip: vec4f,
    @location(0) world_pos: vec3f,
    @location(1) normal: vec3f,
    @location(2) uv: vec2f,
    @location(3) tangent: vec4f,
    @location(4) local_pos: vec3f,
    @location(5) @interpolate(flat) receives: u32,
    @location(6) color: vec3f,
};

// Gouraud: the vertex's lighting terms ride along, per light diffuse (rgb)
// and specular (rgb) radiance before material colours.
struct GouraudOut {
    @invariant @builtin(position) clip: vec4f,
    @location(0) world_pos: vec3f,
    @location(1) uv: vec2f,
    @location(2) local_pos: vec3f,
    @location(3) @interpolate(flat) receives: u32,
    @location(4) diffuse0: vec3f,
    @location(5) diffuse1: vec3f,
    @location(6) diffuse2: vec3f,
    @location(7) diffuse3: vec3f,
    @location(8) specular0: vec3f,
    @location(9) specular1: vec3f,
    @location(10) specular2: vec3f,
    @location(11) specular3: vec3f,
    @location(12) color: vec3f,
};

// Direction to the light (unit) and the radiance reaching `pos`
// (colour × intensity × range window × spot cone), for light `i`. The
// uniform's light directions are unit vectors (`LightGpu::from_light`).
struct LightSample {
    to_light: vec3f,
    radiance: vec3f,
};

fn sample_light(i: u32, pos: vec3f) -> LightSample {
    let l = frame.lights[i];
    var s: LightSample;
    let kind = light_spec(i) & 3u;
    if kind == LIGHT_DIRECTIONAL {
        s.to_light = -l.direction.xyz;
        s.radiance = l.color.rgb;
        return s;
    }
    let d = l.position.xyz - pos;
    let dist = length(d);
    s.to_light = d / max(dist, 1e-6);
    var att = 1.0;
    if (light_spec(i) & SPEC_WINDOWED) != 0u {
        let range = l.position.w;
        // x = 1 − (dist / range)⁴, squared (without pow: exp2/log2 per pixel)
        let q = dist * dist / (range * range);
        let x = clamp(1.0 - q * q, 0.0, 1.0);
        att = x * x;
    }
    if kind == LIGHT_SPOT {
        let c = dot(-s.to_light, l.direction.xyz);
        att *= smoothstep(l.direction.w, l.color.w, c);
    }
    s.radiance = l.color.rgb * att;
    return s;
}

struct LightTerms {
    diffuse: vec3f,
    specular: vec3f,
};

// Lambert diffuse and Phong (V·R)^n or Blinn-Phong (N·H)^n specular
// radiance of light `i` at `pos`, before material colours.
fn light_terms(i: u32, pos: vec3f, n: vec3f, v: vec3f, shininess: f32) -> LightTerms {
    let s = sample_light(i, pos);
    let ndl = dot(n, s.to_light);
    if ndl <= 0.0 {
        return LightTerms(vec3f(0.0), vec3f(0.0));
    }
    var spec: f32;
    if SPECULAR == SPECULAR_PHONG {
        spec = pow(max(dot(v, reflect(-s.to_light, n)), 0.0), shininess);
    } else {
        spec = pow(max(dot(n, normalize(s.to_light + v)), 0.0), shininess);
    }
    return LightTerms(s.radiance * ndl, s.radiance * spec);
}

fn world_normal(obj: ObjectGpu, n: vec3f) -> vec3f {
    return normalize((obj.normal_matrix * vec4f(n, 0.0)).xyz);
}

// A vertex's colour, linear, from its sRGB encoding.
fn vertex_color(encoded: vec4f) -> vec3f {
    let c = encoded.rgb;
    return select(pow((c + 0.055) / 1.055, vec3f(2.4)), c / 12.92, c <= vec3f(0.04045));
}

@vertex
fn vs_lit(v: VertexIn) -> LitOut {
    var o: LitOut;
    let obj = objects[v.object];
    o.clip = clip_position(v.object, v.position);
    o.world_pos = (obj.model * vec4f(v.position, 1.0)).xyz;
    o.normal = world_normal(obj, v.normal);
    // Scaled here, so that the texture's LOD comes from the derivatives of
    // a varying: lavapipe 22 gets those of values read from a parameter
    // block wrong when the block is a storage buffer.
    o.uv = v.uv * material.ka.w;
    // A mirroring model matrix flips cross(n, t): flip the handedness with it.
    let mirror = sign(determinant(mat3x3f(obj.model[0].xyz, obj.model[1].xyz, obj.model[2].xyz)));
    o.tangent = vec4f(normalize((obj.model * vec4f(v.tangent.xyz, 0.0)).xyz), v.tangent.w * mirror);
    o.local_pos = v.position;
    o.receives = obj.info.z;
    o.color = vertex_color(v.color);
    return o;
}

@vertex
fn vs_lit_gouraud(v: VertexIn) -> GouraudOut {
    var o: GouraudOut;
    let obj = objects[v.object];
    o.clip = clip_position(v.object, v.position);
    o.world_pos = (obj.model * vec4f(v.position, 1.0)).xyz;
    o.uv = v.uv * material.ka.w;
    o.local_pos = v.position;
    o.receives = obj.info.z;
    o.color = vertex_color(v.color);
    // Intensities per vertex, interpolated ([004]).
    let n = world_normal(obj, v.normal);
    let view = normalize(frame.camera_pos.xyz - o.world_pos);
    if LIGHT_COUNT > 0u {
        let t = light_terms(0u, o.world_pos, n, view, material.ks.w);
        o.diffuse0 = t.diffuse;
        o.specular0 = t.specular;
    }
    if LIGHT_COUNT > 1u {
        let t = light_terms(1u, o.world_pos, n, view, material.ks.w);
        o.diffuse1 = t.diffuse;
        o.specular1 = t.specular;
    }
    if LIGHT_COUNT > 2u {
        let t = light_terms(2u, o.world_pos, n, view, material.ks.w);
        o.diffuse2 = t.diffuse;
        o.specular2 = t.specular;
    }
    if LIGHT_COUNT > 3u {
        let t = light_terms(3u, o.world_pos, n, view, material.ks.w);
        o.diffuse3 = t.diffuse;
        o.specular3 = t.specular;
    }
    return o;
}

// Surface colours: the vertex colour, texture or procedural pattern
// modulate kd and ka; the opacity is the factor times the texture's alpha.
struct SurfaceColors {
    ka: vec3f,
    kd: vec3f,
    opacity: f32,
};

// The wrap modes along u and v of the diffuse texture (`which` 0) or the
// normal map (1).
fn material_wrap(which: u32) -> vec2u {
    let code = u32(material.flags.w) >> (4u * which);
    return vec2u(code & 3u, (code >> 2u) & 3u);
}

// One coordinate wrapped by `mode` into [0, 1] for the repeating sampler; a
// clamped or mirrored one kept `inset` (half a texel of the level read)
// inside the border, so that the sampler's bilinear taps do not reach the
// opposite border.
fn wrap_coordinate(c: f32, mode: u32, inset: f32) -> f32 {
    switch mode {
        case WRAP_CLAMP: {
            return clamp(c, inset, 1.0 - inset);
        }
        case WRAP_MIRROR: {
            return clamp(1.0 - abs(fract(c * 0.5) * 2.0 - 1.0), inset, 1.0 - inset);
        }
        default: {
            return c;
        }
    }
}

// `t` sampled at `uv` wrapped as `wrap` says (a glTF sampler's wrapS,
// wrapT), at the level the unwrapped coordinates' derivatives choose.
fn sample_wrapped(t: texture_2d<f32>, uv: vec2f, wrap: vec2u) -> vec4f {
    let dx = dpdx(uv);
    let dy = dpdy(uv);
    if all(wrap == vec2u(WRAP_REPEAT)) {
        return textureSampleGrad(t, tex_sampler, uv, dx, dy);
    }
    let size = vec2f(textureDimensions(t));
    let level = lod_of(max(length(dx * size), length(dy * size)));
    let inset = 0.5 * exp2(ceil(level)) / size;
    let w = vec2f(wrap_coordinate(uv.x, wrap.x, inset.x), wrap_coordinate(uv.y, wrap.y, inset.y));
    return textureSampleGrad(t, tex_sampler, w, dx, dy);
}

fn surface_colors(uv: vec2f, local_pos: vec3f, vertex_color: vec3f) -> SurfaceColors {
    var c = SurfaceColors(material.ka.rgb * vertex_color, material.kd.rgb * vertex_color, material.flags.z);
    if DIFFUSE_TEXTURE {
        let t = sample_wrapped(diffuse_tex, uv, material_wrap(0u));
        c.kd *= t.rgb;
        c.ka *= t.rgb;
        c.opacity *= t.a;
    }
    if PROCEDURAL > 0u {
        let f = procedural_factor(PROCEDURAL, local_pos, material.proc_b.w, u32(material.flags.y));
        c.kd = mix(material.proc_a.rgb, material.proc_b.rgb, f);
        c.ka = c.kd;
    }
    return c;
}

// Accumulates one light into `color` (relight: ambient + v·direct) or
// `darken` (darken: the final colour times v).
struct Composed {
    color: vec3f,
    darken: f32,
};

fn compose_light(acc: Composed, l: u32, vis: f32, terms: LightTerms, kd: vec3f) -> Composed {
    let direct = terms.diffuse * kd + terms.specular * material.ks.rgb;
    var out = acc;
    if (light_spec(l) & SPEC_DARKEN) != 0u {
        out.color += direct;
        out.darken *= vis;
    } else {
        out.color += vis * direct;
    }
    return out;
}

// The light's mask value at pixel `px` (1 where the object receives no
// shadow, and on translucent surfaces).
fn visibility(px: vec2i, l: u32, receives: bool) -> f32 {
    if receives && !TRANSLUCENT {
        return textureLoad(masks, px, l, 0).r;
    }
    return 1.0;
}

@fragment
fn fs_lit(i: LitOut) -> @location(0) vec4f {
    let receives = i.receives != 0u;
    let view = normalize(frame.camera_pos.xyz - i.world_pos);
    let uv = i.uv;
    let surface = surface_colors(uv, i.local_pos, i.color);
    // Normal: face normal (flat) or interpolated, normal-mapped (per-pixel).
    let geo = face_normal(i.world_pos);
    var n = geo;
    if SHADING != SHADING_FLAT {
        n = normalize(i.normal);
        if dot(n, geo) < 0.0 {
            n = -n; // two-sided lighting for open meshes
        }
        if SHADING == SHADING_PIXEL && NORMAL_MAP {
            let t = normalize(i.tangent.xyz - n * dot(n, i.tangent.xyz));
            let b = cross(n, t) * i.tangent.w;
            let m = sample_wrapped(normal_tex, uv, material_wrap(1u)).xyz * 2.0 - 1.0;
            n = normalize(t * m.x + b * m.y + n * m.z);
        }
    }
    let px = vec2i(i.clip.xy);
    var acc = Composed(frame.ambient.rgb * surface.ka, 1.0);
    for (var l = 0u; l < LIGHT_COUNT; l++) {
        let terms = light_terms(l, i.world_pos, n, view, material.ks.w);
        acc = compose_light(acc, l, visibility(px, l, receives), terms, surface.kd);
    }
    return vec4f(acc.color * acc.darken, select(1.0, surface.opacity, TRANSLUCENT));
}

@fragment
fn fs_lit_gouraud(i: GouraudOut) -> @location(0) vec4f {
    let receives = i.receives != 0u;
    let surface = surface_colors(i.uv, i.local_pos, i.color);
    let px = vec2i(i.clip.xy);
    var acc = Composed(frame.ambient.rgb * surface.ka, 1.0);
    if LIGHT_COUNT > 0u {
        acc = compose_light(acc, 0u, visibility(px, 0u, receives), LightTerms(i.diffuse0, i.specular0), surface.kd);
    }
    if LIGHT_COUNT > 1u {
        acc = compose_light(acc, 1u, visibility(px, 1u, receives), LightTerms(i.diffuse1, i.specular1), surface.kd);
    }
    if LIGHT_COUNT > 2u {
        acc = compose_light(acc, 2u, visibility(px, 2u, receives), LightTerms(i.diffuse2, i.specular2), surface.kd);
    }
    if LIGHT_COUNT > 3u {
        acc = compose_light(acc, 3u, visibility(px, 3u, receives), LightTerms(i.diffuse3, i.specular3), surface.kd);
    }
    return vec4f(acc.color * acc.darken, select(1.0, surface.opacity, TRANSLUCENT));
}
