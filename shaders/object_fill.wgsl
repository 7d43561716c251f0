// Step 4 of paper 001 (§3.4.2; core/render/src/object_fill.rs): object-space crack filling.
// The frame's grid is drawn twice over the depth mask (step 3) — filled triangles, trimmed,
// and a wireframe of every cell's edges and diagonal, untrimmed, so thin triangles and
// silhouette slivers still make fragments (figures 10, 12, 13); back faces kept in both
// (figure 11). Each fragment ray casts its own face at every crack pixel q of its 1-ring:
// Newton (shaders/ray_newton.wgsl) from the fragment's (u, v) towards q's ray, the hit trimmed
// by the face's quadtree from the root (§3.4.2.a).
//
// WGSL has 32-bit atomics only, and the paper's ZRGB word (depth in the high bits, colour in
// the low ones) would leave the depth 8 bits. Here the atomic word is a **ZF** key: the depth's
// f32 bits with the low 12 cleared (non-negative floats order like their bit patterns; 11
// mantissa bits remain, a relative precision of 5·10⁻⁴) and a 12-bit face tag in the low bits
// (the face index mod 4095; 4095 marks step 1's own surface). Pass A keeps the smallest key
// per crack pixel with `atomicMin`. Pass B then repeats the ray casts only for fragments whose
// face carries the winning tag — most fragments stop at that comparison — and the hit whose
// key equals the winner claims the pixel's payload slot (compare-exchange) and writes its
// (u, v), exact depth and shaded colour. Two hits within 5·10⁻⁴ of each other in depth are
// two faces meeting at the crack; either fills it. Patch mailboxing (§3.4.2.b) in pass A: a
// crack pixel remembers the last face whose ray cast succeeded there, and later fragments of
// that face skip it. Step 5 (object_fill_composite.wgsl) then writes the winners into the
// frame. Concatenated after shading, brep_bindings, trim_quadtree, surface_eval, patch_grid,
// grid_raster, ray_newton.

struct Fill {
    // The eye relative to the scene origin, and the pixel ray basis: a pixel's ray direction
    // is forward + sx·right + sy·up with sx, sy in [−1, 1] (tan(fov/2) and the aspect folded
    // into right and up), so a hit's t is its camera-z distance.
    eye: vec3<f32>,
    width: u32,
    forward: vec3<f32>,
    height: u32,
    right: vec3<f32>,
    // Newton's convergence tolerance, world units.
    tolerance: f32,
    up: vec3<f32>,
    // 0: pass A, 1: pass B.
    phase: u32,
}

@group(2) @binding(0) var<uniform> fill: Fill;
@group(2) @binding(1) var<storage, read> flags: array<u32>;
@group(2) @binding(2) var<storage, read_write> zmin: array<atomic<u32>>;
@group(2) @binding(3) var<storage, read_write> mailbox: array<u32>;
@group(2) @binding(4) var<storage, read_write> winner_face: array<atomic<u32>>;
// Per crack pixel: the winner's (u, v), exact depth and packed colour (as f32 bits).
@group(2) @binding(5) var<storage, read_write> winner: array<vec4<f32>>;

const CRACK_FLAG: u32 = 1u;

// The low bits of a ZF key: the face tag.
const TAG_BITS: u32 = 0xfffu;

// The ZF key of a hit of face `face` at depth `t`.
fn zf_key(face: u32, t: f32) -> u32 {
    return (bitcast<u32>(t) & ~TAG_BITS) | (face % TAG_BITS);
}

// The cell corners of the wireframe: four edges and the diagonal, two ends each.
const LINE_A = array<u32, 10>(0u, 1u, 1u, 1u, 1u, 0u, 0u, 0u, 0u, 1u);
const LINE_B = array<u32, 10>(0u, 0u, 0u, 1u, 1u, 1u, 1u, 0u, 0u, 1u);

@vertex
fn vs_filled(@builtin(vertex_index) vi: u32) -> VertexOut {
    let corner = vi % 6u;
    return cell_vertex(vi / 6u, CORNER_A[corner], CORNER_B[corner]);
}

