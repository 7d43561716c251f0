//! Several faces' packed trim structures in one set of flat buffers (paper 000, section 7:
//! the quadtrees and curves live in video memory, where the shaders walk them), with the
//! f32 reference walk the fragment shader will run (sections 5, 5.1–5.3) and the hand-off
//! from triangle classification to it (section 6).
//!
//! Layout ([`MultiPack`]): the faces' [`PackedTrim`] arrays concatenated, each kept in its
//! own encoding (see [`crate::pack`]) but with every stored index *rebased* to the
//! concatenated arrays — a node word's first child (+ node base), curve (+ curve base) or
//! two-curve record (+ line base), and the curve references of a record (+ curve base) — so
//! that a walk needs a face's header only to find its root. The per-face header table
//! ([`FaceHeader`], 40 bytes, std430-compatible) replaces each face's 16-byte f32 domain
//! header of [`PackedTrim`]: [`MultiPack::bytes`] is the sum of the faces' packed sizes
//! without that domain header, plus the table.
//!
//! Coordinates: the tessellation stage hands the fragment a point of the face's *patch* —
//! normalised (s, t) ∈ [0, 1]² over the rectangle that was tessellated (normally the face's
//! `bounds`). The quadtree's root covers a slightly larger (u, v) rectangle (the bounds grown
//! to hold every trim piece), so the header carries the affine map from patch (s, t) to the
//! quadtree's normalised coordinates, in f32: `x = scale.x · s + origin.x`, likewise y.

use crate::TrimStructure;
use crate::pack::{CURVE_FLOATS, LINE_WORDS, NODE_INDEX_BITS, PackedTrim};
use crate::trim_source::REF_INDEX_BITS;

/// [`FaceHeader::k_i`] of a face without a triangle level (section 6).
pub const NO_LEVEL: u32 = u32::MAX;

/// One face's entry in the header table, as a shader reads it (std430: 10 words, 40 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FaceHeader {
    /// The patch → quadtree map's offset: the quadtree coordinates of patch (0, 0).
    pub origin: [f32; 2],
    /// The patch → quadtree map's scale: the patch's size in quadtree coordinates.
    pub scale: [f32; 2],
    /// The face's root: its first node word in [`MultiPack::nodes`].
    pub node_base: u32,
    /// The face's first curve in [`MultiPack::curves`] (in curves of
    /// [`CURVE_FLOATS`] floats).
    pub curve_base: u32,
    /// The face's first two-curve record in [`MultiPack::lines`] (in records of
    /// [`LINE_WORDS`] words).
    pub line_base: u32,
    /// The triangle level k_i of section 6, or [`NO_LEVEL`].
    pub k_i: u32,
    /// The depth of the face's deepest leaf: a walk from the root visits at most
    /// `depth_limit + 1` nodes, the bound of the shader's loop.
    pub depth_limit: u32,
    /// Padding to the std430 alignment of the struct (8 bytes); zero.
    pub pad: u32,
}

/// Bytes per header-table entry.
pub const FACE_HEADER_BYTES: usize = std::mem::size_of::<FaceHeader>();

/// The packed trim structures of several faces (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MultiPack {
    /// One entry per face, in the order the faces were pushed.
    pub headers: Vec<FaceHeader>,
    /// All faces' node words, indices rebased.
    pub nodes: Vec<u32>,
    /// All faces' curve maps.
    pub curves: Vec<f32>,
    /// All faces' two-curve records, curve references rebased.
    pub lines: Vec<u32>,
}

/// Where the walk of a fragment starts, found once per tessellation cell (section 6): the
/// deepest node whose cell holds the whole (s, t) cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellHandoff {
    /// The node, an index into [`MultiPack::nodes`].
    pub node: u32,
    /// Its depth (the root is 0).
    pub depth: u32,
    /// The quadtree coordinates of its cell's lower-left corner; the side is 2^−depth.
    pub origin: [f32; 2],
    /// `Some(on)` when the node is an on / off leaf: the whole cell classifies without
    /// walking (section 6's first case); `None` otherwise.
    pub whole: Option<bool>,
}

/// 2^−depth, exactly, in f32.
fn side(depth: u32) -> f32 {
    f32::from_bits((127 - depth.min(126)) << 23)
}

