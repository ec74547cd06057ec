// The irregular z-buffer (Johnson, Mark & Burns 2005; Aila & Laine 2004;
// Sintorn, Eisemann & Assarsson 2008): the camera's own samples are binned
// into a light-space grid, each caster triangle visits the cells its image
// covers and tests the samples listed there exactly, and the mask is 0
// where a triangle blocks a sample's ray to the light. This file holds the
// interface and the triangle passes; samples.wgsl the samples and their
// binning. common.wgsl and gbuffer.wgsl are prepended.

struct Irregular {
    // world → light view of each face: six cube faces for point lights and
    // wide spots, one perspective view along a spot's axis (up to 75°), one
    // orthographic view for directional lights
    views: array<mat4x4f, 6>,
    // xyz the light's position (local lights) or the direction it travels
    // (directional), w 1 for a local light
    light: vec4f,
    // x faces, y the grid side asked for (`grid`: cells per face side on
    // every face), or 0: each face's side fitted to its samples
    // (`cs_face_layout`), z frame width, w frame height
    grid: vec4u,
    // x unused, y samples above which a triangle is left to the
    // job pass, z the job list's capacity, w the cells the binning buffer
    // holds (N)
    work: vec4u,
    // x ray-origin offset in ULPs and z its lift as a fraction of the
    // pixel's footprint (the reference's rule), y the light's range (0:
    // none), w the cells per sample a fitted face is given
    offset: vec4f,
    // x samples per pixel (1: its centre; up to 32, one mark bit each), y
    // how rays meet translucent casters (BLENDED_*), zw unused
    pixel: vec4u,
    // xyz a spot light's unit axis, w the cosine of its outer cone (below
    // −1 for other lights: no cone)
    cone: vec4f,
    // The caster triangles this frame tests (`kept_ranges`): x the opaque
    // run's ranges (they lead), y all ranges, z the opaque run's kept
    // triangles, w the see-through run's
    kept: vec4u,
};

struct CasterTriangle {
    // xyz world positions, w the vertex's u
    a: vec4f,
    b: vec4f,
    c: vec4f,
    // xyz the vertices' v, w the object (bits)
    v: vec4f,
};

// Whether pixels have several samples (`irr.pixel.x` > 1): a pipeline
// constant, so that the passes over one sample per pixel carry none of
// the sub-pixel code.
override SUB_PIXEL: bool = false;

// The samples of each pixel.
fn samples_per_pixel() -> u32 {
    return select(1u, irr.pixel.x, SUB_PIXEL);
}

@group(2) @binding(0) var<uniform> irr: Irregular;
// The binning's words, three arrays in one buffer (N = irr.work.w cells,
// face-major, row-major): [0, N) each cell's sample count (for sub-pixel
// samples then the scatter's cursor, back to 0 when it is done); [N, 2N] the exclusive
// prefix sum of the counts, the first sample of each cell in `samples`
// (its last word the total); then the prefix sum's per-block partials.
@group(2) @binding(1) var<storage, read_write> cells: array<atomic<u32>>;
// The samples sorted by cell, so a cell's, and a row of cells', samples
// are contiguous. Each is identified by its pixel · 32 plus its index
// within the pixel. One sample per pixel: four words, the shadow-ray
// origin's xyz (bits) and the id; then, one per pixel, the samples staged
// before the sort (`staged_slot` of samples.wgsl). Sub-pixel samples: the
// id alone, the origin found again from the G-buffer (4 bytes a sample,
// so that 16 of them for a 1280 × 720 frame fit one storage buffer).
@group(2) @binding(2) var<storage, read_write> samples: array<vec4u>;
// Per pixel: bit k set once a caster blocks its sample k; then, under
// BLENDED_TRANSMIT, each sample's optical depth (`depth_slot`).
@group(2) @binding(3) var<storage, read_write> marks: array<atomic<u32>>;
@group(2) @binding(4) var<storage, read> triangles: array<CasterTriangle>;
// The header (AUX_* words: counters, list-length histogram, per-face bounds)
// and then the job list.
@group(2) @binding(5) var<storage, read_write> aux: array<atomic<u32>>;
// The per-face bounds of the header (AUX_BOUNDS), then the faces' grids
// (AUX_LAYOUT), copied there after the layout pass: the passes after it
// read them as plain words, not atomics (which llvmpipe runs a lane at a
// time).
@group(2) @binding(6) var<uniform> face_boxes: array<vec4u, 12>;
// The caster triangles this frame tests, as ranges of `triangles`: (the
// run's thread that starts the range, its first triangle), the opaque
// run's first (`irr.kept`); the clusters that cannot shadow a sample are
// left out (cull.rs).
@group(2) @binding(7) var<storage, read> kept_ranges: array<vec2u>;

