// Virtual shadow maps: per pixel, the level whose texels cover at most one
// pixel (from the texel footprint of the pixel on its surface's plane, as
// `compare` measures it), the pages its kernel needs marked (fs_virtual_mark);
// the lookup reads each texel through the page table and, where a page is
// not resident (a pool too small), from the next coarser level that is.
// Adaptive maps (fs_adaptive_mark) mark fewer: a pixel keeps the finest level
// it has and asks for the next finer one only at a shadow edge.

const NO_LEVEL: u32 = 0xffffffffu;

// Adaptive maps: the least depth step (of [0, 1] light depth) between a
// receiver and a stored texel that counts as a shadow edge, 2^-16.
const EDGE_STEP: f32 = 1.52587890625e-5;

// World size of the texels of the level being filtered (pcss's penumbra).
var<private> virtual_texel_world: f32 = 1.0;
// The level being filtered, read once per pixel (not once per tap: a
// storage read per tap costs llvmpipe more than the taps).
var<private> filtered_level: VirtualLevel;

// Level i's entry of the levels buffer. Read once per level visited and
// passed on: each read is a gather across llvmpipe's lanes, and reading it
// in every helper made the marking pass's level search cost more than all
// the rest of it. (A cache of the last one in private variables behind a
// branch measured 1.6× slower: llvmpipe runs the read under a lane mask
// whatever the branch.)
fn level_at(i: u32) -> VirtualLevel {
    return vsm.levels[i];
}

// World size of one texel of level `l` at world point p.
fn level_texel_world(l: VirtualLevel, p: vec3f) -> f32 {
    let t = l.texel_world;
    if is_orthographic() {
        return t;
    }
    return t * length(p - sm.light.xyz);
}

// Texel coordinates of world point p in `level`'s window and its light
// depth. A clipmap's are taken relative to the camera (a fine level's texel
// is far below the float precision of uv over the whole square); the
// views' matrices take points relative to the camera too.
fn level_texel(l: VirtualLevel, p: vec3f) -> vec4f {
    let d = p - frame.camera_pos.xyz;
    if is_orthographic() {
        // A clipmap has one view, 0, with w = 1: a constant index, where
        // `l.view` would make each lane gather its own matrix.
        let t = vec2f(dot(vsm.axis_u, d), dot(vsm.axis_v, d)) / l.texel_world + l.eye_texel;
        return vec4f(t, (sm.faces[0] * vec4f(d, 1.0)).z, 1.0);
    }
    let c = sm.faces[l.view] * vec4f(d, 1.0);
    let ndc = c.xyz / select(c.w, 1e-6, abs(c.w) < 1e-6);
    return vec4f((vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) - l.origin) / l.texel, ndc.z, c.w);
}

// A lookup point in a level: uv = texel / map size (what the filters
// take), its depth, whether it is inside the window and in front.
struct VirtualPoint {
    uv: vec2f,
    z: f32,
    inside: bool,
};

// A point light's lookup point may lie up to its normal offset
// (`sm.kernel.y` texels of the level) outside the cube face whose
// direction holds the G-buffer point — at a coarse level a visible band
// along the seams — and reads the face's border texels there.
fn virtual_point(l: VirtualLevel, g: vec3f, n: vec3f) -> VirtualPoint {
    let t = level_texel(l, offset_point(g, n, level_texel_world(l, g)));
    let extent = f32(l.pages * vsm.page_texels);
    let margin = select(0.0, sm.kernel.y + 1.0, PROJECTION == PROJECTION_CUBE);
    let inside = t.w > 0.0 && all(t.xy >= vec2f(-margin)) && all(t.xy <= vec2f(extent + margin))
        && t.z >= 0.0 && t.z <= 1.0;
    return VirtualPoint(t.xy * sm.map.y, t.z, inside);
}

