// The screen-space lookup: each G-buffer point's face or cascade, its
// projection into the map (with normal offset), and the filtered,
// cascade-blended visibility written to the mask.

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
    if sm.cascade.w > 0.5 {
        return cascade_by_map(p);
    }
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

// How far p lies towards the border of cascade i's map: the larger |ndc|
// of x and y over the part that holds a lookup (the kernel's reach and a
// texel for the normal offset inside the border; 1 on that line), or
// above 1 where p is outside that part, behind a warped cascade's
// projection centre, or outside an unwarped map's depth range.
fn border_reach(i: u32, p: vec3f) -> f32 {
    let c = sm.faces[i] * vec4f(p, 1.0);
    let ndc = c.xyz / select(c.w, 1e-6, abs(c.w) < 1e-6);
    let held = 1.0 - 2.0 * (sm.map.w + 1.0) / sm.map.x;
    let deep = !is_warped() && (ndc.z < 0.0 || ndc.z > 1.0);
    let outside = select(0.0, 2.0, deep || c.w <= 0.0);
    return max(max(abs(ndc.x), abs(ndc.y)) / held, outside);
}

// select=map: the finest cascade whose map holds p, and the weight of the
// next one over the outer `blend` fraction of that map (where the next
// one holds p too).
fn cascade_by_map(p: vec3f) -> CascadePick {
    let count = u32(sm.cascade.x);
    var i = 0u;
    var reach = 2.0;
    loop {
        if i >= count {
            break;
        }
        reach = border_reach(i, p);
        if reach < 1.0 {
            break;
        }
        i++;
    }
    var pick = CascadePick(i, 0.0);
    let blend = sm.cascade.y;
    if i + 1u < count && blend > 0.0 && border_reach(i + 1u, p) < 1.0 {
        pick.next_weight = clamp((reach - (1.0 - blend)) / blend, 0.0, 1.0);
    }
    return pick;
}

// Face of a point light's six 90° frusta: the major axis of p − light.
fn face_of(p: vec3f) -> u32 {
    if CASCADED {
        return min(cascade_of(p).index, u32(sm.cascade.x) - 1u);
    }
    if is_paraboloid() {
        return select(1u, 0u, (sm.faces[0] * vec4f(p, 1.0)).z <= 0.0);
    }
    if PROJECTION != PROJECTION_CUBE {
        return 0u;
    }
    return cube_face(p - sm.light.xyz);
}

fn linear_depth(z: f32) -> f32 {
    if is_paraboloid() {
        return sm.depth.x + z * (sm.depth.y - sm.depth.x);
    }
    if is_orthographic() {
        return z;
    }
    let n = sm.depth.x;
    let f = sm.depth.y;
    return n * f / (f - z * (f - n));
}

// The world steps over the receiver's plane from this pixel's camera ray to
// its right and lower neighbours' (`set_pixel_steps`).
var<private> pixel_step_x: vec3f;
var<private> pixel_step_y: vec3f;

fn set_pixel_steps(frag: vec2f, g: vec3f, normal: vec3f) {
    pixel_step_x = camera_ray_on_plane(frag + vec2f(1.0, 0.0), g, normal) - g;
    pixel_step_y = camera_ray_on_plane(frag + vec2f(0.0, 1.0), g, normal) - g;
}

// The smaller singular value of the map's Jacobian over the screen, whose
// columns are the uv steps jx, jy of one pixel along x and y: the fewest
// texels a pixel step crosses in any direction (0 where degenerate).
fn texels_per_pixel(jx: vec2f, jy: vec2f) -> f32 {
    let a = jx * sm.map.x;
    let b = jy * sm.map.x;
    let t = dot(a, a) + dot(b, b);
    let d = abs(a.x * b.y - a.y * b.x);
    let largest = sqrt(0.5 * (t + sqrt(max(t * t - 4.0 * d * d, 0.0))));
    return select(0.0, d / largest, largest > 0.0);
}