const AUX_SAMPLES: u32 = 0u;
// (AUX_TESTS follows AUX_PAIRS: `count_work` adds both by one index.)
const AUX_PAIRS: u32 = 1u;
const AUX_TESTS: u32 = 2u;
// Jobs asked for by large triangles (some may not have fitted the list).
const AUX_JOBS: u32 = 3u;
// The job pass's indirect dispatch (x, y, z workgroups).
const AUX_DISPATCH: u32 = 4u;
// Samples of jobs that did not fit the list, tested by their triangle's thread.
const AUX_OVERFLOW: u32 = 7u;
const AUX_HISTOGRAM: u32 = 8u;
const HISTOGRAM_BINS: u32 = 32u;
// Per face, 4 words: −least x, −least y (as ~ordered), greatest x, greatest y.
const AUX_BOUNDS: u32 = 40u;
// The longest list.
const AUX_LONGEST: u32 = 64u;
// The see-through casters' jobs (they fill the list from its end), and the
// indirect dispatch of their job pass.
const AUX_SEE_THROUGH_JOBS: u32 = 65u;
const AUX_SEE_THROUGH_DISPATCH: u32 = 66u;
// Per face, the samples the bounds pass found on it.
const AUX_FACE_SAMPLES: u32 = 80u;
// Per face, 4 words of its grid (`cs_face_layout`): cells per side, its
// first cell, the cells all faces use, 0.
const AUX_LAYOUT: u32 = 88u;
// The jobs, four words each: triangle · 8 + face, job, the box row its
// first sample lies in, the box's samples before that row.
const AUX_JOB_LIST: u32 = 112u;
// Threads of every workgroup; samples of one job (so that no invocation
// loops long: llvmpipe ends a shader's loops after 65535 iterations in
// all, and GPUs have watchdogs); counts summed by one prefix-sum block.
const WORKGROUP: u32 = 64u;
const JOB_SAMPLES: u32 = 1024u;
const SCAN_BLOCK: u32 = 1024u;

// Float bits whose unsigned order is the floats' order (never 0 for a number).
fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b ^ 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_ordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u ^ 0x80000000u, (u & 0x80000000u) != 0u));
}

fn is_local() -> bool {
    return irr.light.w > 0.5;
}

// Offsets `p` along `n` by `ulps` units in the last place of each coordinate
// (Wächter & Binder 2019), as the reference's `offset_ray_origin`.
fn offset_origin(p: vec3f, n: vec3f, ulps: f32) -> vec3f {
    var out: vec3f;
    for (var k = 0; k < 3; k++) {
        let steps = i32(ulps * n[k]);
        let bits = bitcast<i32>(p[k]);
        let moved = bitcast<f32>(select(bits + steps, bits - steps, p[k] < 0.0));
        out[k] = select(moved, p[k] + (1.0 / 65536.0) * n[k] * ulps / 256.0, abs(p[k]) < 1.0 / 32.0);
    }
    return out;
}