// The page-table entry of window page `page` of level `l` (absolute page
// indices wrap around the window: a clipmap level that moves with the
// camera keeps the entries of the pages it still covers).
fn entry_in(l: VirtualLevel, page: vec2i) -> u32 {
    // Windows, pages and the pool's rows are powers of two: masks and
    // shifts instead of integer division (scalar on SIMD CPUs).
    let w = (page + l.origin_page) & vec2i(i32(l.pages) - 1);
    return l.table + u32(w.y) * l.pages + u32(w.x);
}

// The window page holding texel t of level `l` (clamped to the window).
fn virtual_page_of(l: VirtualLevel, t: vec2f) -> vec2i {
    let size = f32(vsm.page_texels);
    let extent = f32(l.pages) * size;
    return vec2i(floor(clamp(t, vec2f(0.0), vec2f(extent - 1.0)) / size));
}

// Where window page `page` of level `l` lies in the pool: its slot's
// atlas texel minus the page's window texel, and its layer; layer −1
// where the page is not resident.
fn page_slot(l: VirtualLevel, page: vec2i) -> vec3i {
    let entry = vsm_table[entry_in(l, page)];
    let k = (entry - 1u) & (vsm.layer_pages - 1u);
    let row = vec2u(k & (vsm.atlas_pages - 1u), k >> countTrailingZeros(vsm.atlas_pages));
    let shift = vec2i(row) * i32(vsm.slot_texels) - page * i32(vsm.page_texels);
    let layer = i32((entry - 1u) >> countTrailingZeros(vsm.layer_pages));
    return select(vec3i(shift, layer), vec3i(0, 0, -1), entry == 0u);
}

// Window texel t of level `l` clamped to the window.
fn window_texel(t: vec2i, l: VirtualLevel) -> vec2i {
    return clamp(t, vec2i(0), vec2i(i32(l.pages * vsm.page_texels) - 1));
}

fn page_of_texel(t: vec2i) -> vec2i {
    return t >> vec2u(countTrailingZeros(vsm.page_texels));
}

// The atlas texel of window texel t of level `l` (clamped to the window)
// and its layer; layer −1 where no page is resident.
fn atlas_texel_in(t: vec2i, l: VirtualLevel) -> vec3i {
    let c = window_texel(t, l);
    let s = page_slot(l, page_of_texel(c));
    return vec3i(c + s.xy, s.z);
}

// The pool slots (`page_slot`) of the 2×2 window pages from `first`, the
// first page of the filtered kernel's span, read once per pixel: the
// kernel's taps take their slots from here instead of each reading the
// page table.
struct KernelSlots {
    first: vec2i,
    at: array<vec3i, 4>,
};
var<private> kernel_slots: KernelSlots;

// The slots of the pages under the kernel around texel t of level `l`:
// one table read where the kernel lies in one page, as it mostly does;
// the others in a one-trip loop (llvmpipe skips it when no lane needs it).
fn kernel_slots_of(l: VirtualLevel, t: vec2f) -> KernelSlots {
    let span = kernel_pages(l, t);
    var k: KernelSlots;
    k.first = span.first;
    k.at[0] = page_slot(l, k.first);
    k.at[1] = k.at[0];
    k.at[2] = k.at[0];
    k.at[3] = k.at[0];
    for (var across = any(span.last != span.first); across; across = false) {
        k.at[1] = page_slot(l, k.first + vec2i(1, 0));
        k.at[2] = page_slot(l, k.first + vec2i(0, 1));
        k.at[3] = page_slot(l, k.first + vec2i(1, 1));
    }
    return k;
}

// The atlas texel and layer of window texel t of the level filtered
// (clamped to the window), from the kernel's slots; through the page table
// only beyond its first 2×2 pages, which only a WIDE_KERNEL reaches (the
// loop's code alone, never run, costs llvmpipe a sixth of the lookup).
fn filtered_texel(t: vec2i) -> vec3i {
    let c = window_texel(t, filtered_level);
    let page = page_of_texel(c);
    let d = page - kernel_slots.first;
    let right = d.x == 1;
    var s = select(select(kernel_slots.at[0], kernel_slots.at[1], right), select(kernel_slots.at[2], kernel_slots.at[3], right), d.y == 1);
    for (var beyond = WIDE_KERNEL && (any(d > vec2i(1)) || any(d < vec2i(0))); beyond; beyond = false) {
        s = page_slot(filtered_level, page);
    }
    return vec3i(c + s.xy, s.z);
}

