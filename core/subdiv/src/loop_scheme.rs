//! Loop subdivision, one level, as OpenSubdiv's `SCHEME_LOOP` uniform refinement (paper 002,
//! section 1.4.7, "Subdivision de Loop": approximating, primal, triangles, C² where regular).
//!
//! Each triangle splits into four. New vertices are numbered **edge points first** (in
//! [`Topology`] edge order), **then vertex points** (vertex `v` becomes `edges + v`). Masks:
//! - smooth edge: `3/8 (a + b) + 1/8 (c + d)`, `c`, `d` the opposite corners of its faces;
//! - smooth vertex of valence `n`: `(1 − nβ) v + β Σ neighbours`, with Loop's original
//!   `β = (5/8 − (3/8 + 1/4 cos(2π/n))²) / n` (5/8 and 1/16 at valence 6; section 1.4.7's
//!   `α_n = 3/8 + (3/8 + 1/4 cos(2π/n))²` is the centre weight `1 − nβ`), not Warren's
//!   simpler `3/(8n)`: OpenSubdiv uses Loop's, and the regression against its icosahedron
//!   levels tells the two apart. (Section 1.4.7's boundary vertex mask should read
//!   `3/4 dᵢ + 1/8 (dᵢ₋₁ + dᵢ₊₁)`.)
//! - sharp edges (boundary edges included) give midpoints; a vertex on two sharp edges takes
//!   the crease mask `(a + 6v + b)/8` (the cubic B-spline along the boundary or crease), three
//!   or more (or a corner) stays put; semi-sharp creases lose one per level and blend by their
//!   fractional sharpness, as in [`crate::catmull_clark`] (rules in [`crate::crease_rules`]).

use crate::boundary::Boundary;
use crate::crease_rules::{self, Phase, Rule};
use crate::error::SubdivError;
use crate::level::{Level, RowBuilder, table_for};
use crate::stencil::StencilTable;
use crate::topology::{Faces, NONE, Topology};

/// Loop's smooth-vertex weight per neighbour at valence `n` (the centre takes `1 − nβ`).
pub fn beta(n: usize) -> f64 {
    let n = n as f64;
    let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n).cos();
    (0.625 - c * c) / n
}

/// Refines the triangles `faces` (with adjacency `topo`) one level.
///
/// # Errors
/// [`SubdivError::NotTriangles`] when a face is not a triangle.
pub fn refine(faces: &Faces, topo: &Topology, boundary: Boundary) -> Result<Level, SubdivError> {
    check_triangles(faces, "loop")?;
    let (ne, nv) = (topo.edge_vertices.len(), faces.vertex_count as usize);
    let mut table = table_for(faces.vertex_count, ne + nv);
    let mut row = RowBuilder::default();
    for e in 0..ne {
        edge_point(faces, topo, e, &mut row);
        row.push_to(&mut table);
    }
    for v in 0..nv {
        vertex_point(topo, v, boundary, &mut row);
        row.push_to(&mut table);
    }
    Ok(triangle_level(faces, topo, table))
}

/// [`SubdivError::NotTriangles`] for the first face of `faces` that is not a triangle.
pub(crate) fn check_triangles(faces: &Faces, scheme: &'static str) -> Result<(), SubdivError> {
    match (0..faces.len()).find(|&f| faces.face(f).len() != 3) {
        Some(face) => Err(SubdivError::NotTriangles {
            scheme,
            face,
            corners: faces.face(face).len(),
        }),
        None => Ok(()),
    }
}

/// A level of a 1-to-4 triangle scheme (Loop, Butterfly) with its `table`: the split
/// triangles, their parents, and both halves of every crease.
pub fn triangle_level(faces: &Faces, topo: &Topology, table: StencilTable) -> Level {
    let (out, face_parent) = split_triangles(faces, topo);
    Level {
        faces: out,
        table,
        creases: crease_rules::split_creases(topo),
        face_parent,
    }
}

