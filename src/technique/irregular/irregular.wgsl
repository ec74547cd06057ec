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
    // x caster triangles, y cells above which a triangle is left to the
    // large-triangle pass, z the large list's capacity in chunks, w unused
    work: vec4u,
    // x ray-origin offset in ULPs (the reference's rule), yzw unused
    offset: vec4f,
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
// Per cell (face-major, row-major): the first sample listed there plus 1 (0: none).
@group(2) @binding(1) var<storage, read_write> heads: array<atomic<u32>>;
// Per sample (pixel index): xyz its shadow-ray origin, w the next sample in
// its cell's list plus 1 (bits), so the tests read one record per sample.
@group(2) @binding(2) var<storage, read_write> samples: array<vec4f>;
// Per sample: nonzero once a caster blocks it.
@group(2) @binding(3) var<storage, read_write> marks: array<atomic<u32>>;
@group(2) @binding(4) var<storage, read> triangles: array<CasterTriangle>;
// The header (AUX_* words: counters, list-length histogram, per-face bounds)
// and then the large triangles' list.
@group(2) @binding(5) var<storage, read_write> aux: array<atomic<u32>>;

const AUX_SAMPLES: u32 = 0u;
const AUX_PAIRS: u32 = 1u;
const AUX_TESTS: u32 = 2u;
// Chunks asked for by large triangles (some may not have fitted the list).
const AUX_LARGE: u32 = 3u;
// The large pass's indirect dispatch (x, y, z workgroups).
const AUX_DISPATCH: u32 = 4u;
// Chunks that did not fit the list and were tested by their triangle's thread.
const AUX_OVERFLOW: u32 = 7u;
const AUX_HISTOGRAM: u32 = 8u;
const HISTOGRAM_BINS: u32 = 32u;
// Per face, 4 words: −least x, −least y (as ~ordered), greatest x, greatest y.
const AUX_BOUNDS: u32 = 40u;
// The large triangles' chunks, two words each: triangle · 8 + face, chunk.
const AUX_LARGE_LIST: u32 = 64u;
// Threads of a chunk's workgroup, and the cells of one chunk (so that no
// invocation loops long: llvmpipe ends a shader's loops after 65535
// iterations in all, and GPUs have watchdogs).
const LARGE_THREADS: u32 = 64u;
const CHUNK_CELLS: u32 = 1024u;

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

