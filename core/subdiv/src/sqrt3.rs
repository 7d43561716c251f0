//! Kobbelt's √3 refinement, one level (paper 002, section 1.4.7, "Subdivision √3": an
//! approximating primal scheme on triangles, C² where regular, C¹ elsewhere).
//!
//! Each triangle gets its centroid as a new point and each old vertex of valence `n` relaxes to
//! `(1 − αₙ)·p + αₙ/n·Σ neighbours` with `αₙ = (4 − 2cos(2π/n))/9`. Then every old edge is
//! *flipped*: the two triangles on edge `(s, t)` (`s → t` in face `f`, `t → s` in face `g`)
//! become `(t, c_f, c_g)` and `(s, c_g, c_f)`, which keeps the faces' orientation. A level
//! gives three triangles per triangle, and two levels the triadic split (each edge in three,
//! nine triangles per triangle), rotated back into place.
//!
//! **Boundaries and creases** (simplified from Kobbelt, whose boundary rule alternates
//! between odd and even levels, which a level-independent table cannot know): an edge that is
//! a boundary or has sharpness above zero is not flipped but split at its midpoint, each of its
//! triangles giving the two `(s, m, c_f)`, `(m, t, c_f)`. A vertex with two such edges follows
//! the cubic B-spline curve rule `1/8·a + 3/4·v + 1/8·b` along them (the paper's Loop boundary
//! mask, section 1.4.7), so a boundary or infinitely sharp crease converges to the cubic
//! B-spline of its polygon, as with Catmull–Clark and Loop; a vertex with more than two, a
//! non-manifold vertex, and with [`Boundary::EdgeAndCorner`] a boundary vertex of one face,
//! stays put. A vertex of one face has its two triangles there re-cut as `(v, m₁, m₂)`,
//! `(m₁, c_f, m₂)`, so it keeps a single face and a kept corner stays one at every level.
//! Splitting dyadically every level keeps boundary edges within a factor `(2/√3)^levels` of
//! the interior ones, where never splitting them would leave ever thinner triangles along the
//! boundary. A crease's halves keep its sharpness minus one per level (uniform creasing);
//! fractional sharpness is not blended: an edge is sharp while above zero.
//!
//! Faces out: `3F` on a closed mesh without creases, plus one per face side that is split.
//!
//! **New vertices**: the old vertices first (vertex `v` stays `v`), then one centroid per face
//! (face `f` gives `vertices + f`), then one midpoint per split edge, in [`Topology`] edge order.
//! **New faces**: by parent face, in its corner order, one triangle per corner (the one holding
//! the edge's end `t` when flipped, the two halves when split); every face is its own parent.

use std::f64::consts::PI;

use crate::boundary::Boundary;
use crate::doo_sabin::edge_sides;
use crate::error::SubdivError;
use crate::level::{Level, RowBuilder, table_for};
use crate::sharpness::decrement;
use crate::topology::{Faces, NONE, Topology};

/// `αₙ`, the share of the neighbours' average in a relaxed vertex of valence `n`.
pub fn alpha(n: usize) -> f64 {
    (4.0 - 2.0 * (2.0 * PI / n as f64).cos()) / 9.0
}

