//! Doo–Sabin refinement, one level (paper 002, section 1.4.7, "Subdivision de Doo-Sabin": an
//! approximating **dual** scheme on any polygon mesh, C¹ where regular).
//!
//! Being dual, it splits vertices rather than faces: every face corner gets a new point, and the
//! new mesh has three kinds of faces, all oriented like the cage:
//! - an **F-face** per old face: its corners' new points, in the face's order;
//! - an **E-face** (quad) per edge: the two points at each end of the edge, one per side;
//! - a **V-face** per vertex: the points of the corners around it, in walking order (none for
//!   an interior vertex of two faces, whose two points are an edge of its E-faces).
//!
//! The corner point of corner `k` of an `n`-gon is `Σⱼ αⱼ·v_{k+j}` with Doo and Sabin's weights
//! `α₀ = 1/4 + 5/(4n)`, `αⱼ = (3 + 2cos(2πj/n))/(4n)`. On quads they are the biquadratic
//! B-spline's 9/16, 3/16, 1/16, 3/16, which is also what the paper's mask `(v + Eⱼ + Eⱼ₋₁ +
//! Vⱼ)/4` gives; for other `n` that simpler mask differs, and these weights are the ones that
//! shrink a regular `n`-gon by exactly 1/2 about its centre, as on quads.
//!
//! **New vertices**: row `i` is corner `i` of the old `faces.indices`; then two boundary points
//! per boundary edge (edges in [`Topology`] order, the point near `edge_vertices[e][0]` first);
//! then one point per corner vertex (see below), in vertex order.
//! **New faces**: F-faces in face order, E-faces in edge order, V-faces in vertex order.
//! **Parents** (`face_parent`): an F-face's is its face; an E- or V-face's is the
//! lowest-numbered old face it takes points from.
//!
//! **Boundaries** (our choice): the surface is made to end on the quadratic
//! B-spline (Chaikin curve, section 1.4.6) of the cage's boundary polygon. A boundary edge
//! `(a, b)` gets the Chaikin points `3/4·a + 1/4·b` and `1/4·a + 3/4·b`, closes its E-face with
//! them, and the V-face of a boundary vertex runs from one of its boundary edges' points through
//! its corner points to the other's. The new boundary polygon is then exactly the Chaikin
//! refinement of the old one, level after level, while across the boundary the rows converge
//! like an end-interpolating quadratic B-spline. With [`Boundary::EdgeAndCorner`] a boundary
//! vertex of one face keeps a point at its position, inserted in its V-face between the two
//! Chaikin points, so the boundary curve keeps that corner; a vertex whose faces form more than
//! one fan (non-manifold) is such a corner in both modes, as in Catmull–Clark.
//!
//! **Creases** are ignored and the output has none: Doo–Sabin has no standard crease rule
//! (OpenSubdiv's `Sdc`, whose creasing the primal schemes here follow, does not define this
//! scheme).
//!
//! Faces out: `F + E + V`, which is `4F + χ` on a closed quad mesh (the cube: 6 + 12 + 8 = 26),
//! `3F + χ` on a closed triangle mesh, and more per face with larger polygons or boundaries.

use std::f64::consts::PI;

use crate::boundary::Boundary;
use crate::error::SubdivError;
use crate::level::{Level, RowBuilder, table_for};
use crate::topology::{Faces, NONE, Topology};

/// One side of an edge: the face and the corner (index into `faces.indices`) the edge starts
/// from in that face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Side {
    /// The face.
    pub face: u32,
    /// The corner of `face` where the edge starts.
    pub corner: u32,
}

/// No side (the missing second side of a boundary edge).
pub(crate) const NO_SIDE: Side = Side {
    face: NONE,
    corner: NONE,
};

