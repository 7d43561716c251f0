//! The flat layout of a trim structure for GPU storage buffers (paper 000, section 7: the
//! structure lives in video memory and the fragment shader walks it; table 3 counts its
//! bytes): three arrays of 4-byte words and a small header.
//!
//! - `header`: 4 × f32, the domain `[u0, u1, v0, v1]`;
//! - `nodes`: **one u32 per node**, breadth first, the four children of a node consecutive
//!   (in the order of [`TrimSource::node`]): bits 0–2 the kind — 0 internal, 1 off, 2 on,
//!   3 / 4 / 5 one curve that is a line / convex / concave, 6 two curves, 7 failed —, bit 3
//!   the coverage bit (section 5.3), bits 4–31 an index: the first child (internal), the
//!   curve (one curve) or the two-curve record (two curves), 0 otherwise;
//! - `curves`: 6 × f32 per curve, the affine map (u, v) → (x, y) of section 3.2 in the
//!   domain's normalised coordinates (`x = m0 s + m1 t + m2`, `y = m3 s + m4 t + m5`);
//! - `lines`: 5 words per two-curve leaf (section 5.2): the separating line a, b, c as f32
//!   bits (`a s + b t + c ≥ 0`: first curve), then the two curve references
//!   ([`crate::trim_source::curve_ref`]: index in bits 0–29, kind in bits 30–31 — 0 line,
//!   1 convex, 2 concave).
//!
//! The paper gives no word layout (section 7 only says the quadtree and the curves live in
//! video memory). This one stores what section 4 asks of a node — the coverage bit, and
//! references to at most two curves — in a single word: a node's depth and cell are known
//! to the walk that reaches it, the curve kinds ride on the references, and the second curve
//! of a two-curve leaf sits with the separating line it always comes with.
//!
//! [`PackedTrim`] implements [`TrimSource`], so the CPU classifier runs on the packed form
//! unchanged — which is how the layout is tested.

use crate::implicit::{Implicit, ImplicitKind};
use crate::quadtree::{NONE, Quadtree};
use crate::trim_source::{NodeKind, NodeRecord, TrimSource, curve_ref, ref_index, ref_kind};

/// Words per node.
pub const NODE_WORDS: usize = 1;
/// Floats per curve.
pub const CURVE_FLOATS: usize = 6;
/// Words per two-curve record (separating line and the two curve references).
pub const LINE_WORDS: usize = 5;
/// The bits of a node word that hold its index (bits 4–31).
pub const NODE_INDEX_BITS: u32 = 28;

/// The packed structure.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedTrim {
    /// `[u0, u1, v0, v1]` as the GPU reads it.
    pub header: [f32; 4],
    /// The domain in f64, for CPU classification of the packed form.
    pub domain: [f64; 4],
    /// The nodes, one word each.
    pub nodes: Vec<u32>,
    /// The curves' maps.
    pub curves: Vec<f32>,
    /// The two-curve records: line coefficients (f32 bits) and curve references.
    pub lines: Vec<u32>,
}

/// The kind code of a node word (bits 0–2).
fn kind_code(kind: NodeKind, first: Option<ImplicitKind>) -> u32 {
    match kind {
        NodeKind::Internal => 0,
        NodeKind::Off => 1,
        NodeKind::On => 2,
        NodeKind::One => match first.expect("a one-curve leaf has a curve") {
            ImplicitKind::Line => 3,
            ImplicitKind::Convex => 4,
            ImplicitKind::Concave => 5,
        },
        NodeKind::Two => 6,
        NodeKind::Failed => 7,
    }
}

impl PackedTrim {
    /// Packs `tree`.
    ///
    /// # Panics
    /// When an index does not fit its bits: 2^28 nodes or two-curve leaves, or 2^30 curves
    /// (far beyond what a face's tree can hold in memory).
    pub fn pack(tree: &Quadtree) -> PackedTrim {
        let index = |i: u32| {
            assert!(
                i < 1 << NODE_INDEX_BITS,
                "index {i} does not fit a node word"
            );
            i << (32 - NODE_INDEX_BITS)
        };
        let mut nodes = Vec::with_capacity(tree.nodes.len() * NODE_WORDS);
        let mut lines = Vec::with_capacity(tree.lines.len() * LINE_WORDS);
        for i in 0..tree.nodes.len() as u32 {
            let r = tree.node(i);
            let first = (r.kind == NodeKind::One).then(|| ref_kind(r.a));
            let word = kind_code(r.kind, first) | u32::from(r.covered) << 3;
            nodes.push(
                word | match r.kind {
                    NodeKind::Internal => index(r.a),
                    NodeKind::One => index(ref_index(r.a)),
                    NodeKind::Two => {
                        // Records follow the lines' order: record k is line k.
                        debug_assert_eq!(r.line as usize * LINE_WORDS, lines.len());
                        lines.extend(tree.lines[r.line as usize].map(f32::to_bits));
                        lines.push(r.a);
                        lines.push(r.b);
                        index(r.line)
                    }
                    NodeKind::Off | NodeKind::On | NodeKind::Failed => 0,
                },
            );
        }
        let mut curves = Vec::with_capacity(tree.implicits.len() * CURVE_FLOATS);
        for c in &tree.implicits {
            curves.extend_from_slice(&c.m);
        }
        PackedTrim {
            header: tree.domain.map(|x| x as f32),
            domain: tree.domain,
            nodes,
            curves,
            lines,
        }
    }

    /// The size on the GPU, in bytes: header, nodes, curves and two-curve records.
    pub fn bytes(&self) -> usize {
        4 * (self.header.len() + self.nodes.len() + self.curves.len() + self.lines.len())
    }
}

impl TrimSource for PackedTrim {
    fn domain(&self) -> [f64; 4] {
        self.domain
    }

    fn node(&self, i: u32) -> NodeRecord {
        let w = self.nodes[i as usize];
        let index = w >> (32 - NODE_INDEX_BITS);
        let covered = w & 8 != 0;
        let leaf = |kind: NodeKind, a: u32| NodeRecord {
            kind,
            covered,
            a,
            b: NONE,
            line: NONE,
        };
        match w & 7 {
            0 => leaf(NodeKind::Internal, index),
            1 => leaf(NodeKind::Off, NONE),
            2 => leaf(NodeKind::On, NONE),
            3 => leaf(NodeKind::One, curve_ref(index, ImplicitKind::Line)),
            4 => leaf(NodeKind::One, curve_ref(index, ImplicitKind::Convex)),
            5 => leaf(NodeKind::One, curve_ref(index, ImplicitKind::Concave)),
            6 => {
                let rec = &self.lines[index as usize * LINE_WORDS..][..LINE_WORDS];
                NodeRecord {
                    kind: NodeKind::Two,
                    covered,
                    a: rec[3],
                    b: rec[4],
                    line: index,
                }
            }
            _ => leaf(NodeKind::Failed, NONE),
        }
    }

    fn implicit(&self, r: u32) -> Implicit {
        let i = ref_index(r) as usize;
        let c = &self.curves[i * CURVE_FLOATS..(i + 1) * CURVE_FLOATS];
        Implicit {
            m: [c[0], c[1], c[2], c[3], c[4], c[5]],
            kind: ref_kind(r),
        }
    }

    fn line(&self, i: u32) -> [f32; 3] {
        let l = &self.lines[i as usize * LINE_WORDS..];
        [l[0], l[1], l[2]].map(f32::from_bits)
    }
}