// Hardware 2×2 comparison at uv of the level being filtered: its four
// texels lie in the slot of the first one's page (which holds the guard
// texels past the page's edges), so the atlas's own bilinear footprint is
// the map's. Clamped to the window's edge texels, as one map's sampler
// clamps; lit where the page is not resident (the lookup's level has its
// kernel's pages).
fn virtual_pcf2x2(uv: vec2f, z: f32) -> f32 {
    let extent = f32(filtered_level.pages * vsm.page_texels);
    let p = clamp(uv * sm.map.x - 0.5, vec2f(0.0), vec2f(extent - 1.0));
    let a = filtered_texel(vec2i(floor(p)));
    let side = f32(vsm.atlas_pages * vsm.slot_texels);
    let atlas_uv = (vec2f(a.xy) + 0.5 + fract(p)) / side;
    let v = textureSampleCompareLevel(depth_map, compare_sampler, atlas_uv, max(a.z, 0), z);
    return select(v, 1.0, a.z < 0);
}

// Stored depth at atlas texel a (layer a.z); 1 (lit) where no page is
// resident (a.z = −1).
fn atlas_stored(a: vec3i) -> f32 {
    return select(textureLoad(depth_map, a.xy, max(a.z, 0), 0), 1.0, a.z < 0);
}

// Stored depth at texel t of level `l`'s window, through the page table.
fn virtual_stored(t: vec2i, l: VirtualLevel) -> f32 {
    return atlas_stored(atlas_texel_in(t, l));
}

// A level found for a pixel: its index (NO_LEVEL for none), its entry and
// the lookup point in it.
struct FoundLevel {
    index: u32,
    level: VirtualLevel,
    point: VirtualPoint,
};

// Whether a pixel's point is inside the window of level `f` and, for a
// clipmap, the window holds the whole kernel around it.
fn level_holds(f: FoundLevel) -> bool {
    let t = f.point.uv * sm.map.x;
    let reach = marked_reach();
    let extent = f32(f.level.pages * vsm.page_texels);
    let holds = all(t >= vec2f(reach)) && all(t <= vec2f(extent - reach));
    return f.point.inside && (!is_orthographic() || holds);
}

// The level for G-buffer point p (normal n) at `pixel`: in its view, the
// coarsest whose texels span at most one pixel (footprint × 2^level ≤ 1),
// `oversample_levels` finer for a local light's view;
// for a clipmap, moved up until the window holds the whole kernel. Its
// entry and point come with it (the marks use them).
fn virtual_level_of(pixel: vec2i, p: vec3f, n: vec3f) -> FoundLevel {
    let base = face_of(p) * vsm.view_levels;
    let base_level = level_at(base);
    // The pixel steps over p's own plane, not toward its G-buffer
    // neighbours: in foliage or at any silhouette both may lie on other
    // surfaces, metres away, which would send the pixel to a level far
    // too coarse.
    set_pixel_steps(vec2f(pixel) + 0.5, p, n);
    let at = level_texel(base_level, p).xy;
    let dx = level_texel(base_level, p + pixel_step_x).xy - at;
    let dy = level_texel(base_level, p + pixel_step_y).xy - at;
    let footprint = texel_footprint(dx, dy);
    let finer = select(f32(vsm.oversample_levels), 0.0, is_orthographic());
    let steps = clamp(floor(-log2(max(footprint, 1e-12))) - finer, 0.0, f32(vsm.view_levels - 1u));
    var found = FoundLevel(base + u32(steps), level_at(base + u32(steps)), VirtualPoint());
    found.point = virtual_point(found.level, p, n);
    // Up a level at a time, in a loop that llvmpipe leaves when no lane of
    // its SIMD group is in it (most pixels hold at the first level); it
    // ends at the view's coarsest level (its own parent) at the latest.
    for (var up = !level_holds(found); up && found.level.parent != found.index; up = !level_holds(found)) {
        found.index = found.level.parent;
        found.level = level_at(found.index);
        found.point = virtual_point(found.level, p, n);
    }
    found.index = select(NO_LEVEL, found.index, found.point.inside);
    return found;
}

