// The depth pass from the light: depth (linear for warped faces), the
// moments of the moment filters and their blur, the 8-bit map.

// Cut-out casters: every fragment entry first drops the caster's holes.
override CUTOUT: bool = false;
// Translucent casters solid where their opacity reaches a hash of the map
// texel, the fragment's depth and the object (hashed alpha testing, Wyman &
// McGuire 2017): a screen door in the map whose density is the opacity,
// which the filter's taps average into fractional visibility; stacked
// casters, the two sides of one glass among them, get independent doors, so
// their transmittances multiply. Otherwise they are solid where it reaches
// ½.
override HASHED: bool = false;

// A uniform value in [0, 1) per map texel, depth and object (two rounds of
// PCG, Jarzynski & Olano 2020). The depth's last 8 bits are dropped, so the
// coincident faces a double-sided material draws, whose depths may differ
// by the rounding of their interpolation, share the door.
fn texel_hash(texel: vec3f, object: u32) -> f32 {
    var v = u32(texel.x) * 1664525u + u32(texel.y) * 22695477u + object * 2654435761u
        + (bitcast<u32>(texel.z) >> 8u) * 3266489917u + 1013904223u;
    v = v * 747796405u + 2891336453u;
    v = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    v = v * 747796405u + 2891336453u;
    let w = ((v >> ((v >> 28u) + 4u)) ^ v) * 277803737u;
    return f32((w >> 22u) ^ w) / 4294967296.0;
}

// Drops the fragment where a cut-out caster has a hole, its opacity map read
// at the mip level of the light's texel footprint on it (its shorter axis).
fn cut_out(i: DepthOut) {
    if CUTOUT {
        let lod = opacity_lod_across(i.object, dpdx(i.uv), dpdy(i.uv));
        let blend_cutoff = select(0.5, texel_hash(i.clip.xyz, i.object), HASHED);
        if !is_solid_at(i.object, i.uv, lod, blend_cutoff) {
            discard;
        }
    }
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
    } else if VIRTUAL {
        // A page's matrix takes points relative to the camera (precision).
        o.clip = sm.faces[sm.face.x] * vec4f(world.xyz - frame.camera_pos.xyz, 1.0);
    } else {
        o.clip = sm.faces[sm.face.x] * world;
    }
    o.linear = select(linear01(o.clip), dot(sm.warp_depth, world), is_warped());
    o.part = part_id(v.object, v.part);
    o.uv = v.uv;
    o.object = v.object;
    return o;
}

// `part_ids`: the depth, and the convex part it came from.
@fragment
fn fs_depth_part(i: DepthOut) -> @location(0) u32 {
    cut_out(i);
    return i.part;
}

// Warped faces: the linear depth with the depth pass's bias applied here,
// as polygon offset would (constant + slope factor × the larger screen
// slope of the depth).
@fragment
fn fs_depth_linear(i: DepthOut) -> @builtin(frag_depth) f32 {
    cut_out(i);
    let slope = max(abs(dpdx(i.linear)), abs(dpdy(i.linear)));
    return clamp(i.linear + sm.depth.w + sm.kernel.z * slope, 0.0, 1.0);
}

// A plain depth pass of cut-out casters.
@fragment
fn fs_depth_cutout(i: DepthOut) {
    cut_out(i);
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
    cut_out(i);
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
            // Log space (Lauritzen 2007): the depth itself; the blur and
            // the lookup filter exp(c·z) without ever forming it.
            return vec4f(z, 0.0, 0.0, 0.0);
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
    cut_out(i);
    if i.hemisphere < 0.0 {
        discard;
    }
    return moments_of(moment_depth_of(i.linear));
}

// The moments k texels from frag along the blur's axis (clamped to the map).
fn blur_tap(frag: vec2f, k: i32) -> vec4f {
    let axis = select(vec2i(1, 0), vec2i(0, 1), sm.face.y == 1u);
    let t = clamp(vec2i(frag) + axis * k, vec2i(0), vec2i(i32(sm.map.x) - 1));
    return textureLoad(moment_map, t, i32(sm.face.x), 0);
}

// Separable box blur of one moment layer along one axis.
@fragment
fn fs_blur(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let r = i32(sm.face.z);
    var sum = vec4f(0.0);
    if FILTER_KIND == FILTER_ESM {
        // log(mean exp(c·z)) / c, taken relative to the largest depth so
        // that no term overflows however large c is.
        let c = sm.moments.y;
        var top = 0.0;
        for (var k = -r; k <= r; k++) {
            top = max(top, blur_tap(frag.xy, k).x);
        }
        for (var k = -r; k <= r; k++) {
            sum.x += exp(c * (blur_tap(frag.xy, k).x - top));
        }
        return vec4f(top + log(sum.x / f32(2 * r + 1)) / c, 0.0, 0.0, 0.0);
    }
    for (var k = -r; k <= r; k++) {
        sum += blur_tap(frag.xy, k);
    }
    return sum / f32(2 * r + 1);
}

// The 8-bit preset stores the depth in an R8 colour target.
@fragment
fn fs_depth_byte(i: DepthOut) -> @location(0) vec4f {
    cut_out(i);
    if i.hemisphere < 0.0 {
        discard;
    }
    return vec4f(select(i.clip.z, i.linear, is_warped()));
}

// Virtual maps: a page's depth cleared to the far plane before its casters
// are drawn into it (the rest of the pool keeps its pages).
@fragment
fn fs_clear_page() -> @builtin(frag_depth) f32 {
    return 1.0;
}