// Whether the filter's ramp is steepened (`edge_ramp_pixels`): sm.screen.y,
// the ramp's reach in texels (`ShadowMapConfig::ramp_reach`), is 0 where
// there is nothing to steepen (a penumbra, or `edge_ramp_pixels` = 0); the
// hard filter, which has no ramp, is left out as a constant of the
// pipeline, so it never finds the pixel's footprint in the map. Callers run
// it as a one-trip loop, not a branch (see `filtered`).
fn steepens_ramps() -> bool {
    return FILTER_KIND != FILTER_HARD && sm.screen.y > 0.0;
}

// `edge_ramp_pixels`: visibility v of a kernel whose ramp spans 2·reach
// texels (sm.screen.y), steepened about ½ where those texels span more
// pixels than that on screen (magnified texels); ½ itself stays, so no
// pixel changes side.
fn sharpened(v: f32, texels_per_pixel: f32) -> f32 {
    if !steepens_ramps() || !(texels_per_pixel > 0.0) {
        return v;
    }
    let ramp_pixels = 2.0 * sm.screen.y / texels_per_pixel;
    let k = max(ramp_pixels / sm.screen.x, 1.0);
    return clamp(0.5 + (v - 0.5) * k, 0.0, 1.0);
}

@fragment
fn fs_lookup(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let g = textureLoad(gbuffer_position, vec2i(frag.xy), 0);
    let normal = normalize(textureLoad(gbuffer_normal, vec2i(frag.xy), 0).xyz);
    for (var steepened = steepens_ramps(); steepened; steepened = false) {
        set_pixel_steps(frag.xy, g.xyz, normal);
    }
    receiver_part = receiver_part_of(vec2i(frag.xy), g.xyz, normal);
    let n = offset_direction(g, normal);
    if VIRTUAL {
        return vec4f(virtual_visibility(frag.xy, g, n, normal));
    }
    if !CASCADED {
        let face = face_of(g.xyz);
        return vec4f(filtered(face, projected(face, g, n, normal), frag.xy));
    }
    // Cascades: this pixel's, blended into the next one's over the band
    // (where the next cascade exists: `cascade_of`).
    let pick = cascade_of(g.xyz);
    if pick.index >= u32(sm.cascade.x) {
        return vec4f(1.0); // beyond the last cascade
    }
    var v = filtered(pick.index, projected(pick.index, g, n, normal), frag.xy);
    // A loop, not a branch: llvmpipe runs both sides of a branch under a
    // lane mask but leaves a loop as soon as no lane is still in it.
    for (var in_band = pick.next_weight > 0.0; in_band; in_band = false) {
        let next = pick.index + 1u;
        v = mix(v, filtered(next, projected(next, g, n, normal), frag.xy), pick.next_weight);
    }
    return vec4f(v);
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
    let uv = map_point(face, p).xy;
    let along_t = length(map_point(face, p + t * step).xy - uv);
    let along_b = length(map_point(face, p + b * step).xy - uv);
    return step / max(min(along_t, along_b) * sm.map.x, 1e-9);
}

// The direction the normal offset moves G-buffer point g (w: object index
// + 1) along, its length the share of the offset it takes: its geometric
// normal n, CONCAVE_SOLID_OFFSET of it on a concave solid whose front
// faces are stored, or none where its own lit surface is not in the map:
// on a solid when `sm.light.w` is 1 (`cull=solids`: back faces alone), on
// a convex one when it is 2 (concave solids also store their front faces,
// pushed back by `solid_front_bias` times a capped bias, which at grazing
// light still meets the lit face it came from), and on a receiver with a
// convex part (it ignores its own texels).
fn offset_direction(g: vec4f, n: vec3f) -> vec3f {
    var solid = SOLID_NONE;
    if g.w >= 0.5 {
        solid = objects[u32(g.w) - 1u].info.w;
    }
    let own_surface_stored = solid == SOLID_NONE || (solid == SOLID_CONCAVE && sm.light.w > 1.5);
    if receiver_part != 0u || (sm.light.w > 0.5 && !own_surface_stored) {
        return vec3f(0.0);
    }
    return n * select(1.0, CONCAVE_SOLID_OFFSET, solid == SOLID_CONCAVE && sm.light.w > 0.5);
}