// Whether the test passes run over the see-through casters (the list's
// triangles from `irr.pixel.z` on) or the opaque ones (before it): a
// pipeline constant, so that the opaque casters' loops hold none of the
// see-through code (llvmpipe slows a loop by the code it holds, run or not).
override SEE_THROUGH: bool = false;
// How a shadow ray meets a translucent (glTF BLEND) caster is `irr.pixel.y`,
// one of the BLENDED_* constants prepended from `BlendedCrossing` of
// mod.rs: solid where its opacity reaches ½, letting 1 − opacity through
// (the reference's transmittance), solid, or not at all.
// Whether the pipeline sums optical depths (`blended_casters=transmit`): a
// pipeline constant, so that the other modes' test passes carry none of
// its code (llvmpipe runs both sides of a branch its lanes diverge on).
override TRANSMIT: bool = false;
// Optical depth −ln(transmittance) is summed per sample in fixed point,
// these units per unit (an order-independent product of transmittances).
const DEPTH_UNITS: f32 = 65536.0;
// The optical depth past which a sample counts as blocked: ln 65536, where
// the reference stops tracing (`OPAQUE_ENOUGH`, a transmittance of 1/65536).
const OPAQUE_DEPTH: f32 = 11.090355;

// The opacity triangle `t` puts in the way of the ray from `o` to the light
// (Möller & Trumbore 1997): 0 where the ray misses it or passes a cut-out's
// hole, 1 where it blocks, the opacity in between where a translucent
// caster transmits the rest (alpha-tested and sampled at full resolution,
// as the reference's see-through casters).
fn opacity_crossed(t: CasterTriangle, o: vec3f) -> f32 {
    var d = -irr.light.xyz;
    var t_max = 3.0e38;
    if is_local() {
        d = irr.light.xyz - o;
        t_max = 1.0;
    }
    let e1 = t.b.xyz - t.a.xyz;
    let e2 = t.c.xyz - t.a.xyz;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if abs(det) < 1e-30 {
        return 0.0;
    }
    let inv = 1.0 / det;
    let s = o - t.a.xyz;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return 0.0;
    }
    let q = cross(s, e1);
    let w = dot(d, q) * inv;
    if w < 0.0 || u + w > 1.0 {
        return 0.0;
    }
    let hit = dot(e2, q) * inv;
    if hit <= 0.0 || hit >= t_max {
        return 0.0;
    }
    if !SEE_THROUGH {
        return 1.0;
    }
    let object = bitcast<u32>(t.v.w);
    let mode = objects[object].alpha.x;
    if mode == ALPHA_OPAQUE {
        return 1.0;
    }
    return see_through_opacity(t, object, mode == ALPHA_BLEND, u, w);
}

// A cut-out's or translucent caster's opacity where the ray meets it, at
// barycentric (u, w): its opacity map read once.
fn see_through_opacity(t: CasterTriangle, object: u32, blended: bool, u: f32, w: f32) -> f32 {
    let uv = vec2f(t.a.w, t.v.x) * (1.0 - u - w) + vec2f(t.b.w, t.v.y) * u + vec2f(t.c.w, t.v.z) * w;
    let opacity = opacity_at(object, uv, 0.0);
    if !blended {
        return select(0.0, 1.0, reaches_cutoff(object, opacity, 0.5));
    }
    if TRANSMIT {
        return clamp(opacity, 0.0, 1.0);
    }
    switch irr.pixel.y {
        case BLENDED_OPAQUE: {
            return 1.0;
        }
        case BLENDED_IGNORE: {
            return 0.0;
        }
        default: {
            return select(0.0, 1.0, reaches_cutoff(object, opacity, 0.5));
        }
    }
}

// Whether `t` is a face of an opaque solid turned away from the light:
// a ray from outside the solid toward the light that crosses it leaves
// the solid through a face turned toward the light, which blocks it too,
// so only those are tested (half a solid's faces; the irregular
// z-buffer's twin of a shadow map storing one side of its solids).
// `caster_triangles` keeps every solid's triangles wound outward.
fn faces_away_on_a_solid(t: CasterTriangle) -> bool {
    let object = bitcast<u32>(t.v.w);
    if objects[object].info.w == SOLID_NONE || objects[object].alpha.x != ALPHA_OPAQUE {
        return false;
    }
    var to_light = -irr.light.xyz;
    if is_local() {
        to_light = irr.light.xyz - t.a.xyz;
    }
    return dot(cross(t.b.xyz - t.a.xyz, t.c.xyz - t.a.xyz), to_light) <= 0.0;
}

