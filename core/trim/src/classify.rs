//! The CPU point classifier (paper 000, sections 5 and 5.3), the reference for the GPU one:
//! descend the quadtree to the point's cell, stopping early — with the node's coverage bit —
//! when the node fits in the given footprint (the multiresolution access of section 5.3);
//! at a leaf, on / off cells answer directly, one-curve cells use the curve's implicit form
//! (5.1), two-curve cells first pick the curve on the point's side of the separating line
//! (5.2). Triangle classification (section 6) is here too.
//!
//! The classifier reads the structure through [`TrimSource`], which the quadtree and the
//! packed buffers both implement, so both are classified by the same code.

use crate::trim_source::{NodeKind, NodeRecord, TrimSource};

/// The outcome of classifying a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Classification {
    /// On the face.
    pub on: bool,
    /// The node the answer came from.
    pub node: u32,
    /// Its depth.
    pub depth: u32,
    /// Whether curves were evaluated (false: a coverage bit or an on / off leaf answered).
    pub used_curves: bool,
}

/// Whether normalised (s, t) is on the face in a leaf with curves.
pub fn leaf_point<S: TrimSource + ?Sized>(src: &S, n: &NodeRecord, s: f64, t: f64) -> bool {
    match n.kind {
        NodeKind::One => src.implicit(n.a).classify(s, t),
        NodeKind::Two => {
            let l = src.line(n.line).map(f64::from);
            let c = if l[0] * s + l[1] * t + l[2] >= 0.0 {
                n.a
            } else {
                n.b
            };
            src.implicit(c).classify(s, t)
        }
        NodeKind::On => true,
        NodeKind::Off => false,
        NodeKind::Failed | NodeKind::Internal => n.covered,
    }
}

/// Classifies (u, v). `footprint` is the (u, v) size of the largest rectangle inside the
/// pixel's footprint (figure 7): the descent stops at the first node no larger than it and
/// answers with its coverage bit. `[0, 0]` classifies exactly. Points outside the domain are
/// off.
pub fn classify<S: TrimSource + ?Sized>(
    src: &S,
    u: f64,
    v: f64,
    footprint: [f64; 2],
) -> Classification {
    let d = src.domain();
    let (w, h) = (d[1] - d[0], d[3] - d[2]);
    let s = (u - d[0]) / w;
    let t = (v - d[2]) / h;
    if !(0.0..=1.0).contains(&s) || !(0.0..=1.0).contains(&t) {
        return Classification {
            on: false,
            node: 0,
            depth: 0,
            used_curves: false,
        };
    }
    let (mut i, mut depth) = (0u32, 0u32);
    let (mut s0, mut t0, mut size) = (0.0f64, 0.0f64, 1.0f64);
    loop {
        let n = src.node(i);
        let small = size * w <= footprint[0] && size * h <= footprint[1];
        let done = |on: bool, used: bool| Classification {
            on,
            node: i,
            depth,
            used_curves: used,
        };
        if small {
            return done(n.covered, false);
        }
        match n.kind {
            NodeKind::Internal => {
                size *= 0.5;
                let hi_s = s >= s0 + size;
                let hi_t = t >= t0 + size;
                if hi_s {
                    s0 += size;
                }
                if hi_t {
                    t0 += size;
                }
                i = n.a + u32::from(hi_s) + 2 * u32::from(hi_t);
                depth += 1;
            }
            NodeKind::One | NodeKind::Two => return done(leaf_point(src, &n, s, t), true),
            _ => return done(leaf_point(src, &n, s, t), false),
        }
    }
}

/// Classifies a whole triangle of normalised coordinates lying in a leaf (section 6):
/// `Some(on)` when the leaf is on / off, or the triangle lies in the convex region of its
/// curve (two-curve leaves: all vertices on one side of the separating line first).
pub fn leaf_triangle<S: TrimSource + ?Sized>(
    src: &S,
    n: &NodeRecord,
    tri: &[[f64; 2]; 3],
) -> Option<bool> {
    match n.kind {
        NodeKind::On => Some(true),
        NodeKind::Off => Some(false),
        NodeKind::One => src.implicit(n.a).classify_triangle(tri),
        NodeKind::Two => {
            let l = src.line(n.line).map(f64::from);
            let sides = tri.map(|p| l[0] * p[0] + l[1] * p[1] + l[2] >= 0.0);
            if sides.iter().all(|&x| x) {
                src.implicit(n.a).classify_triangle(tri)
            } else if sides.iter().all(|&x| !x) {
                src.implicit(n.b).classify_triangle(tri)
            } else {
                None
            }
        }
        NodeKind::Internal | NodeKind::Failed => None,
    }
}