// The share of the normal offset a concave solid's receivers take where
// its front faces are stored: they lie behind a bias `solid_front_bias`
// times an open caster's, so less of the offset clears them, and more
// moves the edges of the shadows it casts on itself.
const CONCAVE_SOLID_OFFSET: f32 = 0.5;

// The unit direction from world point p towards the light.
fn to_light(p: vec3f) -> vec3f {
    return select(normalize(sm.light.xyz - p), -normalize(sm.warp.xyz), is_orthographic());
}

// Whether a surface at p with unit normal `normal` faces the light. Not
// `dot ≤ 0` negated: at the light's own position the direction is NaN,
// which faces nothing.
fn faces_light(p: vec3f, normal: vec3f) -> bool {
    return dot(normal, to_light(p)) > 0.0;
}

// `part_ids`: the convex part of the G-buffer's pixel where its geometric
// normal faces the light (a convex part cannot shadow that side of
// itself), else 0.
fn receiver_part_of(pixel: vec2i, g: vec3f, normal: vec3f) -> u32 {
    if !PART_IDS || !faces_light(g, normal) {
        return 0u;
    }
    return textureLoad(gbuffer_part, pixel, 0).r;
}

// G-buffer point g moved along `offset_direction` n by |n| × `sm.kernel.y`
// texels of world size `texel_world`, × sinⁿθ between normal and light
// for n = `sm.kernel.w` (`normal_offset_power`: full at grazing light, none
// facing it).
fn offset_point(g: vec3f, n: vec3f, texel_world: f32) -> vec3f {
    let cos_theta = clamp(dot(n, to_light(g)) / max(length(n), 1e-12), 0.0, 1.0);
    // pow(0, 0) is undefined in WGSL: power 0 is the whole offset.
    let sin_power = select(pow(max(1.0 - cos_theta * cos_theta, 1e-12), 0.5 * sm.kernel.w), 1.0, sm.kernel.w == 0.0);
    return g + n * (sm.kernel.y * texel_world * sin_power);
}

// A G-buffer point in one face of the map: its light-clip position, map uv
// and depth, the receiver plane's depth gradient there, and whether it is
// looked up at all (a receiver, in front of the light, inside the map).
struct Projected {
    clip: vec4f,
    uv: vec2f,
    z: f32,
    gradient: vec2f,
    crease: f32,
    // The fewest map texels one pixel step crosses, in any direction
    // (`texels_per_pixel`).
    texels_per_pixel: f32,
    inside: bool,
};

// A world point's light-clip position in `face`.
fn clip_of(face: u32, p: vec3f) -> vec4f {
    if is_paraboloid() {
        return paraboloid(vec4f(p, 1.0), face);
    }
    return sm.faces[face] * vec4f(p, 1.0);
}

// A world point's map uv and compared depth in `face`.
fn map_point(face: u32, p: vec3f) -> vec3f {
    let c = clip_of(face, p);
    let ndc = c.xyz / select(c.w, 1e-6, abs(c.w) < 1e-6);
    let z = select(ndc.z, dot(sm.warp_depth, vec4f(p, 1.0)), is_warped());
    return vec3f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, z);
}

// The receiver plane (Isidoro 2006) from the surface itself: d(depth)/d(uv)
// of the plane through p with normal `normal`, from the map points of two
// steps of `step` along it — the kernel's reach: over one texel of a fine
// map the depth difference drowns in float rounding (screen derivatives
// break where a pixel quad straddles an edge, exactly where the plane
// matters); 0 when off, and on a receiver facing away from the light (its
// visibility never reaches the image; seen from behind, the plane is
// ill-conditioned).
fn receiver_plane_at(face: u32, p: vec3f, normal: vec3f, at: vec3f, step: f32) -> vec2f {
    if !RECEIVER_PLANE || !faces_light(p, normal) {
        return vec2f(0.0);
    }
    let t = surface_tangent(normal);
    let dx = map_point(face, p + t * step) - at;
    let dy = map_point(face, p + cross(normal, t) * step) - at;
    return solve_plane(dx, dy, 4.0);
}

