// Full-scene ray casting of B-Rep faces (paper 001 §4.1.2: "Ray-patch intersections are
// calculated using the Newton iterative root finding method", the reference the paper
// compares its crack filling with), as two compute passes, one invocation per pixel:
//
// 1. `cast_rays`: the pixel's ray (the camera convention of `tessd_render::camera`) against every
//    face's world box, then against the boxes of the face's seed cells (a grid over its
//    patch, built on the CPU by `ray_cast.rs` with the part's `BrepScene`); Newton (ray_newton.wgsl) from the centre of
//    each seed cell the ray crosses; a converged hit counts when the trim walk (paper 000 §5,
//    trim_quadtree.wgsl) puts its (u, v) on the face, as paper 001 §3.4.2.a classifies
//    ray-cast points. The nearest such hit goes to `hits`.
// 2. `resolve_hits`: the hit shaded (shading.wgsl, the raster pass's light and modes) into the
//    frame's per-pixel buffers (`tessd_render::frame_buffers` layout: index y·W + x, row 0 at
//    the top).
//
// The search runs in **batches of seed cells**, one dispatch each, every invocation carrying
// its pixel's nearest hit so far in `hits` from one batch to the next; the host submits it one
// region of the image (`row0`, `col0`) and a few batches at a time, so that it can report
// progress and hear a cancel between submissions (`ray_cast.rs`, `RayCastPass::cast`). One loop over all cells
// would be simpler, but llvmpipe (lavapipe) bounds the iterations of a loop nest — the
// outermost loop and everything nested in it, Newton's steps and the B-spline basis loops
// included — to 65 535 per invocation, and silently leaves the loops past that: a thread's
// flanks alone would exhaust it and the faces searched after them would go missing.
//
// Two kinds of pass: the search (the heavy loop) and the shading of its result.
// Bind group 0 is the pass's own (below), group 1 the part's shared buffers
// (brep_bindings.wgsl). Concatenated after brep_bindings.wgsl, surface_eval.wgsl,
// ray_newton.wgsl, trim_quadtree.wgsl and shading.wgsl.

// `ray_cast::Params` (96 bytes). Positions relative to the scene origin.
struct RayParams {
    eye: vec3<f32>,
    // Newton's convergence tolerance, world units.
    tol: f32,
    forward: vec3<f32>,
    width: u32,
    right: vec3<f32>,
    height: u32,
    up: vec3<f32>,
    faces: u32,
    light: vec3<f32>,
    shading: u32,
    // tan(fov/2)·W/H and tan(fov/2).
    tan_x: f32,
    tan_y: f32,
    // The first pixel row and column of the region `cast_rays` searches (the search runs in
    // regions of the image, one submission at a time); `resolve_hits` covers the whole image.
    row0: u32,
    col0: u32,
}

// `ray_cast::SeedBox` (32 bytes): a world box (relative to the scene origin). The first
// `faces` entries are the faces' boxes, `a` = index of their first cell, `b` = cells along s
// | cells along t << 16; then the cells, row by row (s fastest), `a` = their face, `b` = the
// cell's column | row << 16.
struct SeedBox {
    lo: vec3<f32>,
    a: u32,
    hi: vec3<f32>,
    b: u32,
}

// The nearest hit of a pixel: ray parameter, face index + 1 (0: none), native (u, v).
struct CastHit {
    t: f32,
    face: u32,
    uv: vec2<f32>,
}

