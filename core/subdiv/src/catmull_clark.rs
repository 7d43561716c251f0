//! Catmull–Clark refinement, one level: new faces and the stencil table (paper 002, section 5.4).
//!
//! The paper factors a Catmull–Clark step into linear subdivision followed by averaging, with
//! the correction `p' + w(n)(p − p')` for extraordinary vertices (Warren–Schaefer). Composed,
//! those steps give the classic masks, which is what this file writes as stencils: a face point
//! is its face's centroid; a smooth edge point is `(a + b + F₀ + F₁)/4`; a smooth vertex point
//! of valence `n` is `((n − 2)/n)·v + (1/n²)·Σ edge neighbours + (1/n²)·Σ face points`. Writing
//! the composed mask lets every new vertex be one independent row (the GPU part, section 6) and
//! makes the n-gon first level fall out of the same code.
//!
//! Sharp features follow OpenSubdiv's `Sdc` rules, which Blender's modifier runs: boundary edges
//! are infinitely sharp; an edge of sharpness `s > 0` gives a midpoint edge point; a vertex with
//! two sharp edges uses the crease mask `(a + 6v + b)/8`, three or more (or a corner) stays put;
//! sharpness decreases by one per level (the *uniform* creasing method), and where a rule changes
//! between a level and the next, the point blends the two masks by the fractional sharpness
//! (semi-sharp creases, integer and fractional).

use crate::boundary::Boundary;
use crate::halfedges::Halfedges;
use crate::level::table_for;
use crate::sharpness::decrement;
use crate::stencil::StencilTable;
use crate::topology::{Faces, NONE, Topology};
use rayon::prelude::*;

/// A vertex's rule, by how many sharp edges meet there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Rule {
    Smooth,
    Crease,
    Corner,
}

/// The stencils of one Catmull–Clark step over `h`: face points, then edge points, then
/// vertex points (the numbering of [`Halfedges::refine`] and of OpenSubdiv's uniform
/// refinement). Each row is written directly in its final form — the composed mask's terms,
/// each source once in the common cases — with no per-row sorting.
pub fn stencils(h: &Halfedges, boundary: Boundary) -> StencilTable {
    let (nf, ne, nv) = (h.faces.len(), h.edge_count(), h.faces.vertex_count as usize);
    let rows = nf + ne + nv;
    // Rows are independent: build chunks in parallel, then concatenate.
    let parts: Vec<StencilTable> = (0..rows.div_ceil(ROWS_PER_TASK))
        .into_par_iter()
        .map(|task| {
            let range = task * ROWS_PER_TASK..((task + 1) * ROWS_PER_TASK).min(rows);
            let mut w = Writer {
                table: table_for(h.faces.vertex_count, range.len()),
                fan: Vec::new(),
                blend: Vec::new(),
            };
            w.table.sources.reserve(9 * range.len());
            w.table.weights.reserve(9 * range.len());
            for row in range {
                if row < nf {
                    w.face_point(h, row as u32);
                } else if row < nf + ne {
                    w.edge_point(h, (row - nf) as u32);
                } else {
                    w.vertex_point(h, (row - nf - ne) as u32, boundary);
                }
            }
            w.table
        })
        .collect();
    let terms: usize = parts.iter().map(|p| p.sources.len()).sum();
    let mut table = table_for(h.faces.vertex_count, rows);
    table.sources.reserve_exact(terms);
    table.weights.reserve_exact(terms);
    for p in parts {
        let base = table.sources.len() as u32;
        table
            .offsets
            .extend(p.offsets[1..].iter().map(|&o| base + o));
        table.sources.extend_from_slice(&p.sources);
        table.weights.extend_from_slice(&p.weights);
    }
    table
}

/// Rows per parallel task of [`stencils`].
const ROWS_PER_TASK: usize = 1 << 16;

/// Builds one table row by row.
struct Writer {
    table: StencilTable,
    /// Corners leaving the current vertex, in turning order.
    fan: Vec<u32>,
    /// Terms of a blended row before merging.
    blend: Vec<(u32, f64)>,
}

impl Writer {
    #[inline]
    fn term(&mut self, v: u32, w: f64) {
        self.table.sources.push(v);
        self.table.weights.push(w as f32);
    }

    #[inline]
    fn end_row(&mut self) {
        self.table.offsets.push(self.table.sources.len() as u32);
    }

    /// The centroid of face `f`.
    fn face_point(&mut self, h: &Halfedges, f: u32) {
        let r = h.face_corners(f);
        let each = 1.0 / r.len() as f64;
        for c in r {
            self.term(h.vert(c), each);
        }
        self.end_row();
    }