// The sample in `slot`: xyz its shadow-ray origin, w its id (bits).
fn sample_at(slot: u32) -> vec4f {
    if !SUB_PIXEL {
        return bitcast<vec4f>(samples[slot]);
    }
    let id = samples[slot / 4u][slot % 4u];
    let pixel = id / 32u;
    let px = vec2u(pixel % irr.grid.z, pixel / irr.grid.z);
    return vec4f(sample_origin(px, id % 32u, surface(px)), bitcast<f32>(id));
}

// Where sample k of `pixel` sums its optical depth (`BLENDED_TRANSMIT`):
// after the marks, one word per sample.
fn depth_slot(pixel: u32, k: u32) -> u32 {
    return irr.grid.z * irr.grid.w + pixel * max(irr.pixel.x, 1u) + k;
}

// Sample `slot` tested against triangle `t`; whether it needed a test. A
// blocked sample is marked; a translucent crossing adds its optical depth,
// and marks the sample once the sum passes OPAQUE_DEPTH. Only then is a
// marked sample skipped (its sum would grow past the word): elsewhere the
// test costs less than reading its mark first, an atomic that llvmpipe
// runs a lane at a time.
fn test_sample(t: CasterTriangle, slot: u32) -> u32 {
    let sample = sample_at(slot);
    let id = bitcast<u32>(sample.w);
    let pixel = id / 32u;
    let bit = 1u << (id % 32u);
    if TRANSMIT && (atomicLoad(&marks[pixel]) & bit) != 0u {
        return 0u;
    }
    let opacity = opacity_crossed(t, sample.xyz);
    if opacity >= 1.0 {
        atomicOr(&marks[pixel], bit);
    } else if TRANSMIT && opacity > 0.0 {
        let depth = min(-log(1.0 - opacity), OPAQUE_DEPTH);
        let units = u32(round(depth * DEPTH_UNITS));
        let before = atomicAdd(&marks[depth_slot(pixel, id % 32u)], units);
        if f32(before + units) >= OPAQUE_DEPTH * DEPTH_UNITS {
            atomicOr(&marks[pixel], bit);
        }
    }
    return 1u;
}

// The run of `samples` of row y of the box's cells (the row's cells are
// consecutive, so their samples are).
fn row_run(face: u32, box: vec4i, y: i32) -> vec2u {
    let n = irr.work.w;
    let a = atomicLoad(&cells[n + cell_index(face, vec2i(box.x, y))]);
    let b = atomicLoad(&cells[n + cell_index(face, vec2i(box.z, y)) + 1u]);
    return vec2u(a, b);
}

// The samples binned in the box's cells (the triangle's work on a face).
fn box_samples(face: u32, box: vec4i) -> u32 {
    var total = 0u;
    for (var y = box.y; y <= box.w; y++) {
        let run = row_run(face, box, y);
        total += run.y - run.x;
    }
    return total;
}

// The box's samples from the `first`-th to before the `end`-th (in row
// order), every `step`-th, tested against `t`, starting the walk at row
// `y0` before which the box holds `seen0` samples; the tests made.
fn test_samples(t: CasterTriangle, face: u32, box: vec4i, y0: i32, seen0: u32, first: u32,
        end: u32, step: u32) -> u32 {
    var tests = 0u;
    var seen = seen0;
    var k = first;
    for (var y = y0; y <= box.w && k < end; y++) {
        let run = row_run(face, box, y);
        let length = run.y - run.x;
        for (; k < min(seen + length, end); k += step) {
            tests += test_sample(t, run.x + k - seen);
        }
        seen += length;
    }
    return tests;
}

