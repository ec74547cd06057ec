// Shadow maps (SEEDS §5): the depth pass from the light and the
// screen-space lookup that writes the visibility mask. common.wgsl,
// gbuffer.wgsl and the `FILTER_*` constants generated from the `Filter`
// enum are prepended.

// Specialisation (pipeline-overridable constants, set per pipeline by
// pipelines.rs): the filter, taps per side, the 8-bit map and the
// receiver-plane bias are constants of each pipeline.
override FILTER_KIND: u32 = FILTER_GRID;
override TAPS: u32 = 3u;
override BYTE_MAP: bool = false;
override RECEIVER_PLANE: bool = false;

struct ShadowMap {
    // world → light clip, one per face (1 for spot/directional, 6 for point,
    // one per cascade)
    faces: array<mat4x4f, 8>,
    // xyz light position, w faces: 1, 6 (cube) or 2 (dual paraboloid, whose
    // `faces` are the two hemispheres' view matrices)
    light: vec4f,
    // x filter radius (texels), y normal offset (texels), z slope-scaled
    // bias of warped depth passes (per depth slope per pixel), w unused
    kernel: vec4f,
    // x map size, y 1/size, z world size of a texel at unit distance
    // (perspective, paraboloid) or of any texel (orthographic),
    // w projection: 0 perspective, 1 orthographic, 2 dual paraboloid
    map: vec4f,
    // x light size (texels at unit depth ratio, pcss), y variable-width scale,
    // z variable-width exponent, w blocker-search radius (texels)
    soft: vec4f,
    // x near, y far (to linearise perspective depth), z area-light radius
    // for pcss (0 = use soft.x), w constant bias of warped depth passes
    depth: vec4f,
    // x face rendered by the depth pass (or blurred), y blur axis (0 x, 1 y),
    // z blur radius (texels), w unused
    face: vec4u,
    // moments: x light-bleeding reduction, y exponent c (esm, evsm +),
    // z exponent c− (evsm), w moment bias (msm)
    moments: vec4f,
    // x cascades (0: not cascaded), y fraction of each cascade blended into
    // the next, z view depth where the first cascade starts
    cascade: vec4f,
    // view depth at which cascade i ends: [i / 4][i % 4]
    cascade_far: array<vec4f, 2>,
    // world size of a texel of cascade i: [i / 4][i % 4]
    cascade_texel: array<vec4f, 2>,
    // row z of the view matrix of the camera the cascades were fitted to
    cascade_view_z: vec4f,
    // xyz the direction the light travels, w 1 when the faces are warped
    // (LiSPSM: the texel size varies over the map)
    warp: vec4f,
    // Warped faces store depth linear along the light, 0 nearest it:
    // dot(row, (p, 1)) — a perspective's z/w would tilt every surface and
    // the slope bias with it.
    warp_depth: vec4f,
};

@group(2) @binding(0) var<uniform> sm: ShadowMap;
@group(2) @binding(3) var depth_map: texture_depth_2d_array;
@group(2) @binding(4) var compare_sampler: sampler_comparison;
@group(2) @binding(5) var byte_map: texture_2d_array<f32>;
@group(2) @binding(6) var moment_map: texture_2d_array<f32>;

// ---- depth pass

struct DepthOut {
    @builtin(position) clip: vec4f,
    // dual paraboloid: the cosine to the hemisphere's axis (< 0 behind it)
    @location(1) hemisphere: f32,
    // depth linear in distance, 0 at near and 1 at far (moment maps)
    @location(0) linear: f32,
};

// Linear depth in [0, 1] of a light-clip position.
fn linear01(c: vec4f) -> f32 {
    if sm.map.w > 0.5 {
        return c.z; // orthographic, or the paraboloid's linear depth
    }
    return (c.w - sm.depth.x) / (sm.depth.y - sm.depth.x);
}

fn is_paraboloid() -> bool {
    return sm.map.w > 1.5;
}

fn is_warped() -> bool {
    return sm.warp.w > 0.5;
}

