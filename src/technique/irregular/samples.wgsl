// The irregular z-buffer's samples (composed with irregular.wgsl): each
// pixel's sample points (its centre, or sub-pixel points on its surface
// plane), their bounds on each light face, and their binning into the
// light-space grid by count, prefix sum and scatter.

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
    if !SUB_PIXEL {
        return s.p;
    }
    let count = irr.pixel.x;
    let q = camera_ray_on_plane(vec2f(px) + pixel_sample_offset(k, count), s.p, s.n);
    return q + s.n * (PLANE_LIFT * length(q - s.p));
}

// How far a pixel's ray origins are lifted off its surface `s` besides
// the ULP offset: `offset_footprint` (irr.offset.z) of its footprint on
// the surface, its width across the camera ray over the cosine between
// the ray and the normal (at least MIN_FOOTPRINT_COSINE, prepended from
// the reference's); the twin of the reference's `footprint_lift`.
fn footprint_lift(s: Surface) -> f32 {
    let to_p = s.p - frame.camera_pos.xyz;
    let distance = length(to_p);
    let cot_half_fov = frame.proj[1][1];
    if irr.offset.z <= 0.0 || distance <= 0.0 || cot_half_fov <= 0.0 {
        return 0.0;
    }
    let cosine = max(abs(dot(to_p, s.n)) / distance, MIN_FOOTPRINT_COSINE);
    return irr.offset.z * distance * (2.0 / (cot_half_fov * frame.size.y)) / cosine;
}

// The shadow-ray origin of sample `k` of the pixel's surface.
fn sample_origin(px: vec2u, k: u32, s: Surface) -> vec3f {
    let lifted = sub_sample_point(px, k, s) + s.n * footprint_lift(s);
    return offset_origin(lifted, s.n, irr.offset.x);
}

// Whether the light reaches the sample at `o` on a surface with normal
// `n` at all (the reference's rule): its ray to the light leaves above the
// surface's plane (below it the surface itself hides the light), inside a
// spot's outer cone and within the range. Elsewhere the sample is marked
// shadowed and not binned.
fn light_reaches(o: vec3f, n: vec3f) -> bool {
    let to_light = select(-irr.light.xyz, irr.light.xyz - o, is_local());
    if dot(to_light, n) <= 0.0 {
        return false;
    }
    if !is_local() {
        return true;
    }
    let d = length(to_light);
    return dot(-to_light / d, irr.cone.xyz) > irr.cone.w && (irr.offset.y <= 0.0 || d < irr.offset.y);
}