    /// `w_sharp` of the midpoint plus `1 − w_sharp` of the smooth mask `(a + b + F₀ + F₁)/4`.
    fn edge_point(&mut self, h: &Halfedges, e: u32) {
        let c = h.edge_corner[e as usize];
        let (a, b) = (h.vert(c), h.vert(h.next(c)));
        let s = h.edge_sharpness[e as usize];
        let w_sharp = if s <= 0.0 {
            0.0
        } else if decrement(s) > 0.0 {
            1.0
        } else {
            f64::from(s.min(1.0))
        };
        let ws = 1.0 - w_sharp;
        if ws == 0.0 {
            self.term(a, 0.5);
            self.term(b, 0.5);
            return self.end_row();
        }
        let t = h.twin[c as usize];
        let (n0, n1) = (
            h.face_corners(h.face(c)).len(),
            h.face_corners(h.face(t)).len(),
        );
        let (q0, q1) = (0.25 * ws / n0 as f64, 0.25 * ws / n1 as f64);
        let ends = 0.5 * w_sharp + 0.25 * ws + q0 + q1;
        self.term(a, ends);
        self.term(b, ends);
        for (start, q) in [(c, q0), (t, q1)] {
            let mut k = h.next(h.next(start));
            while k != start {
                self.term(h.vert(k), q);
                k = h.next(k);
            }
        }
        self.end_row();
    }

    fn vertex_point(&mut self, h: &Halfedges, v: u32, boundary: Boundary) {
        // The fan of faces around v, in turning order.
        let mut fan = std::mem::take(&mut self.fan);
        fan.clear();
        let start = h.vertex_corner[v as usize];
        let mut c = start;
        let open = loop {
            fan.push(c);
            c = h.turn(c);
            if c == NONE {
                break true;
            }
            if c == start {
                break false;
            }
        };
        let smooth = !open
            && !h.vertex_pinned[v as usize]
            && fan
                .iter()
                .all(|&c| h.edge_sharpness[h.edge[c as usize] as usize] <= 0.0);
        if smooth {
            // The common case: an interior vertex with no sharp edge.
            self.smooth_vertex(h, v, &fan);
            self.end_row();
        } else {
            self.vertex_row(h, v, boundary, &fan, open);
        }
        self.fan = fan;
    }

    /// The row of vertex `v` with the corners `fan` around it (`open` on a boundary).
    fn vertex_row(&mut self, h: &Halfedges, v: u32, boundary: Boundary, fan: &[u32], open: bool) {
        // Its edges: one per corner, plus the last incoming one on a boundary.
        let last_in = if open {
            Some(h.prev(*fan.last().expect("a corner")))
        } else {
            None
        };
        let edges = || {
            fan.iter()
                .map(|&c| (h.edge[c as usize], h.vert(h.next(c))))
                .chain(last_in.map(|p| (h.edge[p as usize], h.vert(p))))
        };
        let corner = h.vertex_pinned[v as usize]
            || (boundary == Boundary::EdgeAndCorner && open && fan.len() == 1);
        let sharpness = |e: u32| h.edge_sharpness[e as usize];
        let rule_of = |sharp: &dyn Fn(f32) -> bool| -> Rule {
            if corner {
                return Rule::Corner;
            }
            match edges().filter(|&(e, _)| sharp(sharpness(e))).count() {
                0 | 1 => Rule::Smooth,
                2 => Rule::Crease,
                _ => Rule::Corner,
            }
        };
        let parent_sharp = |s: f32| s > 0.0;
        let child_sharp = |s: f32| decrement(s) > 0.0;
        let parent = rule_of(&parent_sharp);
        let child = rule_of(&child_sharp);
        // The mask of `rule`, its crease following the edges `sharp` accepts.
        let mask = |this: &mut Self, rule: Rule, sharp: &dyn Fn(f32) -> bool| match rule {
            Rule::Corner => this.term(v, 1.0),
            Rule::Crease => {
                this.term(v, 0.75);
                for (_, u) in edges().filter(|&(e, _)| sharp(sharpness(e))) {
                    this.term(u, 0.125);
                }
            }
            Rule::Smooth => this.smooth_vertex(h, v, fan),
        };
        if parent == child {
            mask(self, parent, &parent_sharp);
            return self.end_row();
        }
        // Edges going from sharp to smooth set how much of the sharper rule remains.
        let w = crate::crease_rules::transition_weight(edges().map(|(e, _)| sharpness(e)));
        self.blend.clear();
        for (rule, sharp, weight) in [
            (parent, &parent_sharp as &dyn Fn(f32) -> bool, w),
            (child, &child_sharp as &dyn Fn(f32) -> bool, 1.0 - w),
        ] {
            if weight <= 0.0 {
                continue;
            }
            let row = self.table.sources.len();
            mask(self, rule, sharp);
            let terms = self
                .table
                .sources
                .drain(row..)
                .zip(self.table.weights.drain(row..));
            self.blend
                .extend(terms.map(|(s, x)| (s, f64::from(x) * weight)));
        }
        self.blend.sort_unstable_by_key(|t| t.0);
        let mut i = 0;
        while i < self.blend.len() {
            let (src, mut x) = self.blend[i];
            i += 1;
            while i < self.blend.len() && self.blend[i].0 == src {
                x += self.blend[i].1;
                i += 1;
            }
            self.term(src, x);
        }
        self.end_row();
    }