// The crease tolerance of a receiver at p (unit geometric normal `normal`)
// whose compared depth is z: the depth a tap may lie below the receiver's
// plane per unit of uv from the lookup point. A facet's plane leaves a
// curved surface behind within the kernel's reach at a concave crease; a
// neighbour rising tan(`crease_angle`) (`sm.screen.z`) per unit of distance
// out of the plane, along its normal, meets the light's ray that far
// before the plane over 1/(N·L) as much (up to CREASE_GRAZING_GAIN times),
// in depth the change over a step towards the light (z_toward) as long as
// a texel; 0 off the plane.
fn crease_tolerance(p: vec3f, normal: vec3f, z: f32, z_toward: f32) -> f32 {
    if !RECEIVER_PLANE || !faces_light(p, normal) {
        return 0.0;
    }
    let rise = max(dot(normal, to_light(p)), 1.0 / CREASE_GRAZING_GAIN);
    return sm.screen.z * abs(z_toward - z) * sm.map.x / rise;
}

// The most the crease tolerance grows as the light grazes the receiver
// (1/(N·L) capped): at grazing light any rise along the normal is a long
// way along the light's ray, and an uncapped tolerance would pass every
// caster near the receiver.
const CREASE_GRAZING_GAIN: f32 = 5.0;

// Projects G-buffer point g into `face`, moved along `offset_n` (its normal,
// or none), with the receiver plane of its geometric `normal`.
fn projected(face: u32, g: vec4f, offset_n: vec3f, normal: vec3f) -> Projected {
    // Normal offset: move the lookup point along the geometric normal by a
    // number of shadow-map texels (their world size grows with distance for
    // perspective maps, and with each cascade).
    var texel_world = sm.map.z;
    if is_warped() {
        texel_world = warped_texel_world(face, g.xyz);
    } else if CASCADED {
        texel_world = sm.cascade_texel[face / 4u][face % 4u];
    } else if !is_orthographic() {
        texel_world = sm.map.z * length(g.xyz - sm.light.xyz);
    }
    let p = offset_point(g.xyz, offset_n, texel_world);
    let c = clip_of(face, p);
    let at = map_point(face, p);
    let gradient = receiver_plane_at(face, p, normal, at, texel_world * max(kernel_reach(), 1.0));
    let crease = crease_tolerance(p, normal, at.z, map_point(face, p + to_light(p) * texel_world).z);
    // Outside the map counts as lit.
    let inside = g.w >= 0.5 && c.w > 0.0 && all(at.xy >= vec2f(0.0)) && all(at.xy <= vec2f(1.0))
        && at.z <= 1.0 && at.z >= 0.0;
    var footprint = 0.0;
    for (var steepened = steepens_ramps(); steepened; steepened = false) {
        let jx = map_point(face, p + pixel_step_x).xy - at.xy;
        let jy = map_point(face, p + pixel_step_y).xy - at.xy;
        footprint = texels_per_pixel(jx, jy);
    }
    return Projected(c, at.xy, at.z, gradient, crease, footprint, inside);
}

// The visibility of a projected point in `face`: the opaque casters'
// filtered test times, with `blended_casters=transmit`, the share of the
// light the translucent casters let through.
fn filtered(face: u32, pr: Projected, frag: vec2f) -> f32 {
    var v = filtered_opaque(face, pr, frag);
    for (var translucent = TRANSMIT && pr.inside; translucent; translucent = false) {
        v *= transmitted(pr.uv, face, pr.z);
    }
    return v;
}