impl MultiPack {
    /// An empty pack.
    pub fn new() -> MultiPack {
        MultiPack::default()
    }

    /// Appends the packed structure of `trim`, whose patch (the tessellated (u, v)
    /// rectangle that normalised (s, t) refer to) is `patch = [u0, u1, v0, v1]`, normally the
    /// face's `bounds`. Returns the face's index in the pack.
    ///
    /// # Panics
    /// When a rebased index no longer fits its bits (2^28 nodes or two-curve records, 2^28
    /// curves in all).
    pub fn push(&mut self, trim: &TrimStructure, patch: [f64; 4]) -> usize {
        let p: &PackedTrim = &trim.packed;
        let d = p.domain;
        let (w, h) = (d[1] - d[0], d[3] - d[2]);
        let node_base = (self.nodes.len() / crate::pack::NODE_WORDS) as u32;
        let curve_base = (self.curves.len() / CURVE_FLOATS) as u32;
        let line_base = (self.lines.len() / LINE_WORDS) as u32;
        let shift = 32 - NODE_INDEX_BITS;
        let rebase = |w: u32, base: u32| {
            let i = (w >> shift) + base;
            assert!(
                i < 1 << NODE_INDEX_BITS,
                "index {i} does not fit a node word"
            );
            (w & ((1 << shift) - 1)) | i << shift
        };
        self.nodes.extend(p.nodes.iter().map(|&w| match w & 7 {
            0 => rebase(w, node_base),
            3..=5 => rebase(w, curve_base),
            6 => rebase(w, line_base),
            _ => w,
        }));
        self.curves.extend_from_slice(&p.curves);
        let mask = (1u32 << REF_INDEX_BITS) - 1;
        self.lines
            .extend(p.lines.chunks(LINE_WORDS).flat_map(|rec| {
                let r = |x: u32| {
                    let i = (x & mask) + curve_base;
                    assert!(i <= mask, "curve index {i} does not fit a reference");
                    (x & !mask) | i
                };
                [rec[0], rec[1], rec[2], r(rec[3]), r(rec[4])]
            }));
        self.headers.push(FaceHeader {
            origin: [
                ((patch[0] - d[0]) / w) as f32,
                ((patch[2] - d[2]) / h) as f32,
            ],
            scale: [
                ((patch[1] - patch[0]) / w) as f32,
                ((patch[3] - patch[2]) / h) as f32,
            ],
            node_base,
            curve_base,
            line_base,
            k_i: trim.stats.k_i.unwrap_or(NO_LEVEL),
            depth_limit: trim.stats.max_depth,
            pad: 0,
        });
        self.headers.len() - 1
    }

    /// The size on the GPU, in bytes: the four buffers.
    pub fn bytes(&self) -> usize {
        self.headers.len() * FACE_HEADER_BYTES
            + 4 * (self.nodes.len() + self.curves.len() + self.lines.len())
    }