// Dual-paraboloid projection (Brabec et al. 2002) of a world point for
// hemisphere `face`: xy = n.xy / (1 + n_forward), z = linear depth, w = 1;
// returns the forward cosine in `hemisphere`.
fn paraboloid(world: vec4f, face: u32) -> vec4f {
    let p = (sm.faces[face] * world).xyz;
    let d = length(p);
    let n = p / max(d, 1e-6);
    let forward = -n.z;
    return vec4f(n.xy / (1.0 + max(forward, -0.999)), (d - sm.depth.x) / (sm.depth.y - sm.depth.x), 1.0);
}

@vertex
fn vs_depth(v: VertexIn) -> DepthOut {
    var o: DepthOut;
    let world = objects[v.object].model * vec4f(v.position, 1.0);
    o.hemisphere = 1.0;
    if is_paraboloid() {
        o.clip = paraboloid(world, sm.face.x);
        let p = (sm.faces[sm.face.x] * world).xyz;
        o.hemisphere = -p.z / max(length(p), 1e-6);
    } else {
        o.clip = sm.faces[sm.face.x] * world;
    }
    o.linear = select(linear01(o.clip), dot(sm.warp_depth, world), is_warped());
    return o;
}

// Warped faces: the linear depth with the depth pass's bias applied here,
// as polygon offset would (constant + slope factor × the larger screen
// slope of the depth).
@fragment
fn fs_depth_linear(i: DepthOut) -> @builtin(frag_depth) f32 {
    let slope = max(abs(dpdx(i.linear)), abs(dpdy(i.linear)));
    return clamp(i.linear + sm.depth.w + sm.kernel.z * slope, 0.0, 1.0);
}

// The floor: a bare depth-only transform (no varyings, no fragment stage).
@vertex
fn vs_floor(v: VertexIn) -> @builtin(position) vec4f {
    let world = objects[v.object].model * vec4f(v.position, 1.0);
    if is_paraboloid() {
        return paraboloid(world, sm.face.x);
    }
    return sm.faces[sm.face.x] * world;
}

// Depth-only pass of a dual paraboloid: drop what lies behind the hemisphere.
@fragment
fn fs_depth_paraboloid(i: DepthOut) {
    if i.hemisphere < 0.0 {
        discard;
    }
}

// The moments each filter stores (Donnelly & Lauritzen 2006; Annen 2008;
// Lauritzen & McCool 2008; Peters & Klein 2015).
fn moments_of(z: f32) -> vec4f {
    let cp = sm.moments.y;
    let cn = sm.moments.z;
    switch FILTER_KIND {
        case FILTER_VSM: {
            return vec4f(z, z * z, 0.0, 0.0);
        }
        case FILTER_ESM: {
            return vec4f(exp(cp * (z - 1.0)), 0.0, 0.0, 0.0);
        }
        case FILTER_EVSM2, FILTER_EVSM4: {
            let p = exp(cp * (z - 1.0));
            let n = -exp(-cn * z);
            return vec4f(p, p * p, n, n * n);
        }
        default: {
            let z2 = z * z;
            return vec4f(z, z2, z2 * z, z2 * z2);
        }
    }
}

@fragment
fn fs_depth_moments(i: DepthOut) -> @location(0) vec4f {
    if i.hemisphere < 0.0 {
        discard;
    }
    return moments_of(clamp(i.linear, 0.0, 1.0));
}

// Separable box blur of one moment layer along one axis.
@fragment
fn fs_blur(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let r = i32(sm.face.z);
    let axis = select(vec2i(1, 0), vec2i(0, 1), sm.face.y == 1u);
    let size = i32(sm.map.x);
    var sum = vec4f(0.0);
    for (var k = -r; k <= r; k++) {
        let t = clamp(vec2i(frag.xy) + axis * k, vec2i(0), vec2i(size - 1));
        sum += textureLoad(moment_map, t, i32(sm.face.x), 0);
    }
    return sum / f32(2 * r + 1);
}

// The 8-bit preset stores the depth in an R8 colour target.
@fragment
fn fs_depth_byte(i: DepthOut) -> @location(0) vec4f {
    if i.hemisphere < 0.0 {
        discard;
    }
    return vec4f(select(i.clip.z, i.linear, is_warped()));
}

// ---- lookup

fn cascade_far(i: u32) -> f32 {
    return sm.cascade_far[i / 4u][i % 4u];
}