// Texels around a pixel's lookup point whose pages are marked: the
// kernel's reach and half a texel more (the texel a tap's edge falls in).
fn marked_reach() -> f32 {
    return kernel_reach() + 0.5;
}

// The window pages a kernel reads: from the page of its marked reach's
// least corner to its greatest corner's (clamped to the window).
struct PageSpan {
    first: vec2i,
    last: vec2i,
};

// The pages of level `l` a kernel around texel t reads.
fn kernel_pages(l: VirtualLevel, t: vec2f) -> PageSpan {
    let r = marked_reach();
    return PageSpan(virtual_page_of(l, t - vec2f(r)), virtual_page_of(l, t + vec2f(r)));
}

// Sets the bit of window page `page` of level `l` (a plain read first: most
// pixels find their pages already marked, and a read is cheaper than an
// atomic write). The write sits in a one-trip loop, which llvmpipe skips
// when no lane of its SIMD group needs it; a branch would run it under a
// lane mask whichever way it went.
fn mark_page(l: VirtualLevel, page: vec2i) {
    let e = entry_in(l, page);
    let bit = 1u << (e % 32u);
    for (var unmarked = (atomicLoad(&vsm_marks[e / 32u]) & bit) == 0u; unmarked; unmarked = false) {
        atomicOr(&vsm_marks[e / 32u], bit);
    }
}

// Marks the pages a kernel around texel t of level `l` reads: those from
// the page of its reach's least corner to its greatest's — one, or across
// borders 2×2, or 3×3 for a kernel wider than a page (those in a one-trip
// loop, as in `mark_page`: most kernels lie in one page).
fn mark_kernel(l: VirtualLevel, t: vec2f) {
    let span = kernel_pages(l, t);
    mark_page(l, span.first);
    for (var across = any(span.last != span.first); across; across = false) {
        // The first page again costs a plain read: its bit is set.
        for (var y = span.first.y; y <= span.last.y; y++) {
            for (var x = span.first.x; x <= span.last.x; x++) {
                mark_page(l, vec2i(x, y));
            }
        }
    }
}

// Marks the pages the kernel of G-buffer point g (normal n) reads in
// `level`.
fn mark_point(level: u32, g: vec3f, n: vec3f) {
    let l = level_at(level);
    mark_kernel(l, virtual_point(l, g, n).uv * sm.map.x);
}

// Marks the pages the kernel of a pixel's point reads in the level found.
fn mark_found(f: FoundLevel) {
    mark_kernel(f.level, f.point.uv * sm.map.x);
}

// Whether every page a kernel around texel t of level `l` reads (as
// `mark_kernel` marks them) is resident: one table read where the kernel
// lies in one page, as it mostly does.
fn kernel_resident(l: VirtualLevel, t: vec2f) -> bool {
    let span = kernel_pages(l, t);
    var resident = vsm_table[entry_in(l, span.first)] != 0u;
    for (var across = resident && any(span.last != span.first); across; across = false) {
        for (var y = span.first.y; y <= span.last.y; y++) {
            for (var x = span.first.x; x <= span.last.x; x++) {
                resident = resident && vsm_table[entry_in(l, vec2i(x, y))] != 0u;
            }
        }
    }
    return resident;
}

