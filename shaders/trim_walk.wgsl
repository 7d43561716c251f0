// The trim walk of paper 000 §5 (quadtree descent), §5.1 (the implicit test of a quadratic
// Bézier curve) and §5.2–5.3 (the two-curve leaf and its separating line), as a compute
// shader over a batch of query points. It is `tessd_trim::multi_pack::MultiPack::walk`
// transcribed: the same f32 arithmetic in the same order and the same branch order, so that
// its answers equal the CPU reference's except where a driver's fused multiply-add rounds a
// point lying within an ulp of a line or a curve to the other side.
//
// Buffers (the layout of `tessd_trim::multi_pack`): the face header table, the node words,
// the curve maps (6 floats each), the two-curve records (5 words each), the queries
// (face, s, t) and one output word per query (1 on the face, 0 off).

struct FaceHeader {
    origin: vec2<f32>,
    scale: vec2<f32>,
    node_base: u32,
    curve_base: u32,
    line_base: u32,
    k_i: u32,
    depth_limit: u32,
    pad: u32,
}

struct Query {
    face: u32,
    s: f32,
    t: f32,
}

@group(0) @binding(0) var<storage, read> headers: array<FaceHeader>;
@group(0) @binding(1) var<storage, read> nodes: array<u32>;
@group(0) @binding(2) var<storage, read> curves: array<f32>;
@group(0) @binding(3) var<storage, read> lines: array<u32>;
@group(0) @binding(4) var<storage, read> queries: array<Query>;
@group(0) @binding(5) var<storage, read_write> results: array<u32>;

const NODE_INDEX_BITS: u32 = 28u;
const REF_INDEX_BITS: u32 = 30u;
const CURVE_FLOATS: u32 = 6u;
const LINE_WORDS: u32 = 5u;
const WORKGROUP: u32 = 64u;

// §5.1: curve `c` of kind `kind` (0 line, 1 convex, 2 concave) at (x, y).
fn curve(c: u32, kind: u32, x: f32, y: f32) -> bool {
    let m = c * CURVE_FLOATS;
    let px = curves[m] * x + curves[m + 1u] * y + curves[m + 2u];
    let py = curves[m + 3u] * x + curves[m + 4u] * y + curves[m + 5u];
    var convex: bool;
    if kind == 0u {
        convex = px >= 0.0;
    } else if py < 0.0 || py - 2.0 * px + 1.0 < 0.0 {
        convex = false;
    } else if py - px >= 0.0 {
        convex = true;
    } else {
        convex = py - px * px >= 0.0;
    }
    return convex == (kind != 2u);
}

// §5: the walk from the face's root for patch point (s, t).
fn walk(face: u32, s: f32, t: f32) -> bool {
    let h = headers[face];
    let x = h.scale.x * s + h.origin.x;
    let y = h.scale.y * t + h.origin.y;
    if !(x >= 0.0 && x <= 1.0 && y >= 0.0 && y <= 1.0) {
        return false;
    }
    var i = h.node_base;
    var size = 1.0;
    var x0 = 0.0;
    var y0 = 0.0;
    var word = 0u;
    for (var d = 0u; d <= h.depth_limit; d += 1u) {
        word = nodes[i];
        let index = word >> (32u - NODE_INDEX_BITS);
        let kind = word & 7u;
        if kind == 0u {
            size *= 0.5;
            let hi_x = x >= x0 + size;
            let hi_y = y >= y0 + size;
            if hi_x {
                x0 += size;
            }
            if hi_y {
                y0 += size;
            }
            i = index + select(0u, 1u, hi_x) + select(0u, 2u, hi_y);
        } else if kind == 1u {
            return false;
        } else if kind == 2u {
            return true;
        } else if kind <= 5u {
            return curve(index, kind - 3u, x, y);
        } else if kind == 6u {
            // §5.2–5.3: the separating line picks one of the leaf's two curves.
            let r0 = index * LINE_WORDS;
            let a = bitcast<f32>(lines[r0]);
            let b = bitcast<f32>(lines[r0 + 1u]);
            let c = bitcast<f32>(lines[r0 + 2u]);
            var r: u32;
            if a * x + b * y + c >= 0.0 {
                r = lines[r0 + 3u];
            } else {
                r = lines[r0 + 4u];
            }
            let mask = (1u << REF_INDEX_BITS) - 1u;
            return curve(r & mask, r >> REF_INDEX_BITS, x, y);
        } else {
            return (word & 8u) != 0u;
        }
    }
    // Not reached on a well-formed pack: the deepest leaf ends the loop.
    return (word & 8u) != 0u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let q = gid.x + gid.y * groups.x * WORKGROUP;
    if q >= arrayLength(&queries) || q >= arrayLength(&results) {
        return;
    }
    let p = queries[q];
    var on = false;
    if p.face < arrayLength(&headers) {
        on = walk(p.face, p.s, p.t);
    }
    results[q] = select(0u, 1u, on);
}