// The cascade of a point at view depth d (the cascade count beyond the
// last), and the weight of the next cascade in the blend band at the far
// end of this one.
struct CascadePick {
    index: u32,
    next_weight: f32,
};

fn cascade_of(p: vec3f) -> CascadePick {
    let d = -dot(sm.cascade_view_z, vec4f(p, 1.0));
    let count = u32(sm.cascade.x);
    var i = 0u;
    while i < count && d > cascade_far(i) {
        i++;
    }
    var pick = CascadePick(i, 0.0);
    if i + 1u < count && sm.cascade.y > 0.0 {
        let start = select(sm.cascade.z, cascade_far(i - 1u), i > 0u);
        let band = sm.cascade.y * (cascade_far(i) - start);
        pick.next_weight = clamp((d - (cascade_far(i) - band)) / band, 0.0, 1.0);
    }
    return pick;
}

// Face of a point light's six 90° frusta: the major axis of p − light.
fn face_of(p: vec3f) -> u32 {
    if sm.cascade.x > 0.5 {
        return min(cascade_of(p).index, u32(sm.cascade.x) - 1u);
    }
    if sm.light.w < 1.5 {
        return 0u;
    }
    if sm.light.w < 2.5 {
        return select(1u, 0u, (sm.faces[0] * vec4f(p, 1.0)).z <= 0.0);
    }
    let d = p - sm.light.xyz;
    let a = abs(d);
    if a.x >= a.y && a.x >= a.z {
        return select(1u, 0u, d.x > 0.0);
    }
    if a.y >= a.z {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

fn linear_depth(z: f32) -> f32 {
    if is_paraboloid() {
        return sm.depth.x + z * (sm.depth.y - sm.depth.x);
    }
    if sm.map.w > 0.5 {
        return z;
    }
    let n = sm.depth.x;
    let f = sm.depth.y;
    return n * f / (f - z * (f - n));
}

// Stored depth at a texel (nearest), from the depth map or the 8-bit map.
fn stored(texel: vec2i, face: u32) -> f32 {
    let size = i32(sm.map.x);
    let t = clamp(texel, vec2i(0), vec2i(size - 1));
    if BYTE_MAP {
        return textureLoad(byte_map, t, i32(face), 0).r;
    }
    return textureLoad(depth_map, t, i32(face), 0);
}

// Receiver-plane depth bias (Isidoro 2006): d(depth)/d(uv) of the receiver's
// plane, and the uv it was measured at; taps compare against that plane.
var<private> rp_gradient: vec2f;
var<private> rp_origin: vec2f;

// d(depth)/d(uv) from the screen derivatives of (u, v, depth): solve
// [du/dx dv/dx; du/dy dv/dy] · g = [dz/dx; dz/dy]. Must run in uniform
// control flow; 0 when off or degenerate (silhouettes, face seams), and
// clamped so that a derivative across an edge cannot swing a tap far.
fn receiver_plane(t: vec3f) -> vec2f {
    let dx = dpdx(t);
    let dy = dpdy(t);
    let det = dx.x * dy.y - dx.y * dy.x;
    let g = vec2f(dy.y * dx.z - dx.y * dy.z, dx.x * dy.z - dy.x * dx.z) / det;
    if !RECEIVER_PLANE || abs(det) < 1e-20 || any(g != g) {
        return vec2f(0.0);
    }
    return clamp(g, vec2f(-4.0), vec2f(4.0));
}

// The receiver depth to compare at a tap's uv.
fn tap_z(z: f32, uv: vec2f) -> f32 {
    return z + dot(uv - rp_origin, rp_gradient);
}

// 1 where the receiver depth z is not behind the stored depth.
fn lit_at(texel: vec2i, face: u32, z: f32) -> f32 {
    return select(0.0, 1.0, z <= stored(texel, face));
}

// Bilinear (hardware-style 2×2) comparison at uv.
fn pcf2x2(uv: vec2f, face: u32, z: f32) -> f32 {
    if !BYTE_MAP {
        return textureSampleCompareLevel(depth_map, compare_sampler, uv, i32(face), z);
    }
    let p = uv * sm.map.x - 0.5;
    let b = vec2i(floor(p));
    let f = fract(p);
    let a = mix(lit_at(b, face, z), lit_at(b + vec2i(1, 0), face, z), f.x);
    let c = mix(lit_at(b + vec2i(0, 1), face, z), lit_at(b + vec2i(1, 1), face, z), f.x);
    return mix(a, c, f.y);
}

fn moment_texel(t: vec2i, face: u32) -> vec4f {
    let size = i32(sm.map.x);
    return textureLoad(moment_map, clamp(t, vec2i(0), vec2i(size - 1)), i32(face), 0);
}

// Bilinear moments at uv (the map is 32-bit float, filtered by hand).
fn moments_at(uv: vec2f, face: u32) -> vec4f {
    let p = uv * sm.map.x - 0.5;
    let b = vec2i(floor(p));
    let f = fract(p);
    let top = mix(moment_texel(b, face), moment_texel(b + vec2i(1, 0), face), f.x);
    let bottom = mix(moment_texel(b + vec2i(0, 1), face), moment_texel(b + vec2i(1, 1), face), f.x);
    return mix(top, bottom, f.y);
}

// Chebyshev's upper bound P(x ≥ t) ≤ σ² / (σ² + (t − μ)²), with light-bleeding
// reduction (linstep from `amount` to 1).
fn chebyshev(m: vec2f, t: f32, min_variance: f32) -> f32 {
    if t <= m.x {
        return 1.0;
    }
    let variance = max(m.y - m.x * m.x, min_variance);
    let d = t - m.x;
    let p = variance / (variance + d * d);
    let amount = sm.moments.x;
    return clamp((p - amount) / (1.0 - amount), 0.0, 1.0);
}

// Hamburger 4-moment shadow mapping (Peters & Klein 2015, algorithm 2).
fn msm_hamburger(moments: vec4f, z: f32) -> f32 {
    let b = mix(moments, vec4f(0.5), sm.moments.w);
    let l32_d22 = -b.x * b.y + b.z;
    let d22 = -b.x * b.x + b.y;
    let squared_depth_variance = -b.y * b.y + b.w;
    let d33_d22 = dot(vec2f(squared_depth_variance, -l32_d22), vec2f(d22, l32_d22));
    let inv_d22 = 1.0 / d22;
    let l32 = l32_d22 * inv_d22;
    var c = vec3f(1.0, z, z * z);
    c.y -= b.x;
    c.z -= b.y + l32 * c.y;
    c.y *= inv_d22;
    c.z *= d22 / d33_d22;
    c.y -= l32 * c.z;
    c.x -= dot(c.yz, b.xy);
    let p = c.y / c.z;
    let q = c.x / c.z;
    let r = sqrt(max(p * p * 0.25 - q, 0.0));
    let z1 = -p * 0.5 - r;
    let z2 = -p * 0.5 + r;
    var sw = vec4f(0.0);
    if z2 < z {
        sw = vec4f(z1, z, 1.0, 1.0);
    } else if z1 < z {
        sw = vec4f(z, z1, 0.0, 1.0);
    }
    let quotient = (sw.x * z2 - b.x * (sw.x + z2) + b.y) / ((z2 - sw.y) * (z - z1));
    return 1.0 - clamp(sw.z + sw.w * quotient, 0.0, 1.0);
}

// Visibility from filtered moments for receiver depth z (linear, [0, 1]).
fn moment_visibility(m: vec4f, z: f32) -> f32 {
    let cp = sm.moments.y;
    let cn = sm.moments.z;
    switch FILTER_KIND {
        case FILTER_VSM: {
            return chebyshev(m.xy, z, 1e-6);
        }
        case FILTER_ESM: {
            return clamp(m.x * exp(-cp * (z - 1.0)), 0.0, 1.0);
        }
        case FILTER_EVSM2: {
            let p = exp(cp * (z - 1.0));
            return chebyshev(m.xy, p, 1e-6 * p * p * cp * cp);
        }
        case FILTER_EVSM4: {
            let p = exp(cp * (z - 1.0));
            let n = -exp(-cn * z);
            return min(chebyshev(m.xy, p, 1e-6 * p * p * cp * cp), chebyshev(m.zw, n, 1e-6 * n * n * cn * cn));
        }
        default: {
            return msm_hamburger(m, z);
        }
    }
}

// Interleaved gradient noise (Jimenez 2014): a per-pixel rotation.
fn ign(p: vec2f) -> f32 {
    return fract(52.9829189 * fract(dot(p, vec2f(0.06711056, 0.00583715))));
}

// Vogel disk sample i of n, rotated by phi, radius ≤ 1.
fn vogel(i: u32, n: u32, phi: f32) -> vec2f {
    let r = sqrt((f32(i) + 0.5) / f32(n));
    let theta = f32(i) * 2.4 + phi;
    return r * vec2f(cos(theta), sin(theta));
}

fn pcf_disk(uv: vec2f, face: u32, z: f32, radius_texels: f32, n: u32, phi: f32) -> f32 {
    var sum = 0.0;
    for (var i = 0u; i < n; i++) {
        let t = uv + vogel(i, n, phi) * radius_texels * sm.map.y;
        sum += pcf2x2(t, face, tap_z(z, t));
    }
    return sum / f32(n);
}

fn pcf_grid(uv: vec2f, face: u32, z: f32, radius_texels: f32, k: u32) -> f32 {
    var sum = 0.0;
    for (var y = 0u; y < k; y++) {
        for (var x = 0u; x < k; x++) {
            let o = (vec2f(f32(x), f32(y)) + 0.5) / f32(k) * 2.0 - 1.0;
            let t = uv + o * radius_texels * sm.map.y;
            sum += pcf2x2(t, face, tap_z(z, t));
        }
    }
    return sum / f32(k * k);
}

// Half-width in texels of the penumbra that a blocker at linear depth db
// casts on a receiver at dr from an area light of radius sm.depth.z (world
// units; for directional lights the tangent of the angular radius): the
// segment from the receiver to the light's rim, seen from the light centre.
fn penumbra_texels(dr: f32, db: f32) -> f32 {
    if sm.map.w > 0.5 && !is_paraboloid() {
        return sm.depth.z * (dr - db) * (sm.depth.y - sm.depth.x) / sm.map.z;
    }
    return sm.depth.z * (dr - db) / (dr * max(db, 1e-4)) / sm.map.z;
}

// Mean linear depth of the blockers (stored < z) in a disk, and their count.
fn blockers(uv: vec2f, face: u32, z: f32, radius_texels: f32, n: u32, phi: f32) -> vec2f {
    var sum = 0.0;
    var count = 0.0;
    for (var i = 0u; i < n; i++) {
        let tap = uv + vogel(i, n, phi) * radius_texels * sm.map.y;
        let d = stored(vec2i(floor(tap * sm.map.x)), face);
        if d < tap_z(z, tap) {
            sum += linear_depth(d);
            count += 1.0;
        }
    }
    return vec2f(sum / max(count, 1.0), count);
}

@fragment
fn fs_lookup(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let g = textureLoad(gbuffer_position, vec2i(frag.xy), 0);
    let n = normalize(textureLoad(gbuffer_normal, vec2i(frag.xy), 0).xyz);
    if sm.cascade.x < 0.5 {
        let face = face_of(g.xyz);
        return vec4f(filtered(face, projected(face, g, n), frag.xy));
    }
    // Cascades: this pixel's, blended into the next one's over the band.
    // Both projections run in uniform control flow (their screen
    // derivatives); the next cascade is filtered only inside the band.
    let pick = cascade_of(g.xyz);
    let count = u32(sm.cascade.x);
    let face = min(pick.index, count - 1u);
    let next_face = min(pick.index + 1u, count - 1u);
    let here = projected(face, g, n);
    let next = projected(next_face, g, n);
    if pick.index >= count {
        return vec4f(1.0); // beyond the last cascade
    }
    var v = filtered(face, here, frag.xy);
    if pick.next_weight > 0.0 {
        v = mix(v, filtered(next_face, next, frag.xy), pick.next_weight);
    }
    return vec4f(v);
}

// The map uv of world point p in `face`.
fn map_uv(face: u32, p: vec3f) -> vec2f {
    let c = sm.faces[face] * vec4f(p, 1.0);
    let ndc = c.xy / select(c.w, 1e-6, abs(c.w) < 1e-6);
    return vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
}

// A warped map's world texel size at p, across the light: the larger of
// the texel's extents along two directions perpendicular to the light,
// from the uv change over a short step.
fn warped_texel_world(face: u32, p: vec3f) -> f32 {
    let l = normalize(sm.warp.xyz);
    var t = cross(l, vec3f(0.0, 1.0, 0.0));
    if length(t) < 1e-3 {
        t = cross(l, vec3f(1.0, 0.0, 0.0));
    }
    t = normalize(t);
    let b = cross(l, t);
    let step = 1e-3 * max(length(p - frame.camera_pos.xyz), 1e-3);
    let uv = map_uv(face, p);
    let along_t = length(map_uv(face, p + t * step) - uv);
    let along_b = length(map_uv(face, p + b * step) - uv);
    return step / max(min(along_t, along_b) * sm.map.x, 1e-9);
}

// A G-buffer point in one face of the map: its light-clip position, map uv
// and depth, the receiver plane's depth gradient there, and whether it is
// looked up at all (a receiver, in front of the light, inside the map).
struct Projected {
    clip: vec4f,
    uv: vec2f,
    z: f32,
    gradient: vec2f,
    inside: bool,
};

// Projects G-buffer point g (normal n) into `face`. Must run in uniform
// control flow (the receiver plane's derivatives).
fn projected(face: u32, g: vec4f, n: vec3f) -> Projected {
    // Normal offset: move the lookup point along the geometric normal by a
    // number of shadow-map texels (their world size grows with distance for
    // perspective maps, and with each cascade).
    var texel_world = sm.map.z;
    if is_warped() {
        texel_world = warped_texel_world(face, g.xyz);
    } else if sm.cascade.x > 0.5 {
        texel_world = sm.cascade_texel[face / 4u][face % 4u];
    } else if sm.map.w < 0.5 || is_paraboloid() {
        texel_world = sm.map.z * length(g.xyz - sm.light.xyz);
    }
    let p = g.xyz + n * sm.kernel.y * texel_world;
    var c = sm.faces[face] * vec4f(p, 1.0);
    if is_paraboloid() {
        c = paraboloid(vec4f(p, 1.0), face);
    }
    let ndc = c.xyz / select(c.w, 1e-6, abs(c.w) < 1e-6);
    let uv = vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let z = select(ndc.z, dot(sm.warp_depth, vec4f(p, 1.0)), is_warped());
    let gradient = receiver_plane(vec3f(uv, z));
    // Outside the map counts as lit.
    let inside = g.w >= 0.5 && c.w > 0.0 && all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0))
        && z <= 1.0 && z >= 0.0;
    return Projected(c, uv, z, gradient, inside);
}