// The job counter of this pass's casters.
fn jobs_word() -> u32 {
    return select(AUX_JOBS, AUX_SEE_THROUGH_JOBS, SEE_THROUGH);
}

// The jobs this pass's casters may list: the whole list for the opaque
// ones (their pass runs first), what they left for the see-through ones.
fn job_room() -> u32 {
    let capacity = irr.work.z;
    if !SEE_THROUGH {
        return capacity;
    }
    return capacity - min(atomicLoad(&aux[AUX_JOBS]), capacity);
}

// The first word of this pass's `slot`-th job: the opaque casters' jobs
// run from the list's start, the see-through ones' from its end.
fn job_word(slot: u32) -> u32 {
    return AUX_JOB_LIST + 4u * select(slot, irr.work.z - 1u - slot, SEE_THROUGH);
}

// Lists the jobs of a triangle's samples on a face (`fitted` of them, from
// list slot `slot`), each with the row its first sample lies in, so that a
// job's threads walk only its own rows.
fn list_jobs(index: u32, face: u32, box: vec4i, slot: u32, fitted: u32) {
    var seen = 0u;
    var job = 0u;
    for (var y = box.y; y <= box.w && job < fitted; y++) {
        let run = row_run(face, box, y);
        let length = run.y - run.x;
        for (; job < fitted && job * JOB_SAMPLES < seen + length; job++) {
            let e = job_word(slot + job);
            atomicStore(&aux[e], index * 8u + face);
            atomicStore(&aux[e + 1u], job);
            atomicStore(&aux[e + 2u], u32(y - box.y));
            atomicStore(&aux[e + 3u], seen);
        }
        seen += length;
    }
}

// The cells' box (x0, y0, x1, y1) of triangle `t`'s image on `face`, empty
// (x1 < x0) where it misses the face's samples. On a local light's face
// the triangle is first clipped to the light's side of the face's plane
// (−z ≥ a hair of its extent): every point between a sample and the light
// lies there and projects onto the sample's own image (Sutherland &
// Hodgman 1974); the clipped polygon's image is clamped to the samples'.
fn triangle_cells(t: CasterTriangle, face: u32, f: FaceBounds) -> vec4i {
    if f.empty {
        return vec4i(0, 0, -1, -1);
    }
    let m = irr.views[face];
    let v = array<vec3f, 3>((m * vec4f(t.a.xyz, 1.0)).xyz, (m * vec4f(t.b.xyz, 1.0)).xyz,
        (m * vec4f(t.c.xyz, 1.0)).xyz);
    var lo = vec2f(3.0e38);
    var hi = vec2f(-3.0e38);
    var kept = 0u;
    let eps = 1e-6 * max(max(length(v[0]), length(v[1])), length(v[2]));
    for (var i = 0u; i < 3u; i++) {
        let a = v[i];
        let b = v[(i + 1u) % 3u];
        let a_in = !is_local() || -a.z >= eps;
        let b_in = !is_local() || -b.z >= eps;
        if a_in {
            let c = clamp(image_of(a), f.lo - 1.0, f.hi + 1.0);
            lo = min(lo, c);
            hi = max(hi, c);
            kept++;
        }
        if a_in != b_in {
            let p = mix(a, b, (-eps - a.z) / (b.z - a.z));
            let c = clamp(image_of(p), f.lo - 1.0, f.hi + 1.0);
            lo = min(lo, c);
            hi = max(hi, c);
            kept++;
        }
    }
    if kept == 0u || any(hi < f.lo) || any(lo > f.hi) {
        return vec4i(0, 0, -1, -1);
    }
    let c0 = clamp_cell(f, cell_of(f, max(lo, f.lo)));
    let c1 = clamp_cell(f, cell_of(f, min(hi, f.hi)));
    return vec4i(c0, c1);
}

const MAX_FACES: u32 = 6u;

