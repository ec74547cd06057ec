// GPU extrusion of shadow volumes: the same index lists as the CPU path
// (silhouette.rs) written into one index buffer drawn with
// draw-indexed-indirect. Index 2v is welded vertex v, 2v + 1 the vertex
// extruded away from the light. Two lists: z-pass from `first[0]`, z-fail
// from `first[1]`; each list's index count is an atomic in its indirect
// arguments.

struct Face {
    v: vec3u,
    caster: u32,
    plane: vec4f,
};

struct Edge {
    a: u32,
    b: u32,
    f0: u32,
    f1: u32,
};

struct Caster {
    // the light in object space (w = 0: direction towards the light)
    light: vec4f,
    // 0 skip, 1 silhouette, 2 per-triangle
    kind: u32,
    // 1: counted with z-fail (its list), caps needed
    zfail: u32,
    caps: u32,
    _pad: u32,
};

struct Args {
    // draw_indexed_indirect arguments of the z-pass and z-fail lists
    zpass_count: atomic<u32>,
    zpass_instances: u32,
    zpass_first: u32,
    zpass_base: i32,
    zpass_first_instance: u32,
    zfail_count: atomic<u32>,
    zfail_instances: u32,
    zfail_first: u32,
    zfail_base: i32,
    zfail_first_instance: u32,
    silhouette_edges: atomic<u32>,
};

struct Params {
    edge_count: u32,
    face_count: u32,
    // 1: emit dark caps (not for directional lights extruded to infinity)
    dark_cap: u32,
    _pad: u32,
};

const NO_FACE: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> faces: array<Face>;
@group(0) @binding(2) var<storage, read> edges: array<Edge>;
@group(0) @binding(3) var<storage, read> casters: array<Caster>;
@group(0) @binding(4) var<storage, read_write> indices: array<u32>;
@group(0) @binding(5) var<storage, read_write> args: Args;

fn lit(f: u32, light: vec4f) -> bool {
    return dot(faces[f].plane, light) > 0.0;
}

// Reserves n indices in a list; returns the first.
fn reserve(zfail: bool, n: u32) -> u32 {
    if zfail {
        return args.zfail_first + atomicAdd(&args.zfail_count, n);
    }
    return args.zpass_first + atomicAdd(&args.zpass_count, n);
}

fn quad(at: u32, u: u32, v: u32) {
    indices[at] = 2u * v;
    indices[at + 1u] = 2u * u;
    indices[at + 2u] = 2u * u + 1u;
    indices[at + 3u] = 2u * v;
    indices[at + 4u] = 2u * u + 1u;
    indices[at + 5u] = 2u * v + 1u;
}

// Light cap, then the dark cap when asked.
fn caps(at: u32, t: vec3u) {
    indices[at] = 2u * t.x;
    indices[at + 1u] = 2u * t.y;
    indices[at + 2u] = 2u * t.z;
    if params.dark_cap == 1u {
        indices[at + 3u] = 2u * t.x + 1u;
        indices[at + 4u] = 2u * t.z + 1u;
        indices[at + 5u] = 2u * t.y + 1u;
    }
}

// A face use's term of the edge multiplicity: its direction along the
// edge times its weight (silhouette: lit 1, unlit 0; per-triangle: lit 1,
// unlit −1, the unlit triangle's volume being turned to face the light).
fn use_term(f: u32, light: vec4f, kind: u32) -> i32 {
    if f == NO_FACE {
        return 0;
    }
    var weight = 0;
    if lit(f >> 1u, light) {
        weight = 1;
    } else if kind == 2u {
        weight = -1;
    }
    return select(weight, -weight, (f & 1u) == 1u);
}

// One thread per edge record: |m| side quads.
@compute @workgroup_size(64)
fn cs_edges(@builtin(global_invocation_id) id: vec3u) {
    let e = id.x + id.y * 65535u * 64u;
    if e >= params.edge_count {
        return;
    }
    let edge = edges[e];
    let caster = casters[faces[edge.f0 >> 1u].caster];
    if caster.kind == 0u {
        return;
    }
    let m = use_term(edge.f0, caster.light, caster.kind) + use_term(edge.f1, caster.light, caster.kind);
    if m == 0 {
        return;
    }
    if caster.kind == 1u {
        atomicAdd(&args.silhouette_edges, 1u);
    }
    let n = u32(abs(m));
    let at = reserve(caster.zfail == 1u, 6u * n);
    for (var k = 0u; k < n; k++) {
        if m > 0 {
            quad(at + 6u * k, edge.a, edge.b);
        } else {
            quad(at + 6u * k, edge.b, edge.a);
        }
    }
}

// One thread per face: caps of lit faces (silhouette casters counted with
// z-fail), or of every face turned to face the light (per-triangle casters).
@compute @workgroup_size(64)
fn cs_faces(@builtin(global_invocation_id) id: vec3u) {
    let f = id.x + id.y * 65535u * 64u;
    if f >= params.face_count {
        return;
    }
    let face = faces[f];
    let caster = casters[face.caster];
    let is_lit = lit(f, caster.light);
    let cap_size = select(3u, 6u, params.dark_cap == 1u);
    if caster.kind == 1u && caster.caps == 1u && is_lit {
        caps(reserve(caster.zfail == 1u, cap_size), face.v);
    } else if caster.kind == 2u {
        caps(reserve(caster.zfail == 1u, cap_size), select(face.v.xzy, face.v, is_lit));
    }
}