// The work items one search dispatch covers, [begin, end) in `items`; `first` is 1 for the
// first batch (the pixel's search starts from no hit).
struct Batch {
    begin: u32,
    end: u32,
    first: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: RayParams;
@group(0) @binding(7) var<uniform> batch: Batch;
// The work items, faces nearest first (by their boxes' nearest depth along the view, sorted
// on the CPU per frame; once a hit is found, farther faces fail the box test at `best.t`):
// (face, first cell, cells, 0), a face's cells split over several items when they would
// not fit one dispatch's loop budget.
@group(0) @binding(8) var<storage, read> items: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> seed_boxes: array<SeedBox>;
@group(0) @binding(2) var<storage, read_write> hits: array<CastHit>;
@group(0) @binding(3) var<storage, read_write> frame_color: array<u32>;
@group(0) @binding(4) var<storage, read_write> frame_depth: array<f32>;
@group(0) @binding(5) var<storage, read_write> frame_face: array<u32>;
@group(0) @binding(6) var<storage, read_write> frame_uv: array<vec2<f32>>;

const F32_MAX: f32 = 3.4028235e38;

// The (unnormalised) ray direction of pixel `px`: forward + sx·right + sy·up'.
fn pixel_ray(px: vec2<u32>) -> vec3<f32> {
    let w = f32(params.width);
    let h = f32(params.height);
    let sx = (2.0 * (f32(px.x) + 0.5) / w - 1.0) * params.tan_x;
    let sy = (1.0 - 2.0 * (f32(px.y) + 0.5) / h) * params.tan_y;
    return params.forward + sx * params.right + sy * params.up;
}

// Slab test: whether the ray enters box `b` before `t_max` and leaves it after 0.
fn ray_box(o: vec3<f32>, inv: vec3<f32>, b: SeedBox, t_max: f32) -> bool {
    let t0 = (b.lo - o) * inv;
    let t1 = (b.hi - o) * inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(near.x, near.y), near.z);
    let leave = min(min(far.x, far.y), far.z);
    return enter <= leave && leave >= 0.0 && enter <= t_max;
}

@compute @workgroup_size(8, 8)
fn cast_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let gid = vec2<u32>(id.x + params.col0, id.y + params.row0);
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let dir = pixel_ray(gid);
    let o = params.eye;
    // 1/dir, with zero components replaced so the slabs stay finite and ordered.
    let safe = select(dir, vec3<f32>(1e-30), abs(dir) < vec3<f32>(1e-30));
    let inv = 1.0 / safe;
    let i = gid.y * params.width + gid.x;
    var best = CastHit(F32_MAX, 0u, vec2<f32>(0.0));
    if batch.first == 0u {
        best = hits[i];
    }
    for (var k = batch.begin; k < batch.end; k += 1u) {
        let item = items[k];
        let f = item.x;
        let fb = seed_boxes[f];
        if !ray_box(o, inv, fb, best.t) {
            continue;
        }
        let n = vec2<u32>(fb.b & 0xffffu, fb.b >> 16u);
        let cells = vec2<f32>(n);
        for (var c = item.y; c < item.y + item.z; c += 1u) {
            let cell = seed_boxes[c];
            if !ray_box(o, inv, cell, best.t) {
                continue;
            }
            let ij = vec2<f32>(f32(cell.b & 0xffffu), f32(cell.b >> 16u));
            let st = (ij + vec2<f32>(0.5)) / cells;
            let h = ray_newton(f, o, dir, patch_to_uv(f, st), params.tol, 1.0 / cells);
            if h.hit && h.t < best.t && trim_walk(f, uv_to_patch(f, h.uv)) {
                best = CastHit(h.t, f + 1u, h.uv);
            }
        }
    }
    hits[i] = best;
}

@compute @workgroup_size(8, 8)
fn resolve_hits(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let i = gid.y * params.width + gid.x;
    let h = hits[i];
    if h.face == 0u {
        frame_color[i] = pack4x8unorm(vec4<f32>(vec3<f32>(224.0 / 255.0), 1.0));
        frame_depth[i] = F32_MAX;
        frame_face[i] = 0u;
        frame_uv[i] = vec2<f32>(0.0);
        return;
    }
    let dir = pixel_ray(gid.xy);
    let face = h.face - 1u;
    let s = surface_eval(face, h.uv);
    let n = surface_normal(face, s);
    let view = normalize(-dir);
    let color = shade(params.shading, h.face, n, view, params.light);
    frame_color[i] = pack4x8unorm(vec4<f32>(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
    frame_depth[i] = h.t * dot(dir, params.forward);
    frame_face[i] = h.face;
    frame_uv[i] = h.uv;
}
