// The irregular z-buffer (Johnson, Mark & Burns 2005; Aila & Laine 2004;
// Sintorn, Eisemann & Assarsson 2008): the camera's own samples are binned
// into a light-space grid, each caster triangle visits the cells its image
// covers and tests the samples listed there exactly, and the mask is 0
// where a triangle blocks a sample's ray to the light. common.wgsl and
// gbuffer.wgsl are prepended.

struct Irregular {
    // world → light view of each face: six cube faces for point and spot
    // lights, one orthographic view for directional ones
    views: array<mat4x4f, 6>,
    // xyz the light's position (local lights) or the direction it travels
    // (directional), w 1 for a local light
    light: vec4f,
    // x faces, y grid side R (cells per face side), z frame width, w frame
    // height
    grid: vec4u,
    // x caster triangles, y samples above which a triangle is left to the
    // job pass, z the job list's capacity, w the cells (faces · R²)
    work: vec4u,
    // x ray-origin offset in ULPs (the reference's rule), yzw unused
    offset: vec4f,
    // x samples per pixel (1: its centre; up to 32, one mark bit each), yzw
    // unused
    pixel: vec4u,
};

struct CasterTriangle {
    // xyz world positions, w the vertex's u
    a: vec4f,
    b: vec4f,
    c: vec4f,
    // xyz the vertices' v, w the object (bits)
    v: vec4f,
};

@group(2) @binding(0) var<uniform> irr: Irregular;
// The binning's words, three arrays in one buffer (N = irr.work.w cells,
// face-major, row-major): [0, N) each cell's sample count (then the
// scatter's cursor, back to 0 when it is done); [N, 2N] the exclusive
// prefix sum of the counts, the first sample of each cell in `samples`
// (its last word the total); then the prefix sum's per-block partials.
@group(2) @binding(1) var<storage, read_write> cells: array<atomic<u32>>;
// The samples sorted by cell, so a cell's, and a row of cells', samples
// are contiguous. Each is identified by its pixel · 32 plus its index
// within the pixel. One sample per pixel: four words, the shadow-ray
// origin's xyz (bits) and the id. Sub-pixel samples: the id alone, the
// origin found again from the G-buffer (4 bytes a sample, so that 16 of
// them for a 1280 × 720 frame fit one storage buffer).
@group(2) @binding(2) var<storage, read_write> samples: array<u32>;
// Per pixel: bit k set once a caster blocks its sample k.
@group(2) @binding(3) var<storage, read_write> marks: array<atomic<u32>>;
@group(2) @binding(4) var<storage, read> triangles: array<CasterTriangle>;
// The header (AUX_* words: counters, list-length histogram, per-face bounds)
// and then the job list.
@group(2) @binding(5) var<storage, read_write> aux: array<atomic<u32>>;

const AUX_SAMPLES: u32 = 0u;
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
// The jobs, four words each: triangle · 8 + face, job, the box row its
// first sample lies in, the box's samples before that row.
const AUX_JOB_LIST: u32 = 80u;
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

// The G-buffer's surface at a pixel: position, unit normal, whether there
// is one.
struct Surface {
    p: vec3f,
    n: vec3f,
    seen: bool,
};

fn surface(px: vec2u) -> Surface {
    let pos = textureLoad(gbuffer_position, px, 0);
    var s: Surface;
    s.seen = pos.w >= 0.5;
    s.p = pos.xyz;
    s.n = normalize(textureLoad(gbuffer_normal, px, 0).xyz);
    return s;
}

// Sub-pixel sample `k` of `count` within a pixel, in [0, 1)²: Hammersley
// (x stratified, y the base-2 radical inverse), centred in its strata;
// the twin of the reference's `pixel_sample_offset`.
fn pixel_sample_offset(k: u32, count: u32) -> vec2f {
    let n = f32(count);
    return vec2f((f32(k) + 0.5) / n, f32(reverseBits(k)) * 2.3283064e-10 + 0.5 / n);
}

