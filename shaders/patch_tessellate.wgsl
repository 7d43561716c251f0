// Basis-surface tessellation per frame (core/render/src/patch_tessellation.rs): one
// invocation per grid vertex evaluates the face's surface (shaders/surface_eval.wgsl) at the
// vertex's quadtree point. Concatenated after brep_bindings, trim_quadtree, surface_eval and
// patch_grid.

@group(0) @binding(0) var<uniform> tp: TessParams;
@group(0) @binding(1) var<storage, read> patches: array<PatchFrame>;
@group(0) @binding(2) var<storage, read_write> grid: array<GridVertex>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * tp.row;
    if i >= tp.vertex_count {
        return;
    }
    let pf = patches[patch_of(i, tp.patch_count, false)];
    let local = i - pf.vertex_base;
    let a = local % (pf.nu + 1u);
    let b = local / (pf.nu + 1u);
    let xy = vec2<f32>(f32(a) / f32(pf.nu), f32(b) / f32(pf.nv));
    let st = tree_to_patch(pf.face, xy);
    let s = surface_eval(pf.face, patch_to_uv(pf.face, st));
    let n = surface_normal(pf.face, s);
    grid[i] = GridVertex(vec4<f32>(s.p, st.x), vec4<f32>(n, st.y));
}