/// The 1-to-4 split of triangles shared by Loop and Butterfly. Edge points are new vertices
/// `0..edges`, vertex points follow. Triangle `(p₀, p₁, p₂)` with edges `eₖ = (pₖ, pₖ₊₁)`
/// gives, in this order, the corner triangles `(p₀, e₀, e₂)`, `(p₁, e₁, e₀)`,
/// `(p₂, e₂, e₁)` and the middle one `(e₀, e₁, e₂)`, all oriented as the parent. Returns the
/// faces and each one's parent face.
pub fn split_triangles(faces: &Faces, topo: &Topology) -> (Faces, Vec<u32>) {
    let nf = faces.len();
    let vp = topo.edge_vertices.len() as u32;
    let mut out = Faces {
        offsets: (0..=4 * nf as u32).map(|f| 3 * f).collect(),
        indices: Vec::with_capacity(12 * nf),
        vertex_count: vp + faces.vertex_count,
    };
    let mut face_parent = Vec::with_capacity(4 * nf);
    for f in 0..nf {
        let base = faces.offsets[f] as usize;
        let p = faces.face(f);
        let e = &topo.corner_edge[base..base + 3];
        out.indices.extend_from_slice(&[
            vp + p[0],
            e[0],
            e[2],
            vp + p[1],
            e[1],
            e[0],
            vp + p[2],
            e[2],
            e[1],
            e[0],
            e[1],
            e[2],
        ]);
        face_parent.extend_from_slice(&[f as u32; 4]);
    }
    (out, face_parent)
}

/// The corner of triangle `face` that is neither `a` nor `b`.
pub(crate) fn third(face: &[u32], a: u32, b: u32) -> u32 {
    *face
        .iter()
        .find(|&&v| v != a && v != b)
        .expect("a triangle has a third corner")
}

/// Adds `w` times the smooth edge mask `3/8 (a + b) + 1/8 (c + d)`.
fn smooth_edge(faces: &Faces, topo: &Topology, e: usize, row: &mut RowBuilder, w: f64) {
    let [a, b] = topo.edge_vertices[e];
    row.add(a, 0.375 * w);
    row.add(b, 0.375 * w);
    for f in topo.edge_faces[e] {
        row.add(third(faces.face(f as usize), a, b), 0.125 * w);
    }
}

fn edge_point(faces: &Faces, topo: &Topology, e: usize, row: &mut RowBuilder) {
    let [a, b] = topo.edge_vertices[e];
    let sharp = if topo.edge_faces[e][1] == NONE {
        1.0
    } else {
        crease_rules::edge_sharp_weight(topo.edge_sharpness[e])
    };
    if sharp > 0.0 {
        row.add(a, 0.5 * sharp);
        row.add(b, 0.5 * sharp);
    }
    if sharp < 1.0 {
        smooth_edge(faces, topo, e, row, 1.0 - sharp);
    }
}

fn vertex_point(topo: &Topology, v: usize, boundary: Boundary, row: &mut RowBuilder) {
    if topo.edges_of(v).is_empty() {
        // An unused vertex is carried through unchanged.
        return row.add(v as u32, 1.0);
    }
    for part in crease_rules::vertex_parts(topo, v, boundary) {
        if part.weight > 0.0 {
            mask(topo, v, part.rule, part.phase, row, part.weight);
        }
    }
}