// The filtered visibility of a projected point in `face`.
fn filtered(face: u32, pr: Projected, frag: vec2f) -> f32 {
    if !pr.inside {
        return 1.0;
    }
    rp_gradient = pr.gradient;
    rp_origin = pr.uv;
    let uv = pr.uv;
    let c = pr.clip;
    // With the receiver plane, a 2×2 comparison still sees texels up to one
    // texel away at a single depth: take off that slope (Isidoro's
    // fractional sampling error), capped.
    let z = pr.z - min(2.0 * dot(vec2f(sm.map.y), abs(rp_gradient)), 0.01);
    if FILTER_KIND >= FILTER_VSM {
        return moment_visibility(moments_at(uv, face), select(linear01(c), pr.z, is_warped()));
    }
    let count = max(TAPS, 1u);
    let radius = sm.kernel.x;
    let phi = ign(frag) * 6.2831853;
    var v = 1.0;
    switch FILTER_KIND {
        case FILTER_HARD: {
            let t = floor(uv * sm.map.x);
            v = lit_at(vec2i(t), face, tap_z(pr.z, (t + 0.5) * sm.map.y));
        }
        case FILTER_PCF2X2: {
            v = pcf2x2(uv, face, z);
        }
        case FILTER_GRID: {
            v = pcf_grid(uv, face, z, radius, count);
        }
        case FILTER_DISK: {
            v = pcf_disk(uv, face, z, radius, count * count, phi);
        }
        case FILTER_PCSS: {
            // PCSS (Fernando 2005): blocker search, then a penumbra
            // w = (d_receiver − d_blocker) / d_blocker · light size; from the
            // light's own area when it has one.
            let dr = linear_depth(z);
            let physical = sm.depth.z > 0.0;
            var search = sm.soft.w;
            if physical {
                search = clamp(penumbra_texels(dr, select(sm.depth.x, 0.0, sm.map.w > 0.5 && !is_paraboloid())), 1.0, 64.0);
            }
            let b = blockers(uv, face, z, search, 16u, phi);
            if b.y > 0.0 {
                var w = (dr - b.x) / max(b.x, 1e-4) * sm.soft.x;
                if physical {
                    w = penumbra_texels(dr, b.x);
                }
                v = pcf_disk(uv, face, z, clamp(w, 0.5, 64.0), count * count, phi);
            }
        }
        default: {
            // Variable-width PCF (002): radius ∝ |d_blocker − d_receiver|^exponent.
            let b = blockers(uv, face, z, sm.soft.w, 16u, phi);
            if b.y > 0.0 {
                let w = sm.soft.y * pow(abs(linear_depth(z) - b.x), sm.soft.z);
                v = pcf_disk(uv, face, z, clamp(w, 0.5, 64.0), count * count, phi);
            }
        }
    }
    return v;
}

