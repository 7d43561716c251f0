// The per-frame tessellation grid of every face's basis surface (core/render/src/
// patch_tessellation.rs; paper 000 §6–7, paper 001 §3.1): the tessellation stage WebGPU lacks,
// as a library shared by the passes that make and draw the grid. A face is drawn as a grid of
// nu × nv cells over its quadtree's root square (nu, nv powers of two), so that a grid cell
// at level k = log2 min(nu, nv) lies inside one quadtree cell of depth k and triangle
// classification (§6) can hand that node down to the fragments.

// One face's tessellation in this frame (32 bytes).
struct PatchFrame {
    // The face (document order).
    face: u32,
    // Cells along the quadtree's x and y axes (powers of two).
    nu: u32,
    nv: u32,
    // The classification depth k_f = log2 min(nu, nv).
    level: u32,
    // The face's first grid vertex and first cell in the frame's arrays.
    vertex_base: u32,
    cell_base: u32,
    pad0: u32,
    pad1: u32,
}

// A grid vertex (32 bytes): the surface point relative to the scene origin, with the patch s
// in `p.w`; the unit face normal, with the patch t in `n.w`.
struct GridVertex {
    p: vec4<f32>,
    n: vec4<f32>,
}

// A grid cell after triangle classification (24 bytes): its face's entry in the frame's
// patches, its column a and row b (a | b << 16), and where its fragments' trim walk starts:
// the node, its depth (bits 0–7) and whether the whole cell is decided (bits 8–9: 0 no, 1 all
// off, 2 all on), and the node's cell origin in quadtree coordinates.
struct CellRecord {
    patch_index: u32,
    ab: u32,
    node: u32,
    depth_whole: u32,
    origin: vec2<f32>,
}

const WHOLE_UNDECIDED: u32 = 0u;
const WHOLE_OFF: u32 = 1u;
const WHOLE_ON: u32 = 2u;

// The uniform block of the grid and classification passes (`TessParams` of
// core/render/src/patch_tessellation.rs, 16 bytes).
struct TessParams {
    patch_count: u32,
    vertex_count: u32,
    cell_count: u32,
    // Invocations per dispatch row (workgroups along x × 64).
    row: u32,
}

// The last of the first `count` patches whose first cell (`by_cell`) or first grid vertex
// (otherwise) is at or before `i`: a binary search, the bases increasing. Every shader that
// includes this library declares the frame's `patches: array<PatchFrame>`.
fn patch_of(i: u32, count: u32, by_cell: bool) -> u32 {
    var lo = 0u;
    var hi = count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if select(patches[mid].vertex_base, patches[mid].cell_base, by_cell) <= i {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// The patch (s, t) of quadtree point `xy` of `face` (the inverse of `trim_to_tree`).
fn tree_to_patch(face: u32, xy: vec2<f32>) -> vec2<f32> {
    let h = trim_headers[face];
    return (xy - h.origin) / h.scale;
}