// The finest level from `level` up (toward its view's coarsest) where the
// point of G-buffer point g (normal n) is inside the window and every page
// its kernel reads is resident; NO_LEVEL where none is (lit).
fn resident_level(level: u32, g: vec3f, n: vec3f) -> FoundLevel {
    var index = level;
    for (var i = 0u; i < vsm.view_levels; i++) {
        let l = level_at(index);
        let q = virtual_point(l, g, n);
        if q.inside && kernel_resident(l, q.uv * sm.map.x) {
            return FoundLevel(index, l, q);
        }
        if l.parent == index {
            break;
        }
        index = l.parent;
    }
    var none: FoundLevel;
    none.index = NO_LEVEL;
    return none;
}

// The coarsest level of the view that `level` belongs to.
fn root_level(level: u32) -> u32 {
    return level - level % vsm.view_levels + vsm.view_levels - 1u;
}

// d(uv, depth) in `level` of a world step `dg` at G-buffer point g: the
// view's linear part applied to the step (not the difference of two
// projected points, which loses the step to rounding of the light depth).
fn level_step(level: u32, g: vec3f, dg: vec3f) -> vec3f {
    let l = level_at(level);
    let m = sm.faces[l.view];
    let dc = m * vec4f(dg, 0.0);
    if is_orthographic() {
        let t = vec2f(dot(vsm.axis_u, dg), dot(vsm.axis_v, dg)) / l.texel_world;
        return vec3f(t * sm.map.y, dc.z);
    }
    let c = m * vec4f(g - frame.camera_pos.xyz, 1.0);
    let d = (dc.xyz - c.xyz / c.w * dc.w) / c.w;
    return vec3f(vec2f(0.5 * d.x, -0.5 * d.y) / l.texel * sm.map.y, d.z);
}

// The receiver plane's d(depth)/d(uv) in `level` from the screen
// derivatives gx, gy of the G-buffer position, clamped as the lookup
// clamps its own, scaled to the level.
fn level_gradient(level: u32, g: vec3f, gx: vec3f, gy: vec3f) -> vec2f {
    let limit = 4.0 * exp2(f32(level % vsm.view_levels));
    return solve_plane(level_step(level, g, gx), level_step(level, g, gy), limit);
}

// Adaptive maps: whether `level` shows a shadow edge under the kernel
// around point (g, n) — the stored depths of the texels it reads and one
// more each side (at most 9 × 9 of them, strided beyond) do not all lie on
// one side of the receiver, compared along the receiver's plane
// (`gradient`, d(depth)/d(uv) in this level) as the filters' taps are.
fn adaptive_edge(level: u32, g: vec3f, n: vec3f, gradient: vec2f) -> bool {
    let l = level_at(level);
    let q = virtual_point(l, g, n);
    let t = q.uv * sm.map.x;
    let r = marked_reach() + 1.0;
    let lo = floor(t - vec2f(r));
    let span = floor(t.x + r) - lo.x + 1.0;
    let stride = max(ceil(span / 9.0), 1.0);
    let count = u32(ceil(span / stride));
    // The 2×2 comparison's slack (as `filtered` takes it), and a depth
    // discontinuity's least step: a receiver that faces the light stores
    // its own depth within rounding of what the lookup computes.
    let z = q.z - min(2.0 * dot(vec2f(sm.map.y), abs(gradient)), 0.01) - EDGE_STEP;
    // Mostly the window lies in one resident page: its atlas texels are
    // then read directly, without a page-table read per texel.
    let first = vec2i(lo);
    let last = first + vec2i(i32(f32(count - 1u) * stride));
    let size = i32(vsm.page_texels);
    let extent = i32(l.pages) * size;
    let one_page = all(first >= vec2i(0)) && all(last < vec2i(extent))
        && all((first >> vec2u(countTrailingZeros(vsm.page_texels))) == (last >> vec2u(countTrailingZeros(vsm.page_texels))));
    let origin = atlas_texel_in(first, l);
    let direct = one_page && origin.z >= 0;
    var lit = 0u;
    var shadowed = 0u;
    for (var y = 0u; y < count; y++) {
        for (var x = 0u; x < count; x++) {
            let step = vec2f(f32(x), f32(y)) * stride;
            let texel = lo + step;
            let receiver = z + dot((texel + 0.5 - t) * sm.map.y, gradient);
            var stored = 1.0;
            if direct {
                stored = textureLoad(depth_map, origin.xy + vec2i(step), origin.z, 0);
            } else {
                stored = virtual_stored(vec2i(texel), l);
            }
            if receiver <= stored {
                lit += 1u;
            } else {
                shadowed += 1u;
            }
        }
    }
    return lit > 0u && shadowed > 0u;
}

