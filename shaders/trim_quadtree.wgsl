// The trim walk of paper 000 §5 (quadtree descent), §5.1 (the implicit test of a quadratic
// Bézier curve), §5.2 (a two-curve leaf's separating line) and §5.3 (the multiresolution stop:
// a node whose cell is under a pixel answers with its coverage bit), as WGSL functions over
// the four flat buffers of `tessd_trim::multi_pack::MultiPack`. It is `MultiPack::walk_from`
// transcribed: the same f32 arithmetic in the same order and the same branch order, so that
// its answers equal the CPU reference's except where a driver's fused multiply-add rounds a
// point lying within an ulp of a line or a curve to the other side.
//
// A library, not a pass: the shader that includes it (the Rust side concatenates the
// sources) declares the four buffers under these names, at bindings of its choosing:
//   var<storage, read> trim_headers: array<TrimHeader>;
//   var<storage, read> trim_nodes: array<u32>;
//   var<storage, read> trim_curves: array<f32>;
//   var<storage, read> trim_lines: array<u32>;

// `tessd_trim::multi_pack::FaceHeader` (40 bytes).
struct TrimHeader {
    origin: vec2<f32>,
    scale: vec2<f32>,
    node_base: u32,
    curve_base: u32,
    line_base: u32,
    k_i: u32,
    depth_limit: u32,
    pad: u32,
}

const TRIM_NODE_INDEX_BITS: u32 = 28u;
const TRIM_REF_INDEX_BITS: u32 = 30u;
const TRIM_CURVE_FLOATS: u32 = 6u;
const TRIM_LINE_WORDS: u32 = 5u;

// Where a walk starts: the root (depth 0, origin 0), or the node that triangle classification
// (§6) handed down for the cell the point lies in.
struct TrimStart {
    node: u32,
    depth: u32,
    origin: vec2<f32>,
}

// 2^−depth, exactly.
fn trim_side(depth: u32) -> f32 {
    return bitcast<f32>((127u - min(depth, 126u)) << 23u);
}

// Patch (s, t) of `face` in its quadtree's normalised coordinates.
fn trim_to_tree(face: u32, st: vec2<f32>) -> vec2<f32> {
    let h = trim_headers[face];
    return vec2<f32>(h.scale.x * st.x + h.origin.x, h.scale.y * st.y + h.origin.y);
}

// The root of `face`.
fn trim_root(face: u32) -> TrimStart {
    return TrimStart(trim_headers[face].node_base, 0u, vec2<f32>(0.0));
}

// §5.1: curve `c` of kind `kind` (0 line, 1 convex, 2 concave) at (x, y).
fn trim_curve(c: u32, kind: u32, x: f32, y: f32) -> bool {
    let m = c * TRIM_CURVE_FLOATS;
    let px = trim_curves[m] * x + trim_curves[m + 1u] * y + trim_curves[m + 2u];
    let py = trim_curves[m + 3u] * x + trim_curves[m + 4u] * y + trim_curves[m + 5u];
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

// §5–5.3: whether patch point `st` of `face` is on the face, walking from `start` (a point of
// that node's cell). The descent stops at a node whose cell side is under `stop` (quadtree
// units; 0 walks to the leaf) and answers with its coverage bit (§5.3). Points mapping
// outside the quadtree are off.
fn trim_walk_from(face: u32, start: TrimStart, st: vec2<f32>, stop: f32) -> bool {
    let h = trim_headers[face];
    let x = h.scale.x * st.x + h.origin.x;
    let y = h.scale.y * st.y + h.origin.y;
    if !(x >= 0.0 && x <= 1.0 && y >= 0.0 && y <= 1.0) {
        return false;
    }
    var i = start.node;
    var size = trim_side(start.depth);
    var x0 = start.origin.x;
    var y0 = start.origin.y;
    var word = 0u;
    for (var d = start.depth; d <= h.depth_limit; d += 1u) {
        word = trim_nodes[i];
        let index = word >> (32u - TRIM_NODE_INDEX_BITS);
        let kind = word & 7u;
        if kind == 0u {
            if size < stop {
                return (word & 8u) != 0u;
            }
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
        } else if size < stop {
            return (word & 8u) != 0u;
        } else if kind <= 5u {
            return trim_curve(index, kind - 3u, x, y);
        } else if kind == 6u {
            // §5.2: the separating line picks one of the leaf's two curves.
            let r0 = index * TRIM_LINE_WORDS;
            let a = bitcast<f32>(trim_lines[r0]);
            let b = bitcast<f32>(trim_lines[r0 + 1u]);
            let c = bitcast<f32>(trim_lines[r0 + 2u]);
            var r: u32;
            if a * x + b * y + c >= 0.0 {
                r = trim_lines[r0 + 3u];
            } else {
                r = trim_lines[r0 + 4u];
            }
            let mask = (1u << TRIM_REF_INDEX_BITS) - 1u;
            return trim_curve(r & mask, r >> TRIM_REF_INDEX_BITS, x, y);
        } else {
            return (word & 8u) != 0u;
        }
    }
    // Not reached on a well-formed pack: the deepest leaf ends the loop.
    return (word & 8u) != 0u;
}

// The walk from the root, to the leaf.
fn trim_walk(face: u32, st: vec2<f32>) -> bool {
    return trim_walk_from(face, trim_root(face), st, 0.0);
}