/// The sides of every edge (second one [`NO_SIDE`] on a boundary), lower corner first.
///
/// # Errors
/// [`SubdivError::DegenerateFace`] naming the second face of an edge whose two faces run it
/// the same way: dual and edge-flipping schemes need consistently oriented faces to orient the
/// faces they build between two old faces.
pub(crate) fn edge_sides(faces: &Faces, topo: &Topology) -> Result<Vec<[Side; 2]>, SubdivError> {
    let mut sides = vec![[NO_SIDE; 2]; topo.edge_vertices.len()];
    for f in 0..faces.len() {
        let base = faces.offsets[f];
        for k in 0..faces.face(f).len() as u32 {
            let corner = base + k;
            let s = &mut sides[topo.corner_edge[corner as usize] as usize];
            let slot = usize::from(s[0] != NO_SIDE);
            s[slot] = Side {
                face: f as u32,
                corner,
            };
            if slot == 1 && faces.indices[s[0].corner as usize] == faces.indices[corner as usize] {
                let [a, b] = topo.edge_vertices[topo.corner_edge[corner as usize] as usize];
                return Err(SubdivError::DegenerateFace {
                    face: f,
                    why: format!(
                        "it runs edge ({a}, {b}) the same way as face {}; this scheme needs \
                         consistently oriented faces",
                        s[0].face
                    ),
                });
            }
        }
    }
    Ok(sides)
}

/// The corner after `corner` in `face`.
pub(crate) fn next_corner(faces: &Faces, face: u32, corner: u32) -> u32 {
    let (s, e) = (
        faces.offsets[face as usize],
        faces.offsets[face as usize + 1],
    );
    if corner + 1 == e { s } else { corner + 1 }
}

/// The corner before `corner` in `face`.
pub(crate) fn prev_corner(faces: &Faces, face: u32, corner: u32) -> u32 {
    let (s, e) = (
        faces.offsets[face as usize],
        faces.offsets[face as usize + 1],
    );
    if corner == s { e - 1 } else { corner - 1 }
}

/// Doo and Sabin's weights for an `n`-gon, from the corner (`j = 0`) onwards.
fn weights(n: usize) -> Vec<f64> {
    let nf = n as f64;
    (0..n)
        .map(|j| {
            let w = (3.0 + 2.0 * (2.0 * PI * j as f64 / nf).cos()) / (4.0 * nf);
            if j == 0 { 0.25 + w } else { w }
        })
        .collect()
}