// Adaptive marking (Fernando et al. 2001, refined on the GPU's marks): the
// pixel keeps the finest level it has (`need` its finest useful one) and
// asks for the next finer one where that level shows a shadow edge; with
// nothing resident yet, its view's coarsest level (the hierarchy's root).
// gx, gy: the screen derivatives of the G-buffer position.
fn adaptive_mark(need: u32, g: vec3f, n: vec3f, gx: vec3f, gy: vec3f) {
    let have = resident_level(need, g, n).index;
    if have == NO_LEVEL {
        mark_point(root_level(need), g, n);
        return;
    }
    mark_point(have, g, n);
    if have != need && adaptive_edge(have, g, n, level_gradient(have, g, gx, gy)) {
        mark_point(have - 1u, g, n);
    }
}

fn pixel_index(pixel: vec2i) -> u32 {
    return u32(pixel.y) * u32(frame.size.x) + u32(pixel.x);
}

// Each receiving pixel's level (index NO_LEVEL for none), stored for the
// lookup.
fn pixel_level(pixel: vec2i, g: vec4f, n: vec3f) -> FoundLevel {
    var found: FoundLevel;
    found.index = NO_LEVEL;
    if g.w >= 0.5 {
        found = virtual_level_of(pixel, g.xyz, n);
    }
    vsm_pixel_level[pixel_index(pixel)] = found.index;
    return found;
}

// A marking pass's pixel: its G-buffer point and normal, and its level
// (stored for the lookup).
struct MarkingPixel {
    g: vec4f,
    n: vec3f,
    found: FoundLevel,
};

fn marking_pixel(frag: vec4f) -> MarkingPixel {
    let pixel = vec2i(frag.xy);
    let g = textureLoad(gbuffer_position, pixel, 0);
    let n = offset_direction(g, normalize(textureLoad(gbuffer_normal, pixel, 0).xyz));
    return MarkingPixel(g, n, pixel_level(pixel, g, n));
}

// The virtual map's marking pass: each receiving pixel's level, and the
// pages its kernel reads (the corners of its reach: at most 2×2 pages).
@fragment
fn fs_virtual_mark(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let p = marking_pixel(frag);
    if p.found.index != NO_LEVEL {
        mark_found(p.found);
    }
    return vec4f(1.0);
}

// The adaptive map's marking pass (one refinement).
@fragment
fn fs_adaptive_mark(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let p = marking_pixel(frag);
    // The receiver's screen derivatives (uniform control flow).
    let gx = dpdx(p.g.xyz);
    let gy = dpdy(p.g.xyz);
    if p.found.index != NO_LEVEL {
        adaptive_mark(p.found.index, p.g.xyz, p.n, gx, gy);
    }
    return vec4f(1.0);
}

