// Drawing the frame's tessellation grid (shaders/patch_grid.wgsl) without a vertex buffer:
// the vertex pulling shared by the trimmed surface pass (paper 001 §3.1) and the filled and
// wireframe passes of object-space crack filling (§3.4.2), and the trim test of a fragment
// from its cell's hand-off (paper 000 §6). Bind group 0 of both: the shading block
// (`Params` of core/render/src/surface.rs), the frame's patches, cells and grid.

// The shading block: clip space from positions relative to the scene origin, the eye (same
// frame), the shading mode, the key light, the edge overlay.
struct Params {
    clip_from_world: mat4x4<f32>,
    eye: vec3<f32>,
    shading: u32,
    light: vec3<f32>,
    edges: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> patches: array<PatchFrame>;
@group(0) @binding(2) var<storage, read> cells: array<CellRecord>;
@group(0) @binding(3) var<storage, read> grid: array<GridVertex>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) st: vec2<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) @interpolate(flat) face: u32,
    @location(4) @interpolate(flat) node: u32,
    @location(5) @interpolate(flat) depth_whole: u32,
    @location(6) @interpolate(flat) origin: vec2<f32>,
    @location(7) @interpolate(flat) grid_size: vec2<u32>,
}

// The grid corner (da, db) of each of a cell's six triangle corners.
const CORNER_A = array<u32, 6>(0u, 1u, 1u, 0u, 1u, 0u);
const CORNER_B = array<u32, 6>(0u, 0u, 1u, 0u, 1u, 1u);

// Cell `cell`'s grid corner (da, db), as a vertex: clip position and attributes.
fn cell_vertex(cell: u32, da: u32, db: u32) -> VertexOut {
    let c = cells[cell];
    let pf = patches[c.patch_index];
    var out: VertexOut;
    out.face = pf.face;
    out.node = c.node;
    out.depth_whole = c.depth_whole;
    out.origin = c.origin;
    out.grid_size = vec2<u32>(pf.nu, pf.nv);
    if ((c.depth_whole >> 8u) & 3u) == WHOLE_OFF {
        // Off the face: a point outside the clip volume, so the triangle is dropped.
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return out;
    }
    let a = (c.ab & 0xffffu) + da;
    let b = (c.ab >> 16u) + db;
    let g = grid[pf.vertex_base + b * (pf.nu + 1u) + a];
    out.clip = params.clip_from_world * vec4<f32>(g.p.xyz, 1.0);
    out.world = g.p.xyz;
    out.st = vec2<f32>(g.p.w, g.n.w);
    out.normal = g.n.xyz;
    return out;
}

// Whether the fragment at patch point `st` is on the face: the walk from the cell's hand-off
// node when the point lies in that node's cell (interpolation can carry a fragment at a cell
// border a rounding outside it), else from the root; `stop` is the §5.3 footprint.
fn on_face(in: VertexOut, stop: f32) -> bool {
    let whole = (in.depth_whole >> 8u) & 3u;
    if whole == WHOLE_ON {
        return true;
    }
    let depth = in.depth_whole & 0xffu;
    let xy = trim_to_tree(in.face, in.st);
    let side = trim_side(depth);
    let inside = all(xy >= in.origin) && all(xy <= in.origin + vec2<f32>(side));
    if inside {
        return trim_walk_from(in.face, TrimStart(in.node, depth, in.origin), in.st, stop);
    }
    return trim_walk_from(in.face, trim_root(in.face), in.st, stop);
}