/// Refines `faces` (with adjacency `topo`) one level; creases in `topo` are ignored.
///
/// # Errors
/// [`SubdivError::DegenerateFace`] when two faces run a shared edge the same way.
pub fn refine(faces: &Faces, topo: &Topology, boundary: Boundary) -> Result<Level, SubdivError> {
    let sides = edge_sides(faces, topo)?;
    let (nc, ne) = (faces.indices.len(), topo.edge_vertices.len());
    let mut table = table_for(faces.vertex_count, nc + ne);
    let mut row = RowBuilder::default();

    // Corner points.
    let mut cache: Vec<Vec<f64>> = Vec::new();
    for f in 0..faces.len() {
        let c = faces.face(f);
        let n = c.len();
        if cache.len() <= n {
            cache.resize(n + 1, Vec::new());
        }
        if cache[n].is_empty() {
            cache[n] = weights(n);
        }
        for k in 0..n {
            for (j, &w) in cache[n].iter().enumerate() {
                row.add(c[(k + j) % n], w);
            }
            row.push_to(&mut table);
        }
    }

    // Chaikin points of boundary edges.
    let mut edge_q = vec![NONE; ne];
    for (e, q) in edge_q.iter_mut().enumerate() {
        if topo.is_boundary(e as u32) {
            *q = table.len() as u32;
            let [a, b] = topo.edge_vertices[e];
            for (wa, wb) in [(0.75, 0.25), (0.25, 0.75)] {
                row.add(a, wa);
                row.add(b, wb);
                row.push_to(&mut table);
            }
        }
    }
    let q = |e: u32, v: u32| edge_q[e as usize] + u32::from(topo.edge_vertices[e as usize][1] == v);

    let mut out = Faces {
        offsets: Vec::with_capacity(faces.len() + ne + faces.vertex_count as usize + 1),
        indices: Vec::with_capacity(nc * 4),
        vertex_count: 0,
    };
    out.offsets.push(0);
    let mut face_parent = Vec::with_capacity(out.offsets.capacity());
    let mut emit = |out: &mut Faces, corners: &mut dyn Iterator<Item = u32>, parent: u32| {
        out.indices.extend(corners);
        out.offsets.push(out.indices.len() as u32);
        face_parent.push(parent);
    };

    // F-faces: the corner points keep their face's order.
    for f in 0..faces.len() {
        let (s, e) = (faces.offsets[f], faces.offsets[f + 1]);
        emit(&mut out, &mut (s..e), f as u32);
    }

    // E-faces: side 0 runs a → b, so its F-face has the edge (p₀(a), p₀(b)); the E-face runs it
    // backwards, then crosses at a to side 1 (or the boundary points).
    for (e, &[s0, s1]) in sides.iter().enumerate() {
        let (a0, b0) = (s0.corner, next_corner(faces, s0.face, s0.corner));
        if s1 == NO_SIDE {
            let (a, b) = (faces.indices[a0 as usize], faces.indices[b0 as usize]);
            let corners = [b0, a0, q(e as u32, a), q(e as u32, b)];
            emit(&mut out, &mut corners.into_iter(), s0.face);
        } else {
            let (b1, a1) = (s1.corner, next_corner(faces, s1.face, s1.corner));
            let corners = [b0, a0, a1, b1];
            emit(&mut out, &mut corners.into_iter(), s0.face.min(s1.face));
        }
    }

    // V-faces: from a corner at v, the next corner in the V-face is the one across the edge
    // coming into v (which leaves v on the other side), so the V-face turns like its
    // neighbours. Boundary fans start at a corner whose outgoing edge is a boundary.
    let mut visited = vec![false; nc];
    let mut at: Vec<Side> = Vec::new();
    let mut ring: Vec<u32> = Vec::new();
    for v in 0..faces.vertex_count {
        at.clear();
        for &f in topo.faces_of(v as usize) {
            let base = faces.offsets[f as usize];
            let k = faces.face(f as usize).iter().position(|&x| x == v);
            let k = k.expect("a face around a vertex uses it") as u32;
            at.push(Side {
                face: f,
                corner: base + k,
            });
        }
        let starts: Vec<Side> = at
            .iter()
            .copied()
            .filter(|s| topo.is_boundary(topo.corner_edge[s.corner as usize]))
            .collect();
        let walk = |start: Side, ring: &mut Vec<u32>, visited: &mut [bool]| -> (u32, u32) {
            // Returns the lowest face and the boundary edge the walk ended on (or NONE).
            let (mut s, mut low) = (start, start.face);
            loop {
                visited[s.corner as usize] = true;
                ring.push(s.corner);
                low = low.min(s.face);
                let e_in = topo.corner_edge[prev_corner(faces, s.face, s.corner) as usize];
                if topo.is_boundary(e_in) {
                    return (low, e_in);
                }
                let [x, y] = sides[e_in as usize];
                s = if x.face == s.face { y } else { x };
                if s == start || visited[s.corner as usize] {
                    return (low, NONE);
                }
            }
        };
        let mut fans = Vec::with_capacity(starts.len());
        for &start in &starts {
            ring.clear();
            let e_out = topo.corner_edge[start.corner as usize];
            ring.push(q(e_out, v));
            let (low, e_in) = walk(start, &mut ring, &mut visited);
            debug_assert_ne!(e_in, NONE, "a fan ends on a boundary");
            ring.push(q(e_in, v));
            fans.push((ring.clone(), low));
        }
        let cycles = at.iter().any(|s| !visited[s.corner as usize]);
        let corner = starts.len() > 1
            || (!starts.is_empty() && cycles)
            || (boundary == Boundary::EdgeAndCorner && starts.len() == 1 && at.len() == 1);
        if corner {
            let p = table.len() as u32;
            row.add(v, 1.0);
            row.push_to(&mut table);
            fans.iter_mut().for_each(|(r, _)| r.push(p));
        }
        for (r, low) in &fans {
            emit(&mut out, &mut r.iter().copied(), *low);
        }
        for s in &at {
            if !visited[s.corner as usize] {
                ring.clear();
                let (low, _) = walk(*s, &mut ring, &mut visited);
                // An interior vertex of two faces has a V-face of two points, an edge the two
                // E-faces around it already share: no face.
                if ring.len() >= 3 {
                    emit(&mut out, &mut ring.iter().copied(), low);
                }
            }
        }
    }
    out.vertex_count = table.len() as u32;
    Ok(Level {
        faces: out,
        table,
        creases: Vec::new(),
        face_parent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_match_the_biquadratic_spline_on_quads() {
        for n in 3..12 {
            let s: f64 = weights(n).iter().sum();
            assert!((s - 1.0).abs() < 1e-12, "n = {n}: {s}");
        }
        let w = weights(4);
        let want = [9.0 / 16.0, 3.0 / 16.0, 1.0 / 16.0, 3.0 / 16.0];
        assert!(w.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
    }
}
