//! The level k_i of paper 000 §6 by the triangle-classification pass's own rule
//! ([`crate::triangle_classification`], `shaders/triangle_classify.wgsl`), read on the CPU
//! when a part is prepared ([`crate::brep_scene`]): the minimum tessellation level a face
//! gets. A rule about the trim structure alone, kept below both the scene that stores k_i and
//! the pass that reads it.

use tessd_trim::multi_pack::MultiPack;
use tessd_trim::pack::NODE_INDEX_BITS;
use tessd_trim::quadtree::K_FRACTION;

/// The level k_i of paper 000 §6 as this renderer's triangulation has it: the smallest k ≤
/// `max_level` at which at least [`K_FRACTION`] of face `face`'s quadtree square lies in grid
/// cells (2^k × 2^k over the square) that the classification pass decides whole, or `None`
/// when no level up to `max_level` gets there. Section 6 asks this of the triangles the
/// renderer really draws; the quadtree's own estimate ([`tessd_trim::Quadtree::k_i`]) splits
/// cells along a diagonal and decides quadratic leaves by their convex region, which
/// `triangle_classify.wgsl` does not — so it is recomputed here with the shader's rule: the
/// node reached by a cell's centre, no deeper than k, decides the cell when it is an on / off
/// leaf, or a line leaf with the cell's four corners on one side.
pub fn classification_level(pack: &MultiPack, face: usize, max_level: u32) -> Option<u32> {
    (0..=max_level).find(|&k| decided_share(pack, face, k) >= K_FRACTION)
}

/// The share of face `face`'s quadtree square in level-`k` cells the pass decides whole.
pub fn decided_share(pack: &MultiPack, face: usize, k: u32) -> f64 {
    let h = &pack.headers[face];
    // (node, depth, cell origin); the side is 2^-depth.
    let mut stack = vec![(h.node_base, 0u32, [0.0f64; 2])];
    let mut share = 0.0;
    while let Some((node, depth, o)) = stack.pop() {
        let word = pack.nodes[node as usize];
        let side = 0.5f64.powi(depth as i32);
        let kind = word & 7;
        if kind == 0 && depth < k && depth < h.depth_limit {
            let first = word >> (32 - NODE_INDEX_BITS);
            let half = 0.5 * side;
            for c in 0..4u32 {
                let d = [f64::from(c & 1) * half, f64::from(c >> 1) * half];
                stack.push((first + c, depth + 1, [o[0] + d[0], o[1] + d[1]]));
            }
            continue;
        }
        share += match kind {
            1 | 2 => side * side,
            3 => {
                // The node's level-k cells with their four corners on one side of the line.
                let n = 1u32 << k.saturating_sub(depth);
                let step = side / f64::from(n);
                let index = word >> (32 - NODE_INDEX_BITS);
                let on = |i: u32, j: u32| {
                    let (x, y) = (o[0] + f64::from(i) * step, o[1] + f64::from(j) * step);
                    pack.curve(index, 0, x as f32, y as f32)
                };
                let mut whole = 0u32;
                for j in 0..n {
                    for i in 0..n {
                        let c = [on(i, j), on(i + 1, j), on(i, j + 1), on(i + 1, j + 1)];
                        whole += u32::from(c.iter().all(|&x| x) || c.iter().all(|&x| !x));
                    }
                }
                f64::from(whole) * step * step
            }
            _ => 0.0,
        };
    }
    share
}