// The reference's PLANE_LIFT: how far a sub-pixel sample is lifted off
// its pixel's plane, per unit of its distance from the pixel's centre.
const PLANE_LIFT: f32 = 0.25;

// Where sample `k` of pixel `px` lies on the surface's plane: the camera
// ray through it met with the plane, written relative to the surface point,
// lifted off the plane by PLANE_LIFT of its distance from the centre (the
// twin of the reference's `pixel_sample_point`, which says why).
fn sub_sample_point(px: vec2u, k: u32, s: Surface) -> vec3f {
    let count = irr.pixel.x;
    if count <= 1u {
        return s.p;
    }
    let uv = (vec2f(px) + pixel_sample_offset(k, count)) / frame.size.xy;
    let ndc = vec2f(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let a = frame.inv_view_proj * vec4f(ndc, 0.0, 1.0);
    let b = frame.inv_view_proj * vec4f(ndc, 0.5, 1.0);
    let near = a.xyz / a.w;
    let d = normalize(b.xyz / b.w - near);
    let along = dot(d, s.n);
    if abs(along) < 1e-6 {
        return s.p;
    }
    let to_near = near - s.p;
    let q = s.p + to_near - d * (dot(to_near, s.n) / along);
    return q + s.n * (PLANE_LIFT * length(q - s.p));
}

// The shadow-ray origin of sample `k` of the pixel's surface.
fn sample_origin(px: vec2u, k: u32, s: Surface) -> vec3f {
    return offset_origin(sub_sample_point(px, k, s), s.n, irr.offset.x);
}

// The cube face a direction from a local light falls in (+x, −x, +y, −y,
// +z, −z), or 0 for a directional light.
fn face_of(p: vec3f) -> u32 {
    if !is_local() {
        return 0u;
    }
    return cube_face(p - irr.light.xyz);
}

// Where a light-view point lands in its face's image: (x, y) of an
// orthographic view, (x, y) / −z of a perspective one.
fn image_of(v: vec3f) -> vec2f {
    if is_local() {
        return v.xy / max(-v.z, 1e-30);
    }
    return v.xy;
}

// A face's samples: their images' bounds.
struct FaceBounds {
    lo: vec2f,
    hi: vec2f,
    empty: bool,
};

fn face_bounds(face: u32) -> FaceBounds {
    let b = AUX_BOUNDS + face * 4u;
    var f: FaceBounds;
    let hx = atomicLoad(&aux[b + 2u]);
    f.empty = hx == 0u;
    f.lo = vec2f(from_ordered(~atomicLoad(&aux[b])), from_ordered(~atomicLoad(&aux[b + 1u])));
    f.hi = vec2f(from_ordered(hx), from_ordered(atomicLoad(&aux[b + 3u])));
    return f;
}

// The grid cell (x, y) of an image point in `f`, unclamped.
fn cell_of(f: FaceBounds, c: vec2f) -> vec2i {
    let r = f32(irr.grid.y);
    let extent = max(f.hi - f.lo, vec2f(1e-30));
    return vec2i(floor((c - f.lo) / extent * r));
}

fn clamp_cell(c: vec2i) -> vec2i {
    return clamp(c, vec2i(0), vec2i(i32(irr.grid.y) - 1));
}

fn cell_index(face: u32, c: vec2i) -> u32 {
    let r = irr.grid.y;
    return (face * r + u32(c.y)) * r + u32(c.x);
}

// Pass 1, per pixel: the bounds of the samples' images on each face.
@fragment
fn fs_bounds(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let s = surface(px);
    for (var k = 0u; s.seen && k < irr.pixel.x; k++) {
        let o = sample_origin(px, k, s);
        let face = face_of(o);
        let v = (irr.views[face] * vec4f(o, 1.0)).xyz;
        if !is_local() || v.z < 0.0 {
            let c = image_of(v);
            let b = AUX_BOUNDS + face * 4u;
            atomicMax(&aux[b], ~ordered(c.x));
            atomicMax(&aux[b + 1u], ~ordered(c.y));
            atomicMax(&aux[b + 2u], ordered(c.x));
            atomicMax(&aux[b + 3u], ordered(c.y));
        }
    }
    return vec4f(1.0);
}

// The cell sample `k` of a seen pixel is binned in, or N (irr.work.w)
// where it lies behind a local light's face.
struct Binned {
    origin: vec3f,
    cell: u32,
};

fn binned(px: vec2u, k: u32, s: Surface) -> Binned {
    var b: Binned;
    b.cell = irr.work.w;
    let o = sample_origin(px, k, s);
    let face = face_of(o);
    let v = (irr.views[face] * vec4f(o, 1.0)).xyz;
    if !is_local() || v.z < 0.0 {
        b.origin = o;
        b.cell = cell_index(face, clamp_cell(cell_of(face_bounds(face), image_of(v))));
    }
    return b;
}

// Pass 2, per pixel: each cell's samples counted.
@fragment
fn fs_count(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let s = surface(px);
    for (var k = 0u; s.seen && k < irr.pixel.x; k++) {
        let b = binned(px, k, s);
        if b.cell < irr.work.w {
            atomicAdd(&cells[b.cell], 1u);
            atomicAdd(&aux[AUX_SAMPLES], 1u);
        }
    }
    return vec4f(1.0);
}

// Pass 3a, a workgroup per block of SCAN_BLOCK counts: their exclusive
// prefix sum (each thread sums 16 serially, then adds the threads before
// it), the block's total kept for pass 3b.
var<workgroup> thread_sums: array<u32, 64>;

@compute @workgroup_size(64)
fn cs_scan_blocks(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let n = irr.work.w;
    let block = group.y * groups.x + group.x;
    let per = SCAN_BLOCK / WORKGROUP;
    let first = block * SCAN_BLOCK + lane * per;
    var sum = 0u;
    for (var k = 0u; k < per; k++) {
        if first + k < n {
            sum += atomicLoad(&cells[first + k]);
        }
    }
    thread_sums[lane] = sum;
    workgroupBarrier();
    var before = 0u;
    for (var k = 0u; k < lane; k++) {
        before += thread_sums[k];
    }
    for (var k = 0u; k < per; k++) {
        if first + k < n {
            atomicStore(&cells[n + first + k], before);
            before += atomicLoad(&cells[first + k]);
        }
    }
    if lane == WORKGROUP - 1u && block * SCAN_BLOCK < n {
        atomicStore(&cells[2u * n + 1u + block], before);
    }
}

// Pass 3b, one workgroup: the blocks' totals turned into their exclusive
// prefix sum (each thread a contiguous run of them), the grand total
// written after the last cell's offset.
@compute @workgroup_size(64)
fn cs_scan_partials(@builtin(local_invocation_index) lane: u32) {
    let n = irr.work.w;
    let blocks = (n + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    let per = (blocks + WORKGROUP - 1u) / WORKGROUP;
    let base = 2u * n + 1u;
    let first = lane * per;
    let last = min(first + per, blocks);
    var sum = 0u;
    for (var k = first; k < last; k++) {
        sum += atomicLoad(&cells[base + k]);
    }
    thread_sums[lane] = sum;
    workgroupBarrier();
    var before = 0u;
    for (var k = 0u; k < lane; k++) {
        before += thread_sums[k];
    }
    for (var k = first; k < last; k++) {
        let total = atomicLoad(&cells[base + k]);
        atomicStore(&cells[base + k], before);
        before += total;
    }
    if lane == WORKGROUP - 1u {
        atomicStore(&cells[2u * n], before);
    }
}

// The histogram's bin of a list length n ≥ 1: n itself below 16, then one
// bin per octave ([16, 32) is bin 16), the last one open.
fn histogram_bin(n: u32) -> u32 {
    if n < 16u {
        return n;
    }
    return min(12u + firstLeadingBit(n), HISTOGRAM_BINS - 1u);
}

// Pass 3c, per cell: its block's partial added to its offset, and its list
// length counted into the histogram.
@compute @workgroup_size(64)
fn cs_scan_add(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let n = irr.work.w;
    let cell = id.y * groups.x * WORKGROUP + id.x;
    if cell >= n {
        return;
    }
    let partial = atomicLoad(&cells[2u * n + 1u + cell / SCAN_BLOCK]);
    atomicAdd(&cells[n + cell], partial);
    let length = atomicLoad(&cells[cell]);
    if length > 0u {
        atomicAdd(&aux[AUX_HISTOGRAM + histogram_bin(length)], 1u);
        atomicMax(&aux[AUX_LONGEST], length);
    }
}

// Pass 4, per pixel: its samples written to their cells' runs of `samples`.
@fragment
fn fs_scatter(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let s = surface(px);
    let pixel = px.y * irr.grid.z + px.x;
    for (var k = 0u; s.seen && k < irr.pixel.x; k++) {
        let b = binned(px, k, s);
        if b.cell < irr.work.w {
            let left = atomicSub(&cells[b.cell], 1u);
            let slot = atomicLoad(&cells[irr.work.w + b.cell]) + left - 1u;
            let id = pixel * 32u + k;
            if irr.pixel.x <= 1u {
                let o = bitcast<vec3u>(b.origin);
                samples[4u * slot] = o.x;
                samples[4u * slot + 1u] = o.y;
                samples[4u * slot + 2u] = o.z;
                samples[4u * slot + 3u] = id;
            } else {
                samples[slot] = id;
            }
        }
    }
    return vec4f(1.0);
}

// Whether triangle `t` blocks the ray from `o` to the light (Möller &
// Trumbore 1997), through a hole of a cut-out (alpha-tested at full
// resolution, blended casters cut at ½, as the reference's cut-outs).
fn blocks(t: CasterTriangle, o: vec3f) -> bool {
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
        return false;
    }
    let inv = 1.0 / det;
    let s = o - t.a.xyz;
    let u = dot(s, p) * inv;
    if u < 0.0 || u > 1.0 {
        return false;
    }
    let q = cross(s, e1);
    let w = dot(d, q) * inv;
    if w < 0.0 || u + w > 1.0 {
        return false;
    }
    let hit = dot(e2, q) * inv;
    if hit <= 0.0 || hit >= t_max {
        return false;
    }
    let object = bitcast<u32>(t.v.w);
    if objects[object].alpha.x == ALPHA_OPAQUE {
        return true;
    }
    let uv = vec2f(t.a.w, t.v.x) * (1.0 - u - w) + vec2f(t.b.w, t.v.y) * u + vec2f(t.c.w, t.v.z) * w;
    return is_solid_at(object, uv, 0.0, 0.5);
}

// The sample in `slot`: xyz its shadow-ray origin, w its id (bits).
fn sample_at(slot: u32) -> vec4f {
    if irr.pixel.x <= 1u {
        let w = 4u * slot;
        let o = vec3u(samples[w], samples[w + 1u], samples[w + 2u]);
        return vec4f(bitcast<vec3f>(o), bitcast<f32>(samples[w + 3u]));
    }
    let id = samples[slot];
    let pixel = id / 32u;
    let px = vec2u(pixel % irr.grid.z, pixel / irr.grid.z);
    return vec4f(sample_origin(px, id % 32u, surface(px)), bitcast<f32>(id));
}

// Sample `slot` tested against triangle `t`; whether it needed a test.
fn test_sample(t: CasterTriangle, slot: u32) -> u32 {
    let sample = sample_at(slot);
    let id = bitcast<u32>(sample.w);
    let pixel = id / 32u;
    let bit = 1u << (id % 32u);
    if (atomicLoad(&marks[pixel]) & bit) != 0u {
        return 0u;
    }
    if blocks(t, sample.xyz) {
        atomicOr(&marks[pixel], bit);
    }
    return 1u;
}

// The run of `samples` of row y of the box's cells.
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
            let e = AUX_JOB_LIST + 4u * (slot + job);
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
    let c0 = clamp_cell(cell_of(f, max(lo, f.lo)));
    let c1 = clamp_cell(cell_of(f, min(hi, f.hi)));
    return vec4i(c0, c1);
}