    /// The header table as bytes, for a storage buffer.
    pub fn header_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.headers)
    }

    /// Patch (s, t) of face `face` in its quadtree's normalised coordinates, in f32 as the
    /// shader computes it.
    pub fn to_tree(&self, face: usize, s: f32, t: f32) -> [f32; 2] {
        let h = &self.headers[face];
        [h.scale[0] * s + h.origin[0], h.scale[1] * t + h.origin[1]]
    }

    /// Whether patch point (s, t) of face `face` is on the face: the fragment shader's walk
    /// from the root (sections 5, 5.1, 5.2), all in f32. Points mapping outside the quadtree
    /// are off.
    pub fn walk(&self, face: usize, s: f32, t: f32) -> bool {
        let h = &self.headers[face];
        let start = CellHandoff {
            node: h.node_base,
            depth: 0,
            origin: [0.0, 0.0],
            whole: None,
        };
        self.walk_from(face, &start, s, t)
    }

    /// The walk resumed from a hand-off (section 6: "la classification des fragments
    /// reprendra à partir de ce nœud"); (s, t) must lie in the cell the hand-off was found
    /// for ([`MultiPack::classify_cell`]), and then the answer is [`MultiPack::walk`]'s.
    pub fn walk_from(&self, face: usize, from: &CellHandoff, s: f32, t: f32) -> bool {
        let h = &self.headers[face];
        let [x, y] = self.to_tree(face, s, t);
        if !((0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y)) {
            return false;
        }
        let (mut i, mut size) = (from.node, side(from.depth));
        let [mut x0, mut y0] = from.origin;
        let mut word = 0;
        for _ in from.depth..=h.depth_limit {
            word = self.nodes[i as usize];
            let index = word >> (32 - NODE_INDEX_BITS);
            match word & 7 {
                0 => {
                    size *= 0.5;
                    let hi_x = x >= x0 + size;
                    let hi_y = y >= y0 + size;
                    if hi_x {
                        x0 += size;
                    }
                    if hi_y {
                        y0 += size;
                    }
                    i = index + u32::from(hi_x) + 2 * u32::from(hi_y);
                }
                1 => return false,
                2 => return true,
                k @ 3..=5 => return self.curve(index, k - 3, x, y),
                6 => {
                    let rec = &self.lines[index as usize * LINE_WORDS..][..LINE_WORDS];
                    let [a, b, c] = [rec[0], rec[1], rec[2]].map(f32::from_bits);
                    let r = if a * x + b * y + c >= 0.0 {
                        rec[3]
                    } else {
                        rec[4]
                    };
                    let mask = (1u32 << REF_INDEX_BITS) - 1;
                    return self.curve(r & mask, r >> REF_INDEX_BITS, x, y);
                }
                _ => return word & 8 != 0,
            }
        }
        // Not reached on a well-formed pack: the deepest leaf ends the loop.
        word & 8 != 0
    }

    /// Section 5.1 in f32: whether quadtree point (x, y) is on the face's side of curve `c`
    /// (an index into [`MultiPack::curves`] in curves) of kind `kind` (0 line, 1 convex,
    /// 2 concave), as the shaders' `trim_curve` decides it.
    pub fn curve(&self, c: u32, kind: u32, x: f32, y: f32) -> bool {
        let m = &self.curves[c as usize * CURVE_FLOATS..][..CURVE_FLOATS];
        let px = m[0] * x + m[1] * y + m[2];
        let py = m[3] * x + m[4] * y + m[5];
        let convex = if kind == 0 {
            px >= 0.0
        } else if py < 0.0 || py - 2.0 * px + 1.0 < 0.0 {
            false
        } else if py - px >= 0.0 {
            true
        } else {
            py - px * px >= 0.0
        };
        convex == (kind != 2)
    }

    /// Triangle classification's hand-off (section 6) for the square patch cell of face
    /// `face` with lower-left corner `origin` and side `size`, in (s, t): the deepest node
    /// whose cell holds the whole cell, as the walk would descend (a point at a child's
    /// lower bound goes to the upper child). A cell that leaves the quadtree gets the root.
    pub fn classify_cell(&self, face: usize, origin: [f32; 2], size: f32) -> CellHandoff {
        let h = &self.headers[face];
        let lo = self.to_tree(face, origin[0], origin[1]);
        let hi = self.to_tree(face, origin[0] + size, origin[1] + size);
        let (mut i, mut depth, mut side) = (h.node_base, 0u32, 1.0f32);
        let mut o = [0.0f32, 0.0];
        let inside = lo.iter().chain(&hi).all(|v| (0.0..=1.0).contains(v));
        while inside && depth < h.depth_limit {
            let word = self.nodes[i as usize];
            if word & 7 != 0 {
                break;
            }
            let half = side * 0.5;
            let pick = |axis: usize| {
                let mid = o[axis] + half;
                if hi[axis] < mid {
                    Some(false)
                } else if lo[axis] >= mid {
                    Some(true)
                } else {
                    None
                }
            };
            let (Some(hx), Some(hy)) = (pick(0), pick(1)) else {
                break;
            };
            if hx {
                o[0] += half;
            }
            if hy {
                o[1] += half;
            }
            side = half;
            depth += 1;
            i = (word >> (32 - NODE_INDEX_BITS)) + u32::from(hx) + 2 * u32::from(hy);
        }
        let whole = match self.nodes[i as usize] & 7 {
            1 if inside => Some(false),
            2 if inside => Some(true),
            _ => None,
        };
        CellHandoff {
            node: i,
            depth,
            origin: o,
            whole,
        }
    }
}
