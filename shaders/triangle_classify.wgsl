// Triangle classification (paper 000 §6; core/render/src/triangle_classification.rs): one
// invocation per grid cell (its two triangles share it) finds the quadtree node at the
// classification depth k_f that holds the cell, found with the cell's centre, and decides the
// whole cell when that node is a leaf that is entirely on or off the face, or a leaf whose
// single curve is a line with all four corners on one side (a half-plane is convex, so the
// cell is then wholly on that side). Otherwise the node is handed down to the fragments,
// whose walk resumes from it. Quadratic-curve leaves are not decided per cell: the implicit
// region of §5.1 is not convex in general, so four corners on one side prove nothing.
// Concatenated after brep_bindings, trim_quadtree, surface_eval and patch_grid.

@group(0) @binding(0) var<uniform> tp: TessParams;
@group(0) @binding(1) var<storage, read> patches: array<PatchFrame>;
@group(0) @binding(2) var<storage, read_write> cells: array<CellRecord>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * tp.row;
    if i >= tp.cell_count {
        return;
    }
    let k = patch_of(i, tp.patch_count, true);
    let pf = patches[k];
    let local = i - pf.cell_base;
    let a = local % pf.nu;
    let b = local / pf.nu;
    let step = vec2<f32>(1.0 / f32(pf.nu), 1.0 / f32(pf.nv));
    let lo = vec2<f32>(f32(a), f32(b)) * step;
    let hi = lo + step;
    let c = 0.5 * (lo + hi);
    let h = trim_headers[pf.face];
    var node = h.node_base;
    var depth = 0u;
    var origin = vec2<f32>(0.0);
    var side = 1.0;
    loop {
        let word = trim_nodes[node];
        if (word & 7u) != 0u || depth >= pf.level || depth >= h.depth_limit {
            break;
        }
        side *= 0.5;
        let hx = c.x >= origin.x + side;
        let hy = c.y >= origin.y + side;
        if hx {
            origin.x += side;
        }
        if hy {
            origin.y += side;
        }
        node = (word >> (32u - TRIM_NODE_INDEX_BITS)) + select(0u, 1u, hx) + select(0u, 2u, hy);
        depth += 1u;
    }
    let word = trim_nodes[node];
    let kind = word & 7u;
    var whole = WHOLE_UNDECIDED;
    if kind == 1u {
        whole = WHOLE_OFF;
    } else if kind == 2u {
        whole = WHOLE_ON;
    } else if kind == 3u {
        let index = word >> (32u - TRIM_NODE_INDEX_BITS);
        let c0 = trim_curve(index, 0u, lo.x, lo.y);
        let c1 = trim_curve(index, 0u, hi.x, lo.y);
        let c2 = trim_curve(index, 0u, lo.x, hi.y);
        let c3 = trim_curve(index, 0u, hi.x, hi.y);
        if c0 && c1 && c2 && c3 {
            whole = WHOLE_ON;
        } else if !(c0 || c1 || c2 || c3) {
            whole = WHOLE_OFF;
        }
    }
    cells[i] = CellRecord(k, a | (b << 16u), node, depth | (whole << 8u), origin);
}