    /// The smooth mask of an interior vertex of valence `n` (its corners `fan`):
    /// `((n − 2)/n)·v + (1/n²)·Σ edge neighbours + (1/n²)·Σ face points`, each source once:
    /// an edge neighbour also collects its share of the two face points around it.
    fn smooth_vertex(&mut self, h: &Halfedges, v: u32, fan: &[u32]) {
        let n = fan.len();
        let q = 1.0 / (n * n) as f64;
        let size = |c: u32| h.face_corners(h.face(c)).len() as f64;
        let centre = (n as f64 - 2.0) / n as f64 + fan.iter().map(|&c| q / size(c)).sum::<f64>();
        self.term(v, centre);
        for i in 0..n {
            let (c, before) = (fan[i], fan[(i + n - 1) % n]);
            let qf = q / size(c);
            self.term(h.vert(h.next(c)), q + qf + q / size(before));
            // The face's corners other than v and its two edge neighbours.
            let mut k = h.next(h.next(c));
            let last = h.prev(c);
            while k != last {
                self.term(h.vert(k), qf);
                k = h.next(k);
            }
        }
    }
}

/// The faces of one Catmull–Clark (or bilinear) step: each corner of each face becomes the
/// quad (vertex point, next edge point, face point, previous edge point), with new vertices
/// numbered face points, then edge points, then vertex points. Child faces come in corner
/// order, so meshes with the same face sizes (a mesh and its UV topology) refine to faces
/// that correspond one to one. Returns the faces and each one's parent face.
pub fn split_faces(faces: &Faces, topo: &Topology) -> (Faces, Vec<u32>) {
    let (nf, ne, nv) = (
        faces.len(),
        topo.edge_vertices.len(),
        faces.vertex_count as usize,
    );
    let (fp, ep, vp) = (0u32, nf as u32, (nf + ne) as u32);
    let mut out = Faces {
        offsets: Vec::with_capacity(faces.indices.len() + 1),
        indices: Vec::with_capacity(faces.indices.len() * 4),
        vertex_count: (nf + ne + nv) as u32,
    };
    out.offsets.push(0);
    let mut face_parent = Vec::with_capacity(faces.indices.len());
    for f in 0..nf {
        let c = faces.face(f);
        let base = faces.offsets[f] as usize;
        let n = c.len();
        for (k, &corner) in c.iter().enumerate() {
            let e_next = topo.corner_edge[base + k];
            let e_prev = topo.corner_edge[base + (k + n - 1) % n];
            out.indices
                .extend_from_slice(&[vp + corner, ep + e_next, fp + f as u32, ep + e_prev]);
            out.offsets.push(out.indices.len() as u32);
            face_parent.push(f as u32);
        }
    }
    (out, face_parent)
}

/// The sharp edges after one split of `topo`'s edges at their midpoints (edge points numbered
/// after `face_points`, vertex points after them): both halves keep the decremented sharpness.
pub fn split_creases(topo: &Topology, face_points: usize) -> Vec<([u32; 2], f32)> {
    let ep = face_points as u32;
    let vp = ep + topo.edge_vertices.len() as u32;
    let mut creases = Vec::new();
    for (e, &[a, b]) in topo.edge_vertices.iter().enumerate() {
        let s = decrement(topo.edge_sharpness[e]);
        if s > 0.0 && !topo.is_boundary(e as u32) {
            creases.push(([vp + a, ep + e as u32], s));
            creases.push(([ep + e as u32, vp + b], s));
        }
    }
    creases
}