// The cube face of a direction `d` from a local light, where its major
// axis exceeds the others by a margin (1/1024 of them), else MAX_FACES.
fn clear_face(d: vec3f) -> u32 {
    let a = abs(d);
    let major = max(a.x, max(a.y, a.z));
    let second = max(min(a.x, a.y), min(max(a.x, a.y), a.z));
    return select(MAX_FACES, cube_face(d), major > second * (1.0 + 1.0 / 1024.0));
}

// The faces triangle `t` may be seen in, as bits: every face of the light,
// or the one face of a local light whose pyramid holds the whole of `t`.
// Where the three vertices lie clear of the same face's edges, so does the
// triangle (the narrowed pyramid is convex), and so does every sample
// whose ray to the light it meets: no rounding bins such a sample on
// another face, whose image the triangle need not be projected into (most
// triangles of a scene: five faces of six saved). Looping over the bits
// set, not over every face, keeps a lane group whose triangles each hold
// one face from stepping through the other five.
fn faces_holding(t: CasterTriangle) -> u32 {
    let every = (1u << irr.grid.x) - 1u;
    if irr.grid.x == 1u {
        return every;
    }
    let l = irr.light.xyz;
    let f = clear_face(t.a.xyz - l);
    if f == MAX_FACES || clear_face(t.b.xyz - l) != f || clear_face(t.c.xyz - l) != f {
        return every;
    }
    return 1u << f;
}

// The triangle-cell pairs and sample tests of one workgroup's threads,
// added to the header once per workgroup (the threads would otherwise
// contend for the same two words).
var<workgroup> group_work: array<atomic<u32>, 2>;

// Adds a thread's (pairs, tests) to the header's counters through its
// workgroup's. Call in uniform control flow (it waits at a barrier).
fn count_work(lane: u32, work: vec2u) {
    if work.x > 0u {
        atomicAdd(&group_work[0], work.x);
    }
    if work.y > 0u {
        atomicAdd(&group_work[1], work.y);
    }
    workgroupBarrier();
    if lane < 2u {
        let total = atomicLoad(&group_work[lane]);
        if total > 0u {
            atomicAdd(&aux[AUX_PAIRS + lane], total);
        }
    }
}

// Triangle `index` on each face it may be seen in: the samples of the cells
// its image covers tested, or, where they are more than `irr.work.y`,
// listed as jobs of JOB_SAMPLES for the job pass. Jobs past the list's
// capacity are counted (AUX_OVERFLOW, in samples) and tested here. Its
// (pairs, tests).
fn triangle_work(index: u32) -> vec2u {
    let t = triangles[index];
    if faces_away_on_a_solid(t) {
        return vec2u(0u);
    }
    var tests = 0u;
    var pairs = 0u;
    var faces = faces_holding(t);
    while faces != 0u {
        let face = firstTrailingBit(faces);
        faces &= faces - 1u;
        let box = triangle_cells(t, face, face_bounds(face));
        if box.z < box.x || box.w < box.y {
            continue;
        }
        pairs += u32(box.z - box.x + 1) * u32(box.w - box.y + 1);
        let work = box_samples(face, box);
        var first = 0u;
        if work > irr.work.y {
            let jobs = (work + JOB_SAMPLES - 1u) / JOB_SAMPLES;
            let slot = atomicAdd(&aux[jobs_word()], jobs);
            let room = job_room();
            let fitted = min(jobs, room - min(slot, room));
            list_jobs(index, face, box, slot, fitted);
            first = min(fitted * JOB_SAMPLES, work);
            if first < work {
                atomicAdd(&aux[AUX_OVERFLOW], work - first);
            }
        }
        tests += test_samples(t, face, box, box.y, 0u, first, work, 1u);
    }
    return vec2u(pairs, tests);
}

// The triangle that thread `i` of a run tests: in the run's kept ranges
// [lo, hi) of `kept_ranges`, the last one whose first thread is at most
// `i` (binary search), and as far into it as `i` is past its start.
fn kept_triangle(i: u32, lo: u32, hi: u32) -> u32 {
    var a = lo;
    var b = hi - 1u;
    while a < b {
        let m = (a + b + 1u) / 2u;
        if kept_ranges[m].x <= i {
            a = m;
        } else {
            b = m - 1u;
        }
    }
    return kept_ranges[a].y + i - kept_ranges[a].x;
}

