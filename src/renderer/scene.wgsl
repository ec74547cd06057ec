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
    // x 1 if a normal map is bound, y procedural octaves
    flags: vec4f,
};

@group(2) @binding(0) var<uniform> material: MaterialGpu;
@group(2) @binding(1) var diffuse_tex: texture_2d<f32>;
@group(2) @binding(2) var normal_tex: texture_2d<f32>;
@group(2) @binding(3) var tex_sampler: sampler;
@group(3) @binding(0) var masks: texture_2d_array<f32>;

struct GOut {
    @invariant @builtin(position) clip: vec4f,
    @location(0) world_pos: vec3f,
    @location(1) @interpolate(flat) object: u32,
};

@vertex
fn vs_gbuffer(v: VertexIn) -> GOut {
    var o: GOut;
    o.clip = clip_position(v.object, v.position);
    o.world_pos = (objects[v.object].model * vec4f(v.position, 1.0)).xyz;
    o.object = v.object;
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
};

@fragment
fn fs_gbuffer(i: GOut) -> GBuffer {
    var g: GBuffer;
    g.position = vec4f(i.world_pos, f32(i.object + 1u));
    g.normal = vec4f(face_normal(i.world_pos), f32(objects[i.object].info.z));
    return g;
}

struct LitOut {
    @invariant @builtin(position) clip: vec4f,
    @location(0) world_pos: vec3f,
    @location(1) normal: vec3f,
    @location(2) uv: vec2f,
    @location(3) tangent: vec4f,
    @location(4) local_pos: vec3f,
    @location(5) @interpolate(flat) object: u32,
    // Gouraud: per-light diffuse (xyz) and specular intensity (w)... as
    // diffuse rgb and specular rgb packed in two vec4 per light pair.
    @location(6) g_diffuse0: vec4f,
    @location(7) g_diffuse1: vec4f,
    @location(8) g_diffuse2: vec4f,
    @location(9) g_diffuse3: vec4f,
    @location(10) g_specular0: vec4f,
    @location(11) g_specular1: vec4f,
    @location(12) g_specular2: vec4f,
    @location(13) g_specular3: vec4f,
};

// Phong (V·R)^n or Blinn-Phong (N·H)^n specular and Lambert diffuse for one
// light: returns (diffuse rgb, specular rgb) before material colours.
fn light_terms(i: u32, pos: vec3f, n: vec3f, v: vec3f, shininess: f32) -> array<vec3f, 2> {
    let s = sample_light(i, pos);
    let ndl = dot(n, s.to_light);
    if ndl <= 0.0 {
        return array<vec3f, 2>(vec3f(0.0), vec3f(0.0));
    }
    var spec: f32;
    if frame.settings.y == 0u {
        spec = pow(max(dot(v, reflect(-s.to_light, n)), 0.0), shininess);
    } else {
        spec = pow(max(dot(n, normalize(s.to_light + v)), 0.0), shininess);
    }
    return array<vec3f, 2>(s.radiance * ndl, s.radiance * spec);
}

@vertex
fn vs_lit(v: VertexIn) -> LitOut {
    var o: LitOut;
    let obj = objects[v.object];
    o.clip = clip_position(v.object, v.position);
    o.world_pos = (obj.model * vec4f(v.position, 1.0)).xyz;
    o.normal = normalize((obj.normal_matrix * vec4f(v.normal, 0.0)).xyz);
    o.uv = v.uv;
    // A mirroring model matrix flips cross(n, t): flip the handedness with it.
    let mirror = sign(determinant(mat3x3f(obj.model[0].xyz, obj.model[1].xyz, obj.model[2].xyz)));
    o.tangent = vec4f(normalize((obj.model * vec4f(v.tangent.xyz, 0.0)).xyz), v.tangent.w * mirror);
    o.local_pos = v.position;
    o.object = v.object;
    if frame.settings.x == 1u {
        // Gouraud: intensities per vertex, interpolated (SEEDS §1).
        let view = normalize(frame.camera_pos.xyz - o.world_pos);
        var d: array<vec4f, 4>;
        var s: array<vec4f, 4>;
        for (var i = 0u; i < frame.settings.z; i++) {
            let t = light_terms(i, o.world_pos, o.normal, view, material.ks.w);
            d[i] = vec4f(t[0], 0.0);
            s[i] = vec4f(t[1], 0.0);
        }
        o.g_diffuse0 = d[0];
        o.g_diffuse1 = d[1];
        o.g_diffuse2 = d[2];
        o.g_diffuse3 = d[3];
        o.g_specular0 = s[0];
        o.g_specular1 = s[1];
        o.g_specular2 = s[2];
        o.g_specular3 = s[3];
    }
    return o;
}

@fragment
fn fs_lit(i: LitOut) -> @location(0) vec4f {
    let obj = objects[i.object];
    let view = normalize(frame.camera_pos.xyz - i.world_pos);
    // Surface colours: texture or procedural pattern modulate kd and ka.
    var kd = material.kd.rgb;
    var ka = material.ka.rgb;
    let uv = i.uv * material.ka.w;
    if material.kd.w > 0.5 {
        let t = textureSample(diffuse_tex, tex_sampler, uv).rgb;
        kd *= t;
        ka *= t;
    }
    let kind = u32(material.proc_a.w);
    if kind > 0u {
        let f = procedural_factor(kind, i.local_pos, material.proc_b.w, u32(material.flags.y));
        kd = mix(material.proc_a.rgb, material.proc_b.rgb, f);
        ka = kd;
    }
    // Normal: face normal (flat) or interpolated, normal-mapped (per-pixel).
    let geo = face_normal(i.world_pos);
    var n = geo;
    if frame.settings.x != 0u {
        n = normalize(i.normal);
        if dot(n, geo) < 0.0 {
            n = -n; // two-sided lighting for open meshes
        }
        if frame.settings.x == 2u && material.flags.x > 0.5 {
            let t = normalize(i.tangent.xyz - n * dot(n, i.tangent.xyz));
            let b = cross(n, t) * i.tangent.w;
            let m = textureSample(normal_tex, tex_sampler, uv).xyz * 2.0 - 1.0;
            n = normalize(t * m.x + b * m.y + n * m.z);
        }
    }
    // Relight lights add v·(diffuse + specular); darken lights add their
    // full light and multiply the final colour by v.
    var color = frame.ambient.rgb * ka;
    var darken = 1.0;
    let px = vec2i(i.clip.xy);
    let receives = obj.info.z != 0u;
    let gd = array<vec4f, 4>(i.g_diffuse0, i.g_diffuse1, i.g_diffuse2, i.g_diffuse3);
    let gs = array<vec4f, 4>(i.g_specular0, i.g_specular1, i.g_specular2, i.g_specular3);
    for (var l = 0u; l < frame.settings.z; l++) {
        var vis = 1.0;
        if receives {
            vis = textureLoad(masks, px, l, 0).r;
        }
        var diffuse: vec3f;
        var specular: vec3f;
        if frame.settings.x == 1u {
            diffuse = gd[l].rgb;
            specular = gs[l].rgb;
        } else {
            let t = light_terms(l, i.world_pos, n, view, material.ks.w);
            diffuse = t[0];
            specular = t[1];
        }
        let direct = diffuse * kd + specular * material.ks.rgb;
        if frame.lights[l].extra.x > 0.5 {
            color += direct;
            darken *= vis;
        } else {
            color += vis * direct;
        }
    }
    return vec4f(color * darken, 1.0);
}