// Debug view: face 0 of the map as grey (near dark, far light), in linear depth.
@fragment
fn fs_debug_map(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let uv = frag.xy / 256.0;
    let t = vec2i(uv * sm.map.x);
    var d: f32;
    if FILTER_KIND >= FILTER_VSM {
        d = moment_texel(t, 0u).x;
        if FILTER_KIND == FILTER_ESM || FILTER_KIND == FILTER_EVSM2 || FILTER_KIND == FILTER_EVSM4 {
            d = 1.0 + log(max(d, 1e-30)) / sm.moments.y;
        }
    } else {
        let z = stored(t, 0u);
        d = (linear_depth(z) - sm.depth.x) / (sm.depth.y - sm.depth.x);
        if sm.map.w > 0.5 && !is_paraboloid() {
            d = z;
        }
        if is_paraboloid() {
            d = z;
        }
    }
    return vec4f(vec3f(clamp(d, 0.0, 1.0)), 1.0);
}

struct DebugFrame {
    // The map's stored depth where each pixel projects (grey, tinted by
    // cascade: red, green, blue, yellow, …; dark red outside the map).
    @location(0) projection: vec4f,
    // Shadow-map texels per screen pixel (SEEDS §5's aliasing measure
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
    let g = textureLoad(gbuffer_position, vec2i(frag.xy), 0);
    let face = face_of(g.xyz);
    var c = sm.faces[face] * vec4f(g.xyz, 1.0);
    if is_paraboloid() {
        c = paraboloid(vec4f(g.xyz, 1.0), face);
    }
    let w = select(c.w, 1e-6, abs(c.w) < 1e-6);
    let ndc = c.xyz / w;
    let uv = vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    // Derivatives first, in uniform control flow.
    let texel = uv * sm.map.x;
    let footprint = max(length(dpdx(texel)), length(dpdy(texel)));
    let pixels_per_texel = texel_footprint(dpdx(texel), dpdy(texel));
    var o: DebugFrame;
    let inside = g.w > 0.5 && c.w > 0.0 && all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0));
    var d = stored(vec2i(floor(texel)), face);
    if sm.map.w < 0.5 {
        d = (linear_depth(d) - sm.depth.x) / (sm.depth.y - sm.depth.x);
    }
    var tint = vec3f(1.0);
    if sm.cascade.x > 0.5 {
        tint = cascade_tint(face);
    }
    o.projection = select(vec4f(0.5, 0.0, 0.0, 1.0), vec4f(tint * (0.35 + 0.65 * d), 1.0), inside);
    let t = clamp(log2(max(footprint, 1e-6)) / 2.0, -1.0, 1.0);
    let colour = select(mix(vec3f(0.0, 1.0, 0.0), vec3f(1.0, 0.0, 0.0), t), mix(vec3f(0.0, 1.0, 0.0), vec3f(0.0, 0.2, 1.0), -t), t < 0.0);
    o.texels = select(vec4f(0.0, 0.0, 0.0, 1.0), vec4f(colour, 1.0), inside);
    o.lookup = select(vec2f(0.0), vec2f(pixels_per_texel, f32(face + 1u)), inside);
    return o;
}