// Pass 5, a thread per kept caster triangle of this pass's run.
@compute @workgroup_size(64)
fn cs_triangles(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let i = id.y * groups.x * WORKGROUP + id.x;
    let lo = select(0u, irr.kept.x, SEE_THROUGH);
    let hi = select(irr.kept.x, irr.kept.y, SEE_THROUGH);
    var work = vec2u(0u);
    if i < select(irr.kept.z, irr.kept.w, SEE_THROUGH) {
        work = triangle_work(kept_triangle(i, lo, hi));
    }
    count_work(lane, work);
}

// The jobs listed and fitted: the opaque casters' (`opaque`) or the
// see-through ones'.
fn jobs_listed(opaque: bool) -> u32 {
    let capacity = irr.work.z;
    let first = min(atomicLoad(&aux[AUX_JOBS]), capacity);
    if opaque {
        return first;
    }
    return min(atomicLoad(&aux[AUX_SEE_THROUGH_JOBS]), capacity - first);
}

// The (x, y, z) workgroups of a job pass over `count` jobs, at `word`.
fn write_dispatch(word: u32, count: u32) {
    let x = min(count, 65535u);
    atomicStore(&aux[word], x);
    atomicStore(&aux[word + 1u], select(0u, (count + x - 1u) / max(x, 1u), x > 0u));
    atomicStore(&aux[word + 2u], 1u);
}

// Pass 6, one invocation: the job passes' workgroups, one per listed job.
@compute @workgroup_size(1)
fn cs_job_dispatch() {
    write_dispatch(AUX_DISPATCH, jobs_listed(true));
    write_dispatch(AUX_SEE_THROUGH_DISPATCH, jobs_listed(false));
}

// Job `e`'s tests by thread `lane` of its workgroup: every WORKGROUP-th
// of the job's samples from the lane's.
fn job_tests(e: u32, lane: u32) -> u32 {
    let w = job_word(e);
    let entry = atomicLoad(&aux[w]);
    let first = atomicLoad(&aux[w + 1u]) * JOB_SAMPLES;
    let t = triangles[entry / 8u];
    let face = entry % 8u;
    let box = triangle_cells(t, face, face_bounds(face));
    let y0 = box.y + i32(atomicLoad(&aux[w + 2u]));
    let seen0 = atomicLoad(&aux[w + 3u]);
    return test_samples(t, face, box, y0, seen0, first + lane, first + JOB_SAMPLES, WORKGROUP);
}

// Pass 7, a workgroup per job of this pass's casters: its threads share
// the job's samples.
@compute @workgroup_size(64)
fn cs_jobs(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let e = group.y * groups.x + group.x;
    var tests = 0u;
    if e < jobs_listed(!SEE_THROUGH) {
        tests = job_tests(e, lane);
    }
    count_work(lane, vec2u(0u, tests));
}

// Pass 8, per pixel: the mask, the mean of its samples' light: 0 where a
// caster blocks the sample, else the transmittance of the translucent
// casters it crossed (1 without `BLENDED_TRANSMIT`).
@fragment
fn fs_mask(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let pixel = px.y * irr.grid.z + px.x;
    let count = max(irr.pixel.x, 1u);
    let blocked = atomicLoad(&marks[pixel]);
    if irr.pixel.y != BLENDED_TRANSMIT {
        return vec4f(1.0 - f32(countOneBits(blocked)) / f32(count));
    }
    var light = 0.0;
    for (var k = 0u; k < count; k++) {
        if (blocked & (1u << k)) == 0u {
            light += exp(-f32(atomicLoad(&marks[depth_slot(pixel, k)])) / DEPTH_UNITS);
        }
    }
    return vec4f(light / f32(count));
}