/// Adds `w` times the mask of `rule` at `v`; `phase` says which edges the crease mask follows.
fn mask(topo: &Topology, v: usize, rule: Rule, phase: Phase, row: &mut RowBuilder, w: f64) {
    let vv = v as u32;
    match rule {
        Rule::Corner => row.add(vv, w),
        Rule::Crease => {
            row.add(vv, 0.75 * w);
            for e in crease_rules::sharp_edges(topo, v, phase) {
                row.add(topo.other(e, vv), 0.125 * w);
            }
        }
        Rule::Smooth => {
            let edges = topo.edges_of(v);
            let b = beta(edges.len());
            row.add(vv, w * (1.0 - edges.len() as f64 * b));
            for &e in edges {
                row.add(topo.other(e, vv), w * b);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stencil::StencilTable;
    use crate::test_meshes::hex_fan as fan;

    fn row(t: &StencilTable, i: usize) -> Vec<(u32, f32)> {
        t.row(i).collect()
    }

    #[test]
    fn beta_is_loops() {
        assert!((beta(6) - 1.0 / 16.0).abs() < 1e-15);
        assert!((beta(3) - 3.0 / 16.0).abs() < 1e-15);
        assert!((1.0 - 6.0 * beta(6) - 0.625).abs() < 1e-15);
    }

    #[test]
    fn regular_stencils() {
        let f = fan();
        let t = Topology::build(&f, &[]).unwrap();
        let level = refine(&f, &t, Boundary::EdgeOnly).unwrap();
        let ne = t.edge_vertices.len();
        assert_eq!(ne, 12);
        // The centre: valence 6, 5/8 and 1/16.
        let centre = row(&level.table, ne);
        assert_eq!(centre.len(), 7);
        assert_eq!(centre[0], (0, 0.625));
        assert!(centre[1..].iter().all(|&(_, w)| w == 0.0625));
        // A spoke (interior edge): 3/8 at its ends, 1/8 at the opposite corners.
        let spoke = t.edge_vertices.iter().position(|&e| e == [0, 1]).unwrap();
        assert_eq!(
            row(&level.table, spoke),
            vec![(0, 0.375), (1, 0.375), (2, 0.125), (6, 0.125)]
        );
        // A rim edge (boundary): midpoint; a rim vertex: (a + 6v + b)/8.
        let rim = t.edge_vertices.iter().position(|&e| e == [1, 2]).unwrap();
        assert_eq!(row(&level.table, rim), vec![(1, 0.5), (2, 0.5)]);
        assert_eq!(
            row(&level.table, ne + 1),
            vec![(1, 0.75), (2, 0.125), (6, 0.125)]
        );
    }

    #[test]
    fn faces_split_in_four_with_parents_and_creases() {
        let f = fan();
        let t = Topology::build(&f, &[([0, 1], 1.5)]).unwrap();
        let level = refine(&f, &t, Boundary::EdgeOnly).unwrap();
        assert_eq!(level.faces.len(), 24);
        assert_eq!(level.faces.vertex_count, 19);
        assert_eq!(&level.face_parent[..8], &[0, 0, 0, 0, 1, 1, 1, 1]);
        let spoke = t.edge_vertices.iter().position(|&e| e == [0, 1]).unwrap() as u32;
        let mut c = level.creases.clone();
        c.sort_by_key(|k| k.0);
        let mut want = vec![([12, spoke], 0.5), ([spoke, 13], 0.5)];
        want.sort_by_key(|k| k.0);
        assert_eq!(c, want);
        // Every new face is a triangle of existing vertices.
        assert!(level.faces.indices.iter().all(|&v| v < 19));
    }

    #[test]
    fn rows_sum_to_one_with_creases_and_corners() {
        let f = fan();
        for creases in [vec![], vec![([0, 1], 0.3), ([0, 4], 1.7), ([0, 2], 10.0)]] {
            let t = Topology::build(&f, &creases).unwrap();
            for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
                let level = refine(&f, &t, boundary).unwrap();
                for i in 0..level.table.len() {
                    let s: f32 = level.table.row(i).map(|(_, w)| w).sum();
                    assert!((s - 1.0).abs() < 1e-6, "row {i}: {s}");
                }
            }
        }
    }

    #[test]
    fn quads_are_refused() {
        let f = Faces {
            offsets: vec![0, 4],
            indices: vec![0, 1, 2, 3],
            vertex_count: 4,
        };
        let t = Topology::build(&f, &[]).unwrap();
        assert!(matches!(
            refine(&f, &t, Boundary::EdgeOnly),
            Err(SubdivError::NotTriangles { face: 0, .. })
        ));
    }
}
