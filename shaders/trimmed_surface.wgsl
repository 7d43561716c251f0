// Step 1 of paper 001 (§3.1): the initial rendering of a B-Rep part by its per-frame basis
// surface tessellation with direct GPU trimming (paper 000 §5–6; core/render/src/
// trimmed_surface.rs). Vertices are pulled from the frame's grid (no vertex buffer): vertex
// i is corner i % 6 of cell i / 6. A cell that triangle classification found wholly off the
// face becomes a degenerate triangle outside the clip volume. Each fragment resumes the trim
// walk from its cell's hand-off node (§6), stopping at a node under the pixel's footprint
// (§5.3), and is discarded off the face; on-face fragments write the colour (per-pixel
// shading with the surface's exact normal at the fragment's (u, v)), the metadata of §3.1
// (face id; (u, v); the patch is the face's basis surface, so its id is the face's) and
// depth. Concatenated after shading, brep_bindings, trim_quadtree, surface_eval, patch_grid,
// grid_raster.

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) face_id: u32,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    let corner = vi % 6u;
    return cell_vertex(vi / 6u, CORNER_A[corner], CORNER_B[corner]);
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    // Derivatives first, in uniform control flow: the fragment's footprint in quadtree
    // coordinates, the parallelogram spanned by the two screen derivatives; §5.3 stops the
    // walk at a node smaller than the largest square inside it, whose side is at most the
    // parallelogram's smaller altitude, |det| / the longer side (a grazing view's long thin
    // footprint gets a small stop, not its long extent). And the grid-cell coordinates for the
    // edge overlay.
    let xy = trim_to_tree(in.face, in.st);
    let ddx = dpdx(xy);
    let ddy = dpdy(xy);
    let stop = abs(ddx.x * ddy.y - ddx.y * ddy.x) / max(max(length(ddx), length(ddy)), 1e-30);
    let cell_xy = xy * vec2<f32>(in.grid_size);
    let cell_w = fwidth(cell_xy);

    if !on_face(in, stop) {
        discard;
    }
    let uv = patch_to_uv(in.face, in.st);
    let s = surface_eval(in.face, uv);
    var n = surface_normal(in.face, s);
    if dot(n, n) < 0.25 {
        n = normalize(in.normal);
    }
    let view = normalize(params.eye - in.world);
    var color = shade(params.shading, in.face + 1u, n, view, params.light);

    if params.edges != 0u {
        // The tessellation grid's lines, about one pixel wide, faded where cells are only a
        // few pixels across.
        let f = fract(cell_xy);
        let d = min(f, vec2<f32>(1.0) - f) / max(cell_w, vec2<f32>(1e-12));
        let e = min(d.x, d.y);
        let small = max(cell_w.x, cell_w.y);
        let a = (1.0 - smoothstep(0.5, 1.5, e)) * (1.0 - smoothstep(0.15, 0.4, small));
        color = mix(color, vec3<f32>(0.08, 0.08, 0.1), 0.85 * a);
    }

    var out: FragmentOut;
    out.color = vec4<f32>(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
    out.face_id = in.face + 1u;
    out.uv = uv;
    return out;
}