// Set in `depth_whole` by the wireframe's vertices: their fragments are not trimmed.
const UNTRIMMED: u32 = 1u << 12u;

@vertex
fn vs_lines(@builtin(vertex_index) vi: u32) -> VertexOut {
    let corner = vi % 10u;
    var out = cell_vertex(vi / 10u, LINE_A[corner], LINE_B[corner]);
    out.depth_whole |= UNTRIMMED;
    return out;
}

// The ray direction of pixel `q`.
fn pixel_ray(q: vec2<i32>) -> vec3<f32> {
    let sx = 2.0 * (f32(q.x) + 0.5) / f32(fill.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(q.y) + 0.5) / f32(fill.height);
    return fill.forward + sx * fill.right + sy * fill.up;
}

// Face `face` ray cast at pixel `q` from (u, v) `uv0`: the hit, `hit.hit` false when none is on the face.
fn cast_at(face: u32, q: vec2<i32>, uv0: vec2<f32>) -> RayHit {
    var hit = ray_newton(face, fill.eye, pixel_ray(q), uv0, fill.tolerance, vec2<f32>(0.25));
    if hit.hit && !trim_walk(face, uv_to_patch(face, hit.uv)) {
        hit.hit = false;
    }
    return hit;
}

// Pass A (`fill.phase` 0) or B (1) at the fragment of face `face`, pixel `p`, (u, v) `uv0`,
// for every crack pixel q of p's 1-ring. A keeps the nearest hit depth per crack pixel
// (atomic min) and mailboxes the face; B repeats the casts, and a hit at the pixel's minimum
// depth claims the pixel. One function for both passes, one ray cast site: each inlined copy
// of the surface evaluator costs seconds of compilation on lavapipe.
fn fill_ring(face: u32, p: vec2<i32>, uv0: vec2<f32>) {
    for (var k = 0; k < 9; k += 1) {
        let q = p + vec2<i32>(k % 3 - 1, k / 3 - 1);
        if q.x < 0 || q.y < 0 || q.x >= i32(fill.width) || q.y >= i32(fill.height) {
            continue;
        }
        let j = u32(q.y) * fill.width + u32(q.x);
        if (flags[j] & CRACK_FLAG) == 0u {
            continue;
        }
        if fill.phase == 0u && mailbox[j] == face + 1u {
            continue;
        }
        if fill.phase == 1u {
            // Only the winning face's fragments cast again, and only until one claims.
            let key = atomicLoad(&zmin[j]);
            if (key & TAG_BITS) != face % TAG_BITS || atomicLoad(&winner_face[j]) != 0u {
                continue;
            }
        }
        let hit = cast_at(face, q, uv0);
        if !(hit.hit && hit.t > 0.0) {
            continue;
        }
        let key = zf_key(face, hit.t);
        if fill.phase == 0u {
            atomicMin(&zmin[j], key);
            mailbox[j] = face + 1u;
            continue;
        }
        if key != atomicLoad(&zmin[j]) {
            continue;
        }
        let claimed = atomicCompareExchangeWeak(&winner_face[j], 0u, face + 1u);
        if claimed.exchanged {
            let n = surface_normal(face, hit.s);
            let view = normalize(fill.eye - hit.s.p);
            let color = shade(params.shading, face + 1u, n, view, params.light);
            let rgba = pack4x8unorm(vec4<f32>(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
            winner[j] = vec4<f32>(hit.uv, hit.t, bitcast<f32>(rgba));
        }
    }
}

// The filled pass keeps on-face fragments only (trimmed, as in step 1); the wireframe pass
// keeps every fragment of a cell not wholly off the face.
@fragment
fn fs_fill(in: VertexOut) {
    if (in.depth_whole & UNTRIMMED) != 0u || on_face(in, 0.0) {
        fill_ring(in.face, vec2<i32>(in.clip.xy), patch_to_uv(in.face, in.st));
    }
}
