// Basis-surface tessellation per frame (core/render/src/patch_tessellation.rs): one
// invocation per grid vertex evaluates the face's surface (shaders/surface_eval.wgsl) at the
// vertex's quadtree point. Concatenated after brep_bindings, trim_quadtree, surface_eval and
// patch_grid.

struct TessParams {
    patch_count: u32,
    vertex_count: u32,
    cell_count: u32,
    // Invocations per dispatch row (workgroups along x × 64).
    row: u32,
}

@group(0) @binding(0) var<uniform> tp: TessParams;
@group(0) @binding(1) var<storage, read> patches: array<PatchFrame>;
@group(0) @binding(2) var<storage, read_write> grid: array<GridVertex>;

// The last patch whose first vertex is at or before `i`.
fn patch_of_vertex(i: u32) -> u32 {
    var lo = 0u;
    var hi = tp.patch_count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if patches[mid].vertex_base <= i {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * tp.row;
    if i >= tp.vertex_count {
        return;
    }
    let pf = patches[patch_of_vertex(i)];
    let local = i - pf.vertex_base;
    let a = local % (pf.nu + 1u);
    let b = local / (pf.nu + 1u);
    let xy = vec2<f32>(f32(a) / f32(pf.nu), f32(b) / f32(pf.nv));
    let st = tree_to_patch(pf.face, xy);
    let s = surface_eval(pf.face, patch_to_uv(pf.face, st));
    let n = surface_normal(pf.face, s);
    grid[i] = GridVertex(vec4<f32>(s.p, st.x), vec4<f32>(n, st.y));
}
