// The lookup's filters over one map face: nearest texel, hardware 2×2
// comparison, N×N grid and rotated Vogel disk of 2×2 taps, the blocker
// search of PCSS and variable-width PCF, and the moment filters.

// Stored depth at a texel (nearest), from the depth map or the 8-bit map.
fn stored(texel: vec2i, face: u32) -> f32 {
    if VIRTUAL {
        return atlas_stored(filtered_texel(texel));
    }
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
// The depth a tap's compared depth sinks below the plane per unit of uv
// from rp_origin (`crease_tolerance`).
var<private> rp_crease: f32;
// The receiver's compared depth at rp_origin.
var<private> rp_depth: f32;

// d(depth)/d(uv) of a plane from its steps dx, dy of (u, v, depth) per
// screen pixel: solve [du/dx dv/dx; du/dy dv/dy] · g = [dz/dx; dz/dy];
// 0 when degenerate (silhouettes, face seams), clamped to ±limit so that a
// step across an edge cannot swing a tap far.
fn solve_plane(dx: vec3f, dy: vec3f, limit: f32) -> vec2f {
    let det = dx.x * dy.y - dx.y * dy.x;
    let g = vec2f(dy.y * dx.z - dx.y * dy.z, dx.x * dy.z - dy.x * dx.z) / det;
    if abs(det) < 1e-20 || any(g != g) {
        return vec2f(0.0);
    }
    return clamp(g, vec2f(-limit), vec2f(limit));
}

// A unit tangent of the surface with unit normal `normal`.
fn surface_tangent(normal: vec3f) -> vec3f {
    let helper = select(vec3f(1.0, 0.0, 0.0), vec3f(0.0, 1.0, 0.0), abs(normal.x) > 0.7);
    return normalize(cross(normal, helper));
}

// The virtual map's receiver plane at lookup point `q` in level `l` of
// world point p (at `lookup` once moved along its normal offset; the
// level's texels `texel_world` wide there), from the level points of two
// steps of the kernel's reach along the surface of geometric normal
// `normal`, as the other maps take it (`receiver_plane_at`): screen
// derivatives broke the plane wherever a pixel quad straddles a
// silhouette. 0 when off or facing away from the light, as there.
fn receiver_plane(l: VirtualLevel, q: VirtualPoint, p: vec3f, lookup: vec3f, texel_world: f32, normal: vec3f) -> vec2f {
    if !RECEIVER_PLANE || !faces_light(p, normal) {
        return vec2f(0.0);
    }
    let step = texel_world * max(kernel_reach(), 1.0);
    // Steps from the lookup point itself, not moved again: the normal
    // offset changes along the surface (with the distance to the light,
    // and as sinⁿθ), and tilted the plane by its change (a floor a point
    // light grazes came out speckled with partial shadow).
    let t = surface_tangent(normal);
    let at = vec3f(q.uv, q.z);
    let qx = virtual_point(l, lookup + t * step, vec3f(0.0));
    let qy = virtual_point(l, lookup + cross(normal, t) * step, vec3f(0.0));
    return solve_plane(vec3f(qx.uv, qx.z) - at, vec3f(qy.uv, qy.z) - at, 4.0);
}

// The receiver depth to compare at a tap's uv: along its plane, less the
// crease tolerance.
fn tap_z(z: f32, uv: vec2f) -> f32 {
    return z + dot(uv - rp_origin, rp_gradient) - rp_crease * length(uv - rp_origin);
}

// `part_ids`: the receiver's convex part where it faces the light, else
// 0 (its own part's texels cannot shadow it; `receiver_part_of`).
var<private> receiver_part: u32;

// Whether the receiver has a part whose texels it ignores.
fn has_own_part() -> bool {
    return PART_IDS && receiver_part != 0u;
}

// Whether the texel's depth came from the receiver's own convex part.
fn own_part(texel: vec2i, face: u32) -> bool {
    if !has_own_part() {
        return false;
    }
    let t = clamp(texel, vec2i(0), vec2i(i32(sm.map.x) - 1));
    return textureLoad(part_map, t, i32(face), 0).r == receiver_part;
}

// 1 where the receiver depth z is not behind the stored depth, or the
// texel is the receiver's own part's.
fn lit_at(texel: vec2i, face: u32, z: f32) -> f32 {
    return select(0.0, 1.0, z <= stored(texel, face) || own_part(texel, face));
}

// Bilinear (hardware-style 2×2) comparison at uv.
fn pcf2x2(uv: vec2f, face: u32, z: f32) -> f32 {
    if RECEIVER_PLANE && any(rp_gradient != vec2f(0.0)) {
        return bilinear_compare(uv, face);
    }
    if !BYTE_MAP && !VIRTUAL {
        // A receiver with its own part gathers the four comparisons and
        // parts at once (a sampled comparison first, then the gathers where
        // it finds shadow, ran all three wherever a SIMD group's taps see
        // their own unbiased surface: 2.9× the lookup time of part_ids=false
        // on columns/sun, NVIDIA H100).
        if has_own_part() {
            return pcf2x2_parts(uv, face, z);
        }
        return textureSampleCompareLevel(depth_map, compare_sampler, uv, i32(face), z);
    }
    if VIRTUAL {
        return virtual_pcf2x2(uv, z);
    }
    return bilinear_compare(uv, face);
}

// `pcf2x2` ignoring the receiver's own part: the four comparisons and
// parts gathered, weighted as the bilinear filter weighs them.
fn pcf2x2_parts(uv: vec2f, face: u32, z: f32) -> f32 {
    let lit = textureGatherCompare(depth_map, compare_sampler, uv, i32(face), z);
    let parts = textureGather(0, part_map, part_sampler, uv, i32(face));
    return bilinear_weighted(max(lit, select(vec4f(0.0), vec4f(1.0), parts == vec4u(receiver_part))), uv);
}

// The 2×2 texels around uv, in gather order — (0, 1), (1, 1), (1, 0),
// (0, 0) — weighted as the bilinear filter weighs them.
fn bilinear_weighted(v: vec4f, uv: vec2f) -> f32 {
    let f = fract(uv * sm.map.x - 0.5);
    return mix(mix(v.w, v.z, f.x), mix(v.x, v.y, f.x), f.y);
}

// A 2×2 comparison at uv filtered by hand from four texel loads, each
// texel compared against the receiver's depth at its centre (its plane's,
// with the receiver plane): the depth a tap at uv compares, `tap_z`.
fn bilinear_compare(uv: vec2f, face: u32) -> f32 {
    let b = vec2i(floor(uv * sm.map.x - 0.5));
    return bilinear_weighted(vec4f(lit_at_plane(b + vec2i(0, 1), face), lit_at_plane(b + vec2i(1, 1), face),
        lit_at_plane(b + vec2i(1, 0), face), lit_at_plane(b, face)), uv);
}

// `lit_at` against the receiver's depth carried along its plane from
// rp_origin to the texel's centre: the same depth for every tap that reads
// the texel (the edge mask compares the texel against it too).
fn lit_at_plane(texel: vec2i, face: u32) -> f32 {
    let centre = (vec2f(texel) + 0.5) * sm.map.y;
    return lit_at(texel, face, tap_z(rp_depth, centre));
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
            // m.x: log(mean exp(c·z_occluder)) / c (log space).
            return clamp(exp(cp * (m.x - z)), 0.0, 1.0);
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
    return sum / f32(max(n, 1u));
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
    return sum / f32(max(k * k, 1u));
}

// Half-width in texels of the penumbra that a blocker at linear depth db
// casts on a receiver at dr from an area light of radius sm.depth.z (world
// units; for directional lights the tangent of the angular radius): the
// segment from the receiver to the light's rim, seen from the light centre.
fn penumbra_texels(dr: f32, db: f32) -> f32 {
    let texel = select(sm.map.z, virtual_texel_world, VIRTUAL);
    if is_orthographic() {
        return sm.depth.z * (dr - db) * (sm.depth.y - sm.depth.x) / texel;
    }
    return sm.depth.z * (dr - db) / (dr * max(db, 1e-4)) / texel;
}

// Taps of the blocker search (PCSS, variable-width PCF).
const BLOCKER_SEARCHES: u32 = 16u;

// Mean linear depth of the blockers (stored < z) in a disk, and their count.
fn blockers(uv: vec2f, face: u32, z: f32, radius_texels: f32, n: u32, phi: f32) -> vec2f {
    var sum = 0.0;
    var count = 0.0;
    for (var i = 0u; i < n; i++) {
        let tap = uv + vogel(i, n, phi) * radius_texels * sm.map.y;
        let texel = vec2i(floor(tap * sm.map.x));
        let d = stored(texel, face);
        if d < tap_z(z, tap) && !own_part(texel, face) {
            sum += linear_depth(d);
            count += 1.0;
        }
    }
    return vec2f(sum / max(count, 1.0), count);
}

// Edge mask: the visibility every tap of a kernel reaching `reach` texels
// from uv agrees on — 1 when the receiver's depth z (along its plane of
// `slope`, depth per texel, with receiver_plane) lies in front of every
// stored depth under the kernel, 0 when behind every one — or −1 (a shadow
// edge: run the kernel). The chain first (`chain_class`, four loads); where
// it finds an edge and the kernel is narrow, the texels themselves
// (`footprint_class`).
fn edge_class(uv: vec2f, face: u32, z: f32, slope: vec2f, reach: f32) -> f32 {
    let known = class_at_depth(uv, face, z, slope, reach);
    // The crease tolerance only lowers the depth a tap compares (`tap_z`),
    // by at most its slope over the farthest texel centre a tap reads: a
    // pixel lit along the plane stays lit, but one shadowed along it must
    // be shadowed at that much less.
    var shadowed_below = true;
    for (var recheck = known == 0.0 && rp_crease > 0.0; recheck; recheck = false) {
        let low = z - rp_crease * (reach + 1.5) * sm.map.y;
        shadowed_below = class_at_depth(uv, face, low, slope, reach) == 0.0;
    }
    return select(-1.0, known, shadowed_below);
}

// `edge_class` at one compared depth z (along the plane).
fn class_at_depth(uv: vec2f, face: u32, z: f32, slope: vec2f, reach: f32) -> f32 {
    var known = chain_class(uv, face, z, slope, reach);
    // A loop, not a branch (see `filtered`).
    for (var refine = known < 0.0 && reach <= FOOTPRINT_REACH; refine; refine = false) {
        known = footprint_class(uv, face, z, slope, reach);
    }
    return known;
}

// `edge_class` from the chain: reads 2×2 texels of the chain level whose
// cells (2^(CHAIN_BLOCK_LOG2 + level) map texels each) cover the kernel's
// texel span, at most floor(2·reach) + 2 texels wherever uv lies; so the
// level is the same for every pixel (a uniform mip level keeps the four
// loads cheap). Float arithmetic throughout: llvmpipe splits integer
// division into lanes.
fn chain_class(uv: vec2f, face: u32, z: f32, slope: vec2f, reach: f32) -> f32 {
    let level = max(ceil(log2(floor(2.0 * reach) + 2.0)) - f32(CHAIN_BLOCK_LOG2), 0.0);
    if u32(level) >= textureNumLevels(edge_bounds) {
        return -1.0;
    }
    let top = vec2f(sm.map.x - 1.0);
    let p = uv * sm.map.x;
    let cover = exp2(f32(CHAIN_BLOCK_LOG2) + level);
    // The kernel's first and last texel, their cells, and the box's texel
    // centres inside each of the two cells a side: the middle and half extent.
    let a = clamp(floor(p - reach), vec2f(0.0), top);
    let b = clamp(floor(p + reach), vec2f(0.0), top);
    let ka = floor(a / cover);
    let kb = floor(b / cover);
    let split_a = min(b, ka * cover + cover - 1.0);
    let split_b = max(a, kb * cover);
    let middle_a = (a + split_a + 1.0) * 0.5;
    let middle_b = (split_b + b + 1.0) * 0.5;
    let half_a = (split_a - a) * 0.5;
    let half_b = (b - split_b) * 0.5;
    let e = EdgeQuery(face, i32(level), cover, z, slope, p);
    let m = range_union(
        range_union(cell_margins(e, ka, middle_a, half_a),
            cell_margins(e, vec2f(kb.x, ka.y), vec2f(middle_b.x, middle_a.y), vec2f(half_b.x, half_a.y))),
        range_union(cell_margins(e, vec2f(ka.x, kb.y), vec2f(middle_a.x, middle_b.y), vec2f(half_a.x, half_b.y)),
            cell_margins(e, kb, middle_b, half_b)));
    if m.x >= 0.0 {
        return 1.0;
    }
    if m.y < 0.0 {
        return 0.0;
    }
    return -1.0;
}

// How far the receiver's plane (`slope`, depth per texel) moves between a
// tap and a texel it reads, at most a texel away on each axis.
fn plane_sway(slope: vec2f) -> f32 {
    return abs(slope.x) + abs(slope.y);
}

// The widest kernel reach (texels) that `edge_class` reads texel by texel
// where the chain finds an edge: at most 6 texels a side, 3×3 gathers (a
// grid of radius 1.5 reaches 1.5 to 2). The chain's cells, 8 texels or
// more, call a pixel an edge wherever any depth step lies within them, far
// more pixels than the kernel actually filters to neither 0 nor 1.
const FOOTPRINT_REACH: f32 = 2.5;

// `edge_class` from the texels themselves: every texel the kernel can read
// (from floor(p − reach) to floor(p + reach), clamped as the taps are),
// gathered 2×2 at a time, compared against the receiver's plane at its
// centre within the one-texel sway of a tap's own plane point; with part
// ids, a texel of the receiver's own part is lit. Gathers past the span
// (an odd count) read texels the kernel does not, which can only call a
// pixel an edge.
fn footprint_class(uv: vec2f, face: u32, z: f32, slope: vec2f, reach: f32) -> f32 {
    let p = uv * sm.map.x;
    let top = vec2f(sm.map.x - 1.0);
    let a = clamp(floor(p - reach), vec2f(0.0), top);
    let b = clamp(floor(p + reach), vec2f(0.0), top);
    let gathers = vec2u(floor((b - a) * 0.5)) + 1u;
    let sway = plane_sway(slope) + select(0.0, 1e-6, any(slope != vec2f(0.0)));
    var lo = 3.4e38;
    var hi = -3.4e38;
    for (var j = 0u; j < gathers.y; j++) {
        for (var i = 0u; i < gathers.x; i++) {
            // Texel (0, 0) of this 2×2 and the gather's shared corner.
            let t = a + 2.0 * vec2f(f32(i), f32(j));
            let corner = (t + 1.0) * sm.map.y;
            var d: vec4f;
            if BYTE_MAP {
                d = textureGather(0, byte_map, part_sampler, corner, i32(face));
            } else {
                d = textureGather(depth_map, part_sampler, corner, i32(face));
            }
            // Gather order: (0, 1), (1, 1), (1, 0), (0, 0); the plane at
            // each texel's centre.
            let c = z + dot(slope, t + 0.5 - p);
            var margin = d - (c + vec4f(slope.y, slope.x + slope.y, slope.x, 0.0));
            if has_own_part() {
                let parts = textureGather(0, part_map, part_sampler, corner, i32(face));
                margin = select(margin, vec4f(3.4e38), parts == vec4u(receiver_part));
            }
            lo = min(lo, min(min(margin.x, margin.y), min(margin.z, margin.w)));
            hi = max(hi, max(max(margin.x, margin.y), max(margin.z, margin.w)));
        }
    }
    if lo - sway >= 0.0 {
        return 1.0;
    }
    if hi + sway < 0.0 {
        return 0.0;
    }
    return -1.0;
}

// What `cell_margins` compares: the chain level's face, level and cell side
// in texels, and the receiver's depth, plane slope (depth per texel) and
// map point (texels).
struct EdgeQuery {
    face: u32,
    level: i32,
    cover: f32,
    z: f32,
    slope: vec2f,
    p: vec2f,
};

fn range_union(a: vec2f, b: vec2f) -> vec2f {
    return vec2f(min(a.x, b.x), max(a.y, b.y));
}

// The least and greatest of (stored − compared depth) over the kernel's
// texel centres inside chain cell k, which lie `extent` texels about `at`.
// The cell's depths lie between two planes (edge_mask.wgsl); a tap
// compares the texels within a texel of it against the receiver's plane
// at each texel's centre (the virtual map: at the tap), within the slope's
// one-texel sway. With part ids, the part chain first: a cell of the
// receiver's own part is lit, a cell of several parts an edge. Rounding: a plane that is
// not flat is widened by 1e-6 (depths lie in [0, 1]); a flat one stays exact.
fn cell_margins(e: EdgeQuery, k: vec2f, at: vec2f, extent: vec2f) -> vec2f {
    if has_own_part() {
        // A cell of the receiver's own part is lit whatever it stores; one
        // of several parts may hold some of it: an edge.
        let part = textureLoad(edge_parts, vec2i(k), i32(e.face), e.level).r;
        if part == receiver_part {
            return vec2f(3.4e38);
        }
        if part == MIXED_PART {
            return vec2f(-3.4e38, 3.4e38);
        }
    }
    let cell = textureLoad(edge_bounds, vec2i(k), i32(e.face), e.level);
    let cell_slope = cell.zw / e.cover;
    let offset = dot(cell_slope, at - (k + 0.5) * e.cover) - dot(e.slope, at - e.p) - e.z;
    let sway = plane_sway(e.slope);
    let spread = dot(abs(cell_slope - e.slope), extent) + sway
        + select(0.0, 1e-6, any(cell.zw != vec2f(0.0)) || sway > 0.0);
    return vec2f(cell.x + offset - spread, cell.y + offset + spread);
}

// How far in texels from its centre a pixel's kernel reads
// (`ShadowMapConfig::kernel_reach`).
fn kernel_reach() -> f32 {
    return sm.map.w;
}
