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

use crate::level::{Level, RowBuilder, table_for};
use crate::topology::{Faces, INFINITELY_SHARP, Topology};

/// How boundary vertices of one face (valence 2) behave, as OpenSubdiv's
/// `VTX_BOUNDARY_EDGE_ONLY` / `VTX_BOUNDARY_EDGE_AND_CORNER` and Blender's "Smooth, keep
/// corners" option.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Boundary curves are smooth (B-spline) everywhere, corners included.
    #[default]
    EdgeOnly,
    /// Boundary vertices with a single face are corners: they keep their position.
    EdgeAndCorner,
}

/// Sharpness one level down (uniform creasing: minus one, infinite stays infinite).
pub fn decrement(s: f32) -> f32 {
    if s >= INFINITELY_SHARP {
        INFINITELY_SHARP
    } else {
        (s - 1.0).max(0.0)
    }
}

/// A vertex's rule, by how many sharp edges meet there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Rule {
    Smooth,
    Crease,
    Corner,
}

/// Refines `faces` (with adjacency `topo`) one level.
pub fn refine(faces: &Faces, topo: &Topology, boundary: Boundary) -> Level {
    let (nf, ne, nv) = (
        faces.len(),
        topo.edge_vertices.len(),
        faces.vertex_count as usize,
    );
    let mut table = table_for(faces.vertex_count, nf + ne + nv);
    let mut row = RowBuilder::default();
    for f in 0..nf {
        row.add_face(faces.face(f), 1.0);
        row.push_to(&mut table);
    }
    for e in 0..ne {
        edge_point(faces, topo, e, &mut row);
        row.push_to(&mut table);
    }
    for v in 0..nv {
        vertex_point(faces, topo, v, boundary, &mut row);
        row.push_to(&mut table);
    }
    let (out, face_parent) = split_faces(faces, topo);
    Level {
        creases: split_creases(topo, nf),
        faces: out,
        table,
        face_parent,
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

/// The smooth edge mask: `(a + b + F₀ + F₁) / 4`.
fn smooth_edge(faces: &Faces, topo: &Topology, e: usize, row: &mut RowBuilder, w: f64) {
    let [a, b] = topo.edge_vertices[e];
    row.add(a, 0.25 * w);
    row.add(b, 0.25 * w);
    for f in topo.edge_faces[e] {
        row.add_face(faces.face(f as usize), 0.25 * w);
    }
}

fn edge_point(faces: &Faces, topo: &Topology, e: usize, row: &mut RowBuilder) {
    let [a, b] = topo.edge_vertices[e];
    let s = topo.edge_sharpness[e];
    if s <= 0.0 {
        return smooth_edge(faces, topo, e, row, 1.0);
    }
    // Sharp now; if it becomes smooth at the next level, blend by the fractional sharpness.
    let w = if decrement(s) > 0.0 {
        1.0
    } else {
        f64::from(s.min(1.0))
    };
    row.add(a, 0.5 * w);
    row.add(b, 0.5 * w);
    if w < 1.0 {
        smooth_edge(faces, topo, e, row, 1.0 - w);
    }
}

fn vertex_point(
    faces: &Faces,
    topo: &Topology,
    v: usize,
    boundary: Boundary,
    row: &mut RowBuilder,
) {
    let vv = v as u32;
    let edges = topo.edges_of(v);
    let adjacent = topo.faces_of(v);
    if edges.is_empty() {
        // An unused vertex is carried through unchanged.
        return row.add(vv, 1.0);
    }
    let boundary_edges = edges.iter().filter(|&&e| topo.is_boundary(e)).count();
    let manifold = if boundary_edges == 0 {
        adjacent.len() == edges.len()
    } else {
        boundary_edges == 2 && adjacent.len() + 1 == edges.len()
    };
    let corner = !manifold
        || (boundary == Boundary::EdgeAndCorner && boundary_edges > 0 && adjacent.len() == 1);
    let sharpness = |e: &u32| topo.edge_sharpness[*e as usize];
    let rule_of = |sharp: &dyn Fn(&u32) -> bool| -> Rule {
        if corner {
            return Rule::Corner;
        }
        match edges.iter().filter(|e| sharp(e)).count() {
            0 | 1 => Rule::Smooth,
            2 => Rule::Crease,
            _ => Rule::Corner,
        }
    };
    let parent = rule_of(&|e| sharpness(e) > 0.0);
    let child = rule_of(&|e| decrement(sharpness(e)) > 0.0);
    if parent == child {
        return mask(faces, topo, v, parent, &|e| sharpness(e) > 0.0, row, 1.0);
    }
    // Edges going from sharp to smooth set how much of the sharper rule remains.
    let (sum, count) = edges
        .iter()
        .map(sharpness)
        .filter(|&s| s > 0.0 && decrement(s) <= 0.0)
        .fold((0.0f64, 0usize), |(sum, n), s| (sum + f64::from(s), n + 1));
    let w = if count == 0 {
        0.0
    } else {
        (sum / count as f64).min(1.0)
    };
    if w > 0.0 {
        mask(faces, topo, v, parent, &|e| sharpness(e) > 0.0, row, w);
    }
    if w < 1.0 {
        let child_sharp = |e: &u32| decrement(sharpness(e)) > 0.0;
        mask(faces, topo, v, child, &child_sharp, row, 1.0 - w);
    }
}

/// Adds `w` times the mask of `rule` at vertex `v`; `sharp` says which edges the crease rule
/// follows.
fn mask(
    faces: &Faces,
    topo: &Topology,
    v: usize,
    rule: Rule,
    sharp: &dyn Fn(&u32) -> bool,
    row: &mut RowBuilder,
    w: f64,
) {
    let vv = v as u32;
    match rule {
        Rule::Corner => row.add(vv, w),
        Rule::Crease => {
            row.add(vv, 0.75 * w);
            for e in topo.edges_of(v).iter().filter(|e| sharp(e)) {
                row.add(topo.other(*e, vv), 0.125 * w);
            }
        }
        Rule::Smooth => {
            let edges = topo.edges_of(v);
            let n = edges.len() as f64;
            row.add(vv, w * (n - 2.0) / n);
            for &e in edges {
                row.add(topo.other(e, vv), w / (n * n));
            }
            for &f in topo.faces_of(v) {
                row.add_face(faces.face(f as usize), w / (n * n));
            }
        }
    }
}