// The filtered visibility of a projected point in `face` behind the opaque
// casters.
fn filtered_opaque(face: u32, pr: Projected, frag: vec2f) -> f32 {
    if !pr.inside {
        return 1.0;
    }
    // A receiver with its own part keeps one depth (`receiver_plane`).
    rp_gradient = select(pr.gradient, vec2f(0.0), has_own_part());
    rp_origin = pr.uv;
    rp_crease = select(pr.crease, 0.0, has_own_part());
    rp_depth = pr.z;
    if FILTER_KIND >= FILTER_VSM {
        return sharpened(moment_visibility(moments_at(pr.uv, face), moment_depth_of(select(linear01(pr.clip), pr.z, is_warped()))), pr.texels_per_pixel);
    }
    // The crease tolerance forgives the taps only where the receiver's own
    // texel (the one its lookup point lies in) is lit: a surface meeting a
    // lit receiver at a concave crease (a dome on a plate, the next facet)
    // rises beside it, while a low caster's shadow (raised lettering under
    // grazing light) covers the receiver's own texel as well. A loop, not
    // a branch (see the edge mask below): no load where there is no
    // tolerance to keep (receivers with a part, receiver_plane=false).
    for (var forgiving = rp_crease > 0.0; forgiving; forgiving = false) {
        rp_crease = select(rp_crease, 0.0, lit_at_plane(vec2i(floor(pr.uv * sm.map.x)), face) == 0.0);
    }
    // Edge mask: where every tap agrees, the kernel's loops run zero times.
    // A trip count, not an early return: SIMD rasterisers (llvmpipe among
    // them) run both sides of a branch under a lane mask but leave a loop
    // as soon as no lane is still in it. (A constant count inside a
    // one-trip loop, unrolled, measured slower on llvmpipe.)
    var count = max(TAPS, 1u);
    var known = -1.0;
    if EDGE_MASK && (FILTER_KIND == FILTER_GRID || FILTER_KIND == FILTER_DISK
        || FILTER_KIND == FILTER_PCSS || FILTER_KIND == FILTER_VARWIDTH) {
        // Taps compare z along the receiver plane (depth per texel).
        known = edge_class(pr.uv, face, pr.z, rp_gradient * sm.map.y, kernel_reach());
        count = select(count, 0u, known >= 0.0);
    }
    return select(sharpened(kernel(face, pr, frag, count), pr.texels_per_pixel), known, known >= 0.0);
}

// The filter's kernel at a projected point, with `count` taps per side (0:
// none, and no blocker search).
fn kernel(face: u32, pr: Projected, frag: vec2f, count: u32) -> f32 {
    let uv = pr.uv;
    let z = pr.z;
    let radius = sm.kernel.x;
    let phi = ign(frag) * 6.2831853;
    var v = 1.0;
    switch FILTER_KIND {
        case FILTER_HARD: {
            v = lit_at_plane(vec2i(floor(uv * sm.map.x)), face);
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
                search = clamp(penumbra_texels(dr, select(sm.depth.x, 0.0, is_orthographic())), 1.0, 64.0);
            }
            let b = blockers(uv, face, z, search, select(BLOCKER_SEARCHES, 0u, count == 0u), phi);
            // Loops, not branches (see `filtered`): no disk where no blocker.
            for (var blocked = b.y > 0.0; blocked; blocked = false) {
                var w = (dr - b.x) / max(b.x, 1e-4) * sm.soft.x;
                if physical {
                    w = penumbra_texels(dr, b.x);
                }
                v = pcf_disk(uv, face, z, clamp(w, 0.5, 64.0), count * count, phi);
            }
        }
        default: {
            // Variable-width PCF (002): radius ∝ |d_blocker − d_receiver|^exponent.
            let b = blockers(uv, face, z, sm.soft.w, select(BLOCKER_SEARCHES, 0u, count == 0u), phi);
            for (var blocked = b.y > 0.0; blocked; blocked = false) {
                let w = sm.soft.y * pow(abs(linear_depth(z) - b.x), sm.soft.z);
                v = pcf_disk(uv, face, z, clamp(w, 0.5, 64.0), count * count, phi);
            }
        }
    }
    return v;
}
