//! The flat layout of a trim structure for GPU storage buffers (paper 000, section 7: the
//! structure lives in video memory and the fragment shader walks it): three arrays and a
//! small header, all 4-byte words.
//!
//! - `header`: 4 × f32, the domain `[u0, u1, v0, v1]`;
//! - `nodes`: 4 × u32 per node, breadth first, the four children of a node consecutive:
//!   word 0 = kind (bits 0–2: 0 internal, 1 off, 2 on, 3 one curve, 4 two curves, 5 failed)
//!   | coverage bit << 3 | depth << 4; word 1 = first child (internal) or first curve;
//!   word 2 = second curve; word 3 = separating line (`u32::MAX` where absent);
//! - `curves`: 8 × f32 per curve: the affine map (u, v) → (x, y) of section 3.2 in the
//!   domain's normalised coordinates (6 floats), the kind (0 line, 1 convex, 2 concave), 0;
//! - `lines`: 4 × f32 per separating line: a, b, c, 0 (`a s + b t + c ≥ 0`: first curve).
//!
//! [`PackedTrim`] implements [`TrimSource`], so the CPU classifier runs on the packed form
//! unchanged — which is how the layout is tested.

use crate::classify::{NodeRecord, TrimSource};
use crate::implicit::{Implicit, ImplicitKind};
use crate::quadtree::{NodeKind, Quadtree};

/// Words per node.
pub const NODE_WORDS: usize = 4;
/// Floats per curve.
pub const CURVE_FLOATS: usize = 8;
/// Floats per separating line.
pub const LINE_FLOATS: usize = 4;

/// The packed structure.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedTrim {
    /// `[u0, u1, v0, v1]` as the GPU reads it.
    pub header: [f32; 4],
    /// The domain in f64, for CPU classification of the packed form.
    pub domain: [f64; 4],
    /// The nodes.
    pub nodes: Vec<u32>,
    /// The curves.
    pub curves: Vec<f32>,
    /// The separating lines.
    pub lines: Vec<f32>,
}

fn kind_code(k: NodeKind) -> u32 {
    k as u32
}

fn kind_of(code: u32) -> NodeKind {
    match code & 7 {
        0 => NodeKind::Internal,
        1 => NodeKind::Off,
        2 => NodeKind::On,
        3 => NodeKind::One,
        4 => NodeKind::Two,
        _ => NodeKind::Failed,
    }
}

impl PackedTrim {
    /// Packs `tree`.
    pub fn pack(tree: &Quadtree) -> PackedTrim {
        let mut nodes = Vec::with_capacity(tree.nodes.len() * NODE_WORDS);
        for i in 0..tree.nodes.len() {
            let n = &tree.nodes[i];
            let r = tree.node(i as u32);
            nodes.push(kind_code(r.kind) | (u32::from(r.covered) << 3) | (n.depth << 4));
            nodes.push(r.a);
            nodes.push(r.b);
            nodes.push(r.line);
        }
        let mut curves = Vec::with_capacity(tree.implicits.len() * CURVE_FLOATS);
        for c in &tree.implicits {
            curves.extend_from_slice(&c.m);
            curves.push(c.kind as u32 as f32);
            curves.push(0.0);
        }
        let mut lines = Vec::with_capacity(tree.lines.len() * LINE_FLOATS);
        for l in &tree.lines {
            lines.extend_from_slice(l);
            lines.push(0.0);
        }
        PackedTrim {
            header: tree.domain.map(|x| x as f32),
            domain: tree.domain,
            nodes,
            curves,
            lines,
        }
    }

    /// The size on the GPU, in bytes: header, nodes, curves and lines.
    pub fn bytes(&self) -> usize {
        4 * (self.header.len() + self.nodes.len() + self.curves.len() + self.lines.len())
    }
}

impl TrimSource for PackedTrim {
    fn domain(&self) -> [f64; 4] {
        self.domain
    }

    fn node(&self, i: u32) -> NodeRecord {
        let w = &self.nodes[i as usize * NODE_WORDS..(i as usize + 1) * NODE_WORDS];
        NodeRecord {
            kind: kind_of(w[0]),
            covered: w[0] & 8 != 0,
            a: w[1],
            b: w[2],
            line: w[3],
        }
    }

    fn implicit(&self, i: u32) -> Implicit {
        let c = &self.curves[i as usize * CURVE_FLOATS..(i as usize + 1) * CURVE_FLOATS];
        Implicit {
            m: [c[0], c[1], c[2], c[3], c[4], c[5]],
            kind: match c[6] as u32 {
                0 => ImplicitKind::Line,
                1 => ImplicitKind::Convex,
                _ => ImplicitKind::Concave,
            },
        }
    }

    fn line(&self, i: u32) -> [f32; 3] {
        let l = &self.lines[i as usize * LINE_FLOATS..];
        [l[0], l[1], l[2]]
    }
}