// The cube face a direction from a local light falls in (+x, −x, +y, −y,
// +z, −z), or 0 for a light of one face (directional, or a spot along its
// axis).
fn face_of(p: vec3f) -> u32 {
    if irr.grid.x == 1u {
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

// A face's samples: their images' bounds, and the cells per side of its
// grid over them.
struct FaceBounds {
    lo: vec2f,
    hi: vec2f,
    side: u32,
    empty: bool,
};

// A face's bounds and grid, from their copy (`face_boxes`) once the bounds
// and layout passes have found them.
fn face_bounds(face: u32) -> FaceBounds {
    let b = face_boxes[face];
    var f: FaceBounds;
    f.empty = b.z == 0u;
    f.lo = vec2f(from_ordered(~b.x), from_ordered(~b.y));
    f.hi = vec2f(from_ordered(b.z), from_ordered(b.w));
    f.side = face_boxes[MAX_FACES + face].x;
    return f;
}

// The grid cell (x, y) of an image point in `f`, unclamped.
fn cell_of(f: FaceBounds, c: vec2f) -> vec2i {
    let r = f32(f.side);
    let extent = max(f.hi - f.lo, vec2f(1e-30));
    return vec2i(floor((c - f.lo) / extent * r));
}

fn clamp_cell(f: FaceBounds, c: vec2i) -> vec2i {
    return clamp(c, vec2i(0), vec2i(i32(f.side) - 1));
}

// Cell (x, y) of a face: the faces' grids follow one another, each
// row-major.
fn cell_index(face: u32, c: vec2i) -> u32 {
    let grid = face_boxes[MAX_FACES + face];
    return grid.y + u32(c.y) * grid.x + u32(c.x);
}

// The cells the faces' grids use, of the N the buffer holds.
fn cells_used() -> u32 {
    return face_boxes[MAX_FACES].z;
}

// aux[word] raised to `value`, read first: after the first samples few
// raise a bound, and a read does not contend for the word as a write does.
fn raise(word: u32, value: u32) {
    if value > atomicLoad(&aux[word]) {
        atomicMax(&aux[word], value);
    }
}

// One sample per pixel: pass 1 keeps each pixel's sample in `samples`
// past the sorted ones (`staged_slot`), as its origin's bits and in w its
// face, or NOT_BINNED; pass 2 replaces the face by the face in the top 3
// bits and the sample's rank in its cell below, and pass 4 moves it to its
// cell's run. The G-buffer is read and the origin found once, not thrice.
const NOT_BINNED: u32 = 0xffffffffu;
const RANK_BITS: u32 = 29u;

fn staged_slot(pixel: u32) -> u32 {
    return irr.grid.z * irr.grid.w + pixel;
}

// The face the sample at `o` falls in and the point in that face's view;
// whether it lies in front of the face (every point does for a
// directional light).
struct FacePoint {
    face: u32,
    v: vec3f,
    in_front: bool,
};

fn face_point(o: vec3f) -> FacePoint {
    var f: FacePoint;
    f.face = face_of(o);
    f.v = view_point(f.face, o);
    f.in_front = !is_local() || f.v.z < 0.0;
    return f;
}

// The point `o` in the view of `face`.
fn view_point(face: u32, o: vec3f) -> vec3f {
    return (irr.views[face] * vec4f(o, 1.0)).xyz;
}

// The cell of the sample at `v` in the view of `face`.
fn cell_at(face: u32, v: vec3f) -> u32 {
    let f = face_bounds(face);
    return cell_index(face, clamp_cell(f, cell_of(f, image_of(v))));
}

// A run of samples on one face: their images' bounds and count.
struct FaceRun {
    face: u32,
    lo: vec2f,
    hi: vec2f,
    count: u32,
};

// The run's bounds raised into the header's and its count added to its
// face's.
fn add_face_run(r: FaceRun) {
    if r.count == 0u {
        return;
    }
    let b = AUX_BOUNDS + r.face * 4u;
    raise(b, ~ordered(r.lo.x));
    raise(b + 1u, ~ordered(r.lo.y));
    raise(b + 2u, ordered(r.hi.x));
    raise(b + 3u, ordered(r.hi.y));
    atomicAdd(&aux[AUX_FACE_SAMPLES + r.face], r.count);
}

// Pass 1, a thread per run of BOUNDS_RUN pixels along a row (prepended
// from gpu.rs): the bounds of the samples' images on each face, and the
// samples each face holds, gathered in registers while the samples stay
// on one face and added to the header when they leave it (a global atomic
// per sample would contend for the header's few words); samples the light
// does not reach marked (and not binned); one sample per pixel staged.
@compute @workgroup_size(64)
fn cs_bounds(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let runs_per_row = (irr.grid.z + BOUNDS_RUN - 1u) / BOUNDS_RUN;
    let run = id.y * groups.x * WORKGROUP + id.x;
    let y = run / runs_per_row;
    if y >= irr.grid.w {
        return;
    }
    let x0 = (run % runs_per_row) * BOUNDS_RUN;
    var r = FaceRun(0u, vec2f(0.0), vec2f(0.0), 0u);
    for (var x = x0; x < min(x0 + BOUNDS_RUN, irr.grid.z); x++) {
        let px = vec2u(x, y);
        let pixel = y * irr.grid.z + x;
        let s = surface(px);
        var staged = vec4u(0u, 0u, 0u, NOT_BINNED);
        for (var k = 0u; s.seen && k < samples_per_pixel(); k++) {
            let o = sample_origin(px, k, s);
            if !light_reaches(o, s.n) {
                atomicOr(&marks[pixel], 1u << k);
                continue;
            }
            let f = face_point(o);
            if f.in_front {
                let c = image_of(f.v);
                if f.face != r.face || r.count == 0u {
                    add_face_run(r);
                    r = FaceRun(f.face, c, c, 0u);
                }
                r.lo = min(r.lo, c);
                r.hi = max(r.hi, c);
                r.count += 1u;
                staged = vec4u(bitcast<vec3u>(o), f.face);
            }
        }
        if !SUB_PIXEL {
            samples[staged_slot(pixel)] = staged;
        }
    }
    add_face_run(r);
}

// Pass 1b, one invocation: each face's grid. A side asked for (`grid`) is
// every face's; else a face's side is fitted to its samples, so that it
// has about `irr.offset.w` cells per sample (a point light's samples
// crowd onto one or two of its six faces, whose cells they need; an empty
// face takes none). The faces' grids follow one another in the buffer's
// N cells; a face never takes the cells the faces after it need, one at
// least (mod.rs sizes N for the fitted sides).
@compute @workgroup_size(1)
fn cs_face_layout() {
    let faces = irr.grid.x;
    var first = 0u;
    for (var face = 0u; face < faces; face++) {
        let n = atomicLoad(&aux[AUX_FACE_SAMPLES + face]);
        var side = irr.grid.y;
        if side == 0u {
            side = select(0u, u32(ceil(sqrt(f32(n) * irr.offset.w))), n > 0u);
            let room = irr.work.w - first - (faces - 1u - face);
            side = clamp(side, min(n, 1u), u32(sqrt(f32(room))));
            if side * side > room {
                side -= 1u;
            }
        }
        let w = AUX_LAYOUT + face * 4u;
        atomicStore(&aux[w], side);
        atomicStore(&aux[w + 1u], first);
        first += side * side;
    }
    for (var face = 0u; face < faces; face++) {
        atomicStore(&aux[AUX_LAYOUT + face * 4u + 2u], first);
    }
}

// The cell sample `k` of a seen pixel is binned in, or N (irr.work.w)
// where it lies behind a local light's face or the light does not reach
// it (sub-pixel samples, found again from the G-buffer).
fn binned_cell(px: vec2u, k: u32, s: Surface) -> u32 {
    let o = sample_origin(px, k, s);
    let f = face_point(o);
    if !light_reaches(o, s.n) || !f.in_front {
        return irr.work.w;
    }
    return cell_at(f.face, f.v);
}

// Pass 2, per pixel: each cell's samples counted (a staged sample keeps
// its rank).
@fragment
fn fs_count(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    if !SUB_PIXEL {
        let slot = staged_slot(px.y * irr.grid.z + px.x);
        let staged = samples[slot];
        if staged.w != NOT_BINNED {
            let v = view_point(staged.w, bitcast<vec3f>(staged.xyz));
            let rank = atomicAdd(&cells[cell_at(staged.w, v)], 1u);
            samples[slot].w = (staged.w << RANK_BITS) | rank;
        }
        return vec4f(1.0);
    }
    let s = surface(px);
    for (var k = 0u; s.seen && k < samples_per_pixel(); k++) {
        let cell = binned_cell(px, k, s);
        if cell < irr.work.w {
            atomicAdd(&cells[cell], 1u);
        }
    }
    return vec4f(1.0);
}

// Each thread's sum of its run, for the threads after it (passes 3a, 3b).
var<workgroup> thread_sums: array<u32, 64>;

// The workgroup's exclusive prefix sum of `cells[start, end)`, written at
// `dst_offset` past each word: each thread sums its run of `per` words
// serially, adds the sums of the threads before it, and writes its run.
// Returns the running sum past this thread's run (the whole range's total
// in the last thread). Call in uniform control flow (it waits at a
// barrier).
fn scan_in_workgroup(lane: u32, start: u32, end: u32, per: u32, dst_offset: u32) -> u32 {
    let first = min(start + lane * per, end);
    let last = min(first + per, end);
    var sum = 0u;
    for (var k = first; k < last; k++) {
        sum += atomicLoad(&cells[k]);
    }
    thread_sums[lane] = sum;
    workgroupBarrier();
    var before = 0u;
    for (var k = 0u; k < lane; k++) {
        before += thread_sums[k];
    }
    for (var k = first; k < last; k++) {
        let count = atomicLoad(&cells[k]);
        atomicStore(&cells[k + dst_offset], before);
        before += count;
    }
    return before;
}

// Pass 3a, a workgroup per block of SCAN_BLOCK counts: their exclusive
// prefix sum (16 counts a thread), the block's total kept for pass 3b.
@compute @workgroup_size(64)
fn cs_scan_blocks(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let n = irr.work.w;
    let block = group.y * groups.x + group.x;
    let start = min(block * SCAN_BLOCK, n);
    if start > cells_used() {
        // Past the faces' grids every count is 0 and no offset is read.
        if lane == 0u && start < n {
            atomicStore(&cells[2u * n + 1u + block], 0u);
        }
        return;
    }
    let total = scan_in_workgroup(lane, start, min(start + SCAN_BLOCK, n), SCAN_BLOCK / WORKGROUP, n);
    if lane == WORKGROUP - 1u && start < n {
        atomicStore(&cells[2u * n + 1u + block], total);
    }
}

// Pass 3b, one workgroup: the blocks' totals turned into their exclusive
// prefix sum (each thread a contiguous run of them), the grand total
// written after the last cell's offset and as the samples binned.
@compute @workgroup_size(64)
fn cs_scan_partials(@builtin(local_invocation_index) lane: u32) {
    let n = irr.work.w;
    let blocks = (n + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    let per = (blocks + WORKGROUP - 1u) / WORKGROUP;
    let base = 2u * n + 1u;
    let total = scan_in_workgroup(lane, base, base + blocks, per, 0u);
    if lane == WORKGROUP - 1u {
        atomicStore(&cells[2u * n], total);
        atomicStore(&aux[AUX_SAMPLES], total);
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

// The list-length histogram and longest list of one workgroup's cells,
// added to the header once per workgroup (not once per cell: every cell
// would contend for the same few words).
var<workgroup> block_histogram: array<atomic<u32>, HISTOGRAM_BINS>;
var<workgroup> block_longest: atomic<u32>;

// Pass 3c, a workgroup per block of SCAN_BLOCK cells: each cell's block
// partial added to its offset, and its list length counted into the
// histogram.
@compute @workgroup_size(64)
fn cs_scan_add(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let n = irr.work.w;
    let block = group.y * groups.x + group.x;
    let start = min(block * SCAN_BLOCK, n);
    if start > cells_used() {
        return;
    }
    let end = min(start + SCAN_BLOCK, n);
    let partial = atomicLoad(&cells[2u * n + 1u + block]);
    for (var cell = start + lane; cell < end; cell += WORKGROUP) {
        let offset = atomicLoad(&cells[n + cell]);
        atomicStore(&cells[n + cell], offset + partial);
        let length = atomicLoad(&cells[cell]);
        if length > 0u {
            atomicAdd(&block_histogram[histogram_bin(length)], 1u);
            atomicMax(&block_longest, length);
        }
    }
    workgroupBarrier();
    if lane < HISTOGRAM_BINS {
        let count = atomicLoad(&block_histogram[lane]);
        if count > 0u {
            atomicAdd(&aux[AUX_HISTOGRAM + lane], count);
        }
    }
    if lane == 0u {
        raise(AUX_LONGEST, atomicLoad(&block_longest));
    }
}

// Pass 4, per pixel: its samples written to their cells' runs of `samples`
// (a staged sample at its rank; sub-pixel samples from the end of their
// cell's run down).
@fragment
fn fs_scatter(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let pixel = px.y * irr.grid.z + px.x;
    if !SUB_PIXEL {
        let staged = samples[staged_slot(pixel)];
        if staged.w != NOT_BINNED {
            let face = staged.w >> RANK_BITS;
            let cell = cell_at(face, view_point(face, bitcast<vec3f>(staged.xyz)));
            let rank = staged.w & ((1u << RANK_BITS) - 1u);
            let slot = atomicLoad(&cells[irr.work.w + cell]) + rank;
            samples[slot] = vec4u(staged.xyz, pixel * 32u);
        }
        return vec4f(1.0);
    }
    let s = surface(px);
    for (var k = 0u; s.seen && k < samples_per_pixel(); k++) {
        let cell = binned_cell(px, k, s);
        if cell < irr.work.w {
            let left = atomicSub(&cells[cell], 1u);
            let slot = atomicLoad(&cells[irr.work.w + cell]) + left - 1u;
            samples[slot / 4u][slot % 4u] = pixel * 32u + k;
        }
    }
    return vec4f(1.0);
}
