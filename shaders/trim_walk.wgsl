// The trim walk (shaders/trim_quadtree.wgsl, paper 000 §5–5.3) as a compute pass over a batch
// of query points, to check the shader's walk against its CPU reference
// (`MultiPack::walk`). Concatenated after trim_quadtree.wgsl.
//
// Buffers: the four of the trim library, the queries (face, s, t) and one output word per
// query (1 on the face, 0 off).

struct Query {
    face: u32,
    s: f32,
    t: f32,
}

@group(0) @binding(0) var<storage, read> trim_headers: array<TrimHeader>;
@group(0) @binding(1) var<storage, read> trim_nodes: array<u32>;
@group(0) @binding(2) var<storage, read> trim_curves: array<f32>;
@group(0) @binding(3) var<storage, read> trim_lines: array<u32>;
@group(0) @binding(4) var<storage, read> queries: array<Query>;
@group(0) @binding(5) var<storage, read_write> results: array<u32>;

const WORKGROUP: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let q = gid.x + gid.y * groups.x * WORKGROUP;
    if q >= arrayLength(&queries) || q >= arrayLength(&results) {
        return;
    }
    let p = queries[q];
    var on = false;
    if p.face < arrayLength(&trim_headers) {
        on = trim_walk(p.face, vec2<f32>(p.s, p.t));
    }
    results[q] = select(0u, 1u, on);
}