// Pass 5, per triangle: on every face the samples of the cells its image
// covers tested, or, where they are more than `irr.work.y`, listed as jobs
// of JOB_SAMPLES for the job pass. Jobs past the list's capacity are
// counted (AUX_OVERFLOW, in samples) and tested here.
@compute @workgroup_size(64)
fn cs_triangles(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let index = id.y * groups.x * WORKGROUP + id.x;
    if index >= irr.work.x {
        return;
    }
    let t = triangles[index];
    var tests = 0u;
    var pairs = 0u;
    for (var face = 0u; face < irr.grid.x; face++) {
        let box = triangle_cells(t, face, face_bounds(face));
        if box.z < box.x || box.w < box.y {
            continue;
        }
        pairs += u32(box.z - box.x + 1) * u32(box.w - box.y + 1);
        let work = box_samples(face, box);
        var first = 0u;
        if work > irr.work.y {
            let jobs = (work + JOB_SAMPLES - 1u) / JOB_SAMPLES;
            let slot = atomicAdd(&aux[AUX_JOBS], jobs);
            let fitted = min(jobs, irr.work.z - min(slot, irr.work.z));
            list_jobs(index, face, box, slot, fitted);
            first = min(fitted * JOB_SAMPLES, work);
            if first < work {
                atomicAdd(&aux[AUX_OVERFLOW], work - first);
            }
        }
        tests += test_samples(t, face, box, box.y, 0u, first, work, 1u);
    }
    if pairs > 0u {
        atomicAdd(&aux[AUX_PAIRS], pairs);
        atomicAdd(&aux[AUX_TESTS], tests);
    }
}