// The shadow-ray origin of the pixel's surface; w 0 where the pixel shows
// no surface.
fn sample_origin(px: vec2u) -> vec4f {
    let pos = textureLoad(gbuffer_position, px, 0);
    if pos.w < 0.5 {
        return vec4f(0.0);
    }
    let n = normalize(textureLoad(gbuffer_normal, px, 0).xyz);
    return vec4f(offset_origin(pos.xyz, n, irr.offset.x), 1.0);
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
    let o = sample_origin(vec2u(frag.xy));
    if o.w > 0.0 {
        let face = face_of(o.xyz);
        let v = (irr.views[face] * vec4f(o.xyz, 1.0)).xyz;
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

// Pass 2, per pixel: the sample pushed onto its cell's list.
@fragment
fn fs_bin(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let o = sample_origin(px);
    if o.w > 0.0 {
        let face = face_of(o.xyz);
        let v = (irr.views[face] * vec4f(o.xyz, 1.0)).xyz;
        if !is_local() || v.z < 0.0 {
            let cell = clamp_cell(cell_of(face_bounds(face), image_of(v)));
            let node = px.y * irr.grid.z + px.x;
            let after = atomicExchange(&heads[cell_index(face, cell)], node + 1u);
            samples[node] = vec4f(o.xyz, bitcast<f32>(after));
            atomicAdd(&aux[AUX_SAMPLES], 1u);
        }
    }
    return vec4f(1.0);
}

// Pass 3, per cell: the histogram of list lengths.
@compute @workgroup_size(64)
fn cs_histogram(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let r = irr.grid.y;
    let cell = id.y * groups.x * 64u + id.x;
    if cell >= irr.grid.x * r * r {
        return;
    }
    var n = 0u;
    var node = atomicLoad(&heads[cell]);
    loop {
        if node == 0u || n >= HISTOGRAM_BINS - 1u {
            break;
        }
        n++;
        node = bitcast<u32>(samples[node - 1u].w);
    }
    if n > 0u {
        atomicAdd(&aux[AUX_HISTOGRAM + n], 1u);
    }
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

// The samples listed in one cell, tested against triangle `t`.
fn test_cell(t: CasterTriangle, face: u32, cell: vec2i) {
    var node = atomicLoad(&heads[cell_index(face, cell)]);
    var tests = 0u;
    loop {
        if node == 0u {
            break;
        }
        let s = node - 1u;
        let sample = samples[s];
        if atomicLoad(&marks[s]) == 0u {
            tests++;
            if blocks(t, sample.xyz) {
                atomicStore(&marks[s], 1u);
            }
        }
        node = bitcast<u32>(sample.w);
    }
    atomicAdd(&aux[AUX_TESTS], tests);
}

// The cells' box (x0, y0, x1, y1) of triangle `t`'s image on `face`, empty
// (x1 < x0) where it misses the face's samples. On a local light's face
// the triangle is first clipped to the light's side of the face's plane
// (−z ≥ a hair of its extent): every point between a sample and the light
// lies there and projects onto the sample's own image (Sutherland &
// Hodgman 1974); the clipped polygon's image is clamped to the samples'.
fn triangle_cells(t: CasterTriangle, face: u32) -> vec4i {
    let f = face_bounds(face);
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

// Cell `k` of the box `box` (row-major).
fn box_cell(box: vec4i, k: u32) -> vec2i {
    let width = u32(box.z - box.x + 1);
    return vec2i(box.x + i32(k % width), box.y + i32(k / width));
}

fn box_cells(box: vec4i) -> u32 {
    return u32(box.z - box.x + 1) * u32(box.w - box.y + 1);
}

// Pass 4, per triangle: every face's cells visited and their samples tested,
// or, where the triangle covers more than `irr.work.y` cells, its cells
// listed in chunks for the large pass. Chunks past the list's capacity are
// counted (AUX_OVERFLOW) and tested here.
@compute @workgroup_size(64)
fn cs_triangles(@builtin(global_invocation_id) id: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let index = id.y * groups.x * 64u + id.x;
    if index >= irr.work.x {
        return;
    }
    let t = triangles[index];
    for (var face = 0u; face < irr.grid.x; face++) {
        let box = triangle_cells(t, face);
        if box.z < box.x || box.w < box.y {
            continue;
        }
        let cells = box_cells(box);
        var first = 0u;
        if cells > irr.work.y {
            let chunks = (cells + CHUNK_CELLS - 1u) / CHUNK_CELLS;
            let slot = atomicAdd(&aux[AUX_LARGE], chunks);
            let fitted = min(chunks, irr.work.z - min(slot, irr.work.z));
            for (var c = 0u; c < fitted; c++) {
                atomicStore(&aux[AUX_LARGE_LIST + 2u * (slot + c)], index * 8u + face);
                atomicStore(&aux[AUX_LARGE_LIST + 2u * (slot + c) + 1u], c);
            }
            if fitted == chunks {
                continue;
            }
            atomicAdd(&aux[AUX_OVERFLOW], chunks - fitted);
            first = fitted * CHUNK_CELLS;
        }
        atomicAdd(&aux[AUX_PAIRS], cells - first);
        for (var k = first; k < cells; k++) {
            test_cell(t, face, box_cell(box, k));
        }
    }
}

// Pass 5, one invocation: the large pass's workgroups, one per listed chunk.
@compute @workgroup_size(1)
fn cs_large_dispatch() {
    let count = min(atomicLoad(&aux[AUX_LARGE]), irr.work.z);
    let x = min(count, 65535u);
    atomicStore(&aux[AUX_DISPATCH], x);
    atomicStore(&aux[AUX_DISPATCH + 1u], select(0u, (count + x - 1u) / max(x, 1u), x > 0u));
    atomicStore(&aux[AUX_DISPATCH + 2u], 1u);
}

// Pass 6, a workgroup per chunk: its threads share the chunk's cells.
@compute @workgroup_size(64)
fn cs_large(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u,
        @builtin(local_invocation_index) lane: u32) {
    let e = group.y * groups.x + group.x;
    if e >= min(atomicLoad(&aux[AUX_LARGE]), irr.work.z) {
        return;
    }
    let entry = atomicLoad(&aux[AUX_LARGE_LIST + 2u * e]);
    let chunk = atomicLoad(&aux[AUX_LARGE_LIST + 2u * e + 1u]);
    let t = triangles[entry / 8u];
    let face = entry % 8u;
    let box = triangle_cells(t, face);
    let end = min(box_cells(box), (chunk + 1u) * CHUNK_CELLS);
    let first = chunk * CHUNK_CELLS;
    if lane == 0u {
        atomicAdd(&aux[AUX_PAIRS], end - first);
    }
    for (var k = first + lane; k < end; k += LARGE_THREADS) {
        test_cell(t, face, box_cell(box, k));
    }
}

// Pass 7, per pixel: the mask, 0 where a caster blocks the sample.
@fragment
fn fs_mask(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2u(frag.xy);
    let node = px.y * irr.grid.z + px.x;
    let blocked = atomicLoad(&marks[node]) != 0u;
    return vec4f(select(1.0, 0.0, blocked));
}