// The lookup: the pixel's level or, where its kernel's pages are not all
// resident, the first coarser level of the view where they are; lit where
// none is. With MARKED_RESIDENT, the pixel's level without that search.
fn virtual_visibility(frag: vec2f, g: vec4f, n: vec3f, normal: vec3f) -> f32 {
    let marked = vsm_pixel_level[pixel_index(vec2i(frag))];
    let first = select(marked, 0u, marked == NO_LEVEL);
    var found = FoundLevel(first, level_at(first), VirtualPoint());
    found.point = virtual_point(found.level, g.xyz, n);
    if marked == NO_LEVEL || g.w < 0.5 {
        return 1.0;
    }
    if !MARKED_RESIDENT {
        found = resident_level(first, g.xyz, n);
        if found.index == NO_LEVEL {
            return 1.0;
        }
    }
    filtered_level = found.level;
    let q = found.point;
    kernel_slots = kernel_slots_of(filtered_level, q.uv * sm.map.x);
    virtual_texel_world = level_texel_world(filtered_level, g.xyz);
    let lookup = offset_point(g.xyz, n, virtual_texel_world);
    let gradient = receiver_plane(filtered_level, q, g.xyz, lookup, virtual_texel_world, normal);
    var footprint = 0.0;
    for (var steepened = steepens_ramps(); steepened; steepened = false) {
        let jx = virtual_point(filtered_level, g.xyz + pixel_step_x, n).uv - q.uv;
        let jy = virtual_point(filtered_level, g.xyz + pixel_step_y, n).uv - q.uv;
        footprint = texels_per_pixel(jx, jy);
    }
    let toward = virtual_point(filtered_level, lookup + to_light(lookup) * virtual_texel_world, vec3f(0.0));
    let crease = crease_tolerance(g.xyz, normal, q.z, toward.z);
    let pr = Projected(vec4f(0.0, 0.0, q.z, 1.0), q.uv, q.z, gradient, crease, footprint, q.inside);
    return filtered(found.index, pr, frag);
}

// Debug views of a virtual map: pages tinted by level over the scene, and
// the texel footprint `compare` reads (of the level looked up).
fn virtual_debug_frame(frag: vec4f) -> DebugFrame {
    let pixel = vec2i(frag.xy);
    let g = textureLoad(gbuffer_position, pixel, 0);
    let gx = dpdx(g.xyz);
    let gy = dpdy(g.xyz);
    let n = offset_direction(g, normalize(textureLoad(gbuffer_normal, pixel, 0).xyz));
    let marked = vsm_pixel_level[pixel_index(pixel)];
    let first = select(marked, 0u, marked == NO_LEVEL);
    let found = resident_level(first, g.xyz, n).index;
    let level = select(found, first, found == NO_LEVEL);
    let l = level_at(level);
    let vp = virtual_point(l, g.xyz, n);
    let texel = vp.uv * sm.map.x;
    let dx = (virtual_point(l, g.xyz + gx, n).uv - vp.uv) * sm.map.x;
    let dy = (virtual_point(l, g.xyz + gy, n).uv - vp.uv) * sm.map.x;
    let pixels_per_texel = texel_footprint(dx, dy);
    let texels_per_pixel = max(length(dx), length(dy));
    var o: DebugFrame;
    let inside = g.w > 0.5 && marked != NO_LEVEL && vp.inside;
    let resident = found != NO_LEVEL;
    // Page borders darkened; a missing page dark red.
    let in_page = fract(texel / f32(vsm.page_texels));
    let border = any(in_page < vec2f(0.02)) || any(in_page > vec2f(0.98));
    let tint = cascade_tint(level % vsm.view_levels) * select(1.0, 0.55, border);
    let colour = select(vec3f(0.5, 0.0, 0.0), tint, resident);
    o.projection = select(vec4f(0.0, 0.0, 0.0, 1.0), vec4f(colour, 1.0), inside);
    let t = clamp(log2(max(texels_per_pixel, 1e-6)) / 2.0, -1.0, 1.0);
    let heat = select(mix(vec3f(0.0, 1.0, 0.0), vec3f(1.0, 0.0, 0.0), t), mix(vec3f(0.0, 1.0, 0.0), vec3f(0.0, 0.2, 1.0), -t), t < 0.0);
    o.texels = select(vec4f(0.0, 0.0, 0.0, 1.0), vec4f(heat, 1.0), inside);
    o.lookup = select(vec2f(0.0), vec2f(pixels_per_texel, f32(level + 1u)), inside);
    return o;
}