// Pass 6, one invocation: the job pass's workgroups, one per listed job.
@compute @workgroup_size(1)
fn cs_job_dispatch() {
    let count = min(atomicLoad(&aux[AUX_JOBS]), irr.work.z);
    let x = min(count, 65535u);
    atomicStore(&aux[AUX_DISPATCH], x);
    atomicStore(&aux[AUX_DISPATCH + 1u], select(0u, (count + x - 1u) / max(x, 1u), x > 0u));
    atomicStore(&aux[AUX_DISPATCH + 2u], 1u);
}

// Pass 7, a workgroup per job: its threads share the job's samples.
@compute @workgroup_size(64)
fn cs_jobs(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let e = group.y * groups.x + group.x;
    if e >= min(atomicLoad(&aux[AUX_JOBS]), irr.work.z) {
        return;
    }
    let w = AUX_JOB_LIST + 4u * e;
    let entry = atomicLoad(&aux[w]);
    let first = atomicLoad(&aux[w + 1u]) * JOB_SAMPLES;
    let t = triangles[entry / 8u];
    let face = entry % 8u;
    let box = triangle_cells(t, face, face_bounds(face));
    let y0 = box.y + i32(atomicLoad(&aux[w + 2u]));
    let seen0 = atomicLoad(&aux[w + 3u]);
    let tests = test_samples(t, face, box, y0, seen0, first + lane, first + JOB_SAMPLES, WORKGROUP);
    if tests > 0u {
        atomicAdd(&aux[AUX_TESTS], tests);
    }
}

// Pass 8, per pixel: the mask, the fraction of its samples no caster blocks.
@fragment
fn fs_mask(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let blocked = countOneBits(atomicLoad(&marks[px.y * irr.grid.z + px.x]));
    return vec4f(1.0 - f32(blocked) / f32(max(irr.pixel.x, 1u)));
}