/// Refines the triangles `faces` (with adjacency `topo`) one level.
///
/// # Errors
/// [`SubdivError::NotTriangles`] for a face that is not a triangle;
/// [`SubdivError::DegenerateFace`] when two faces run a shared edge the same way.
pub fn refine(faces: &Faces, topo: &Topology, boundary: Boundary) -> Result<Level, SubdivError> {
    if let Some(face) = (0..faces.len()).find(|&f| faces.face(f).len() != 3) {
        return Err(SubdivError::NotTriangles {
            scheme: "sqrt3",
            face,
            corners: faces.face(face).len(),
        });
    }
    let sides = edge_sides(faces, topo)?;
    let (nv, nf, ne) = (
        faces.vertex_count as usize,
        faces.len(),
        topo.edge_vertices.len(),
    );
    let split: Vec<bool> = topo.edge_sharpness.iter().map(|&s| s > 0.0).collect();
    let mut table = table_for(faces.vertex_count, nv + nf + ne / 8);
    let mut row = RowBuilder::default();
    for v in 0..nv {
        vertex_point(topo, v, boundary, &split, &mut row);
        row.push_to(&mut table);
    }
    for f in 0..nf {
        row.add_face(faces.face(f), 1.0);
        row.push_to(&mut table);
    }
    let mut mid = vec![NONE; ne];
    let mut creases = Vec::new();
    for e in (0..ne).filter(|&e| split[e]) {
        let m = table.len() as u32;
        mid[e] = m;
        let [a, b] = topo.edge_vertices[e];
        row.add(a, 0.5);
        row.add(b, 0.5);
        row.push_to(&mut table);
        let s = decrement(topo.edge_sharpness[e]);
        if s > 0.0 && !topo.is_boundary(e as u32) {
            creases.push(([a, m], s));
            creases.push(([m, b], s));
        }
    }

    let mut out = Faces {
        offsets: Vec::with_capacity(3 * nf + 1),
        indices: Vec::with_capacity(9 * nf),
        vertex_count: table.len() as u32,
    };
    out.offsets.push(0);
    let mut face_parent = Vec::with_capacity(3 * nf);
    // A vertex of one face has both its edges split; its two triangles are cut as
    // (v, m₁, m₂), (m₁, c_f, m₂) so it keeps a single face, and a corner stays one.
    let lone = |v: u32| topo.faces_of(v as usize).len() == 1;
    for f in 0..nf {
        let c = faces.face(f);
        let cf = (nv + f) as u32;
        let edge = |k: usize| topo.corner_edge[faces.offsets[f] as usize + k % 3] as usize;
        for k in 0..3 {
            let (s, t, e) = (c[k], c[(k + 1) % 3], edge(k));
            if split[e] {
                let m = mid[e];
                let first = if lone(s) {
                    [s, m, mid[edge(k + 2)]]
                } else {
                    [s, m, cf]
                };
                let second = if lone(t) {
                    [m, mid[edge(k + 1)], cf]
                } else {
                    [m, t, cf]
                };
                out.indices.extend_from_slice(&first);
                out.offsets.push(out.indices.len() as u32);
                face_parent.push(f as u32);
                out.indices.extend_from_slice(&second);
            } else {
                let [x, y] = sides[e];
                let g = if x.face == f as u32 { y.face } else { x.face };
                out.indices.extend_from_slice(&[t, cf, nv as u32 + g]);
            }
            out.offsets.push(out.indices.len() as u32);
            face_parent.push(f as u32);
        }
    }
    Ok(Level {
        faces: out,
        table,
        creases,
        face_parent,
    })
}

/// The relaxed position of old vertex `v`; `split` marks the boundary and sharp edges.
fn vertex_point(
    topo: &Topology,
    v: usize,
    boundary: Boundary,
    split: &[bool],
    row: &mut RowBuilder,
) {
    let vv = v as u32;
    let edges = topo.edges_of(v);
    if edges.is_empty() {
        // An unused vertex is carried through unchanged.
        return row.add(vv, 1.0);
    }
    let corner = topo.fan(v).is_corner(boundary);
    let sharp = || edges.iter().filter(|&&e| split[e as usize]);
    match sharp().count() {
        _ if corner => row.add(vv, 1.0),
        0 | 1 => {
            let n = edges.len();
            let a = alpha(n);
            row.add(vv, 1.0 - a);
            for &e in edges {
                row.add(topo.other(e, vv), a / n as f64);
            }
        }
        2 => {
            row.add(vv, 0.75);
            for &e in sharp() {
                row.add(topo.other(e, vv), 0.125);
            }
        }
        _ => row.add(vv, 1.0),
    }
}
