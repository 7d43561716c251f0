//! Vertex weights (Belblidia & Perrin, section 2, "pondération des sommets"): a number per
//! vertex saying how much it matters geometrically. The barycentre representative averages with
//! these weights; the heaviest-vertex representative picks the largest.

use crate::blocks;
use crate::options::Weighting;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::atomic::{AtomicBool, AtomicU32};
use tessd_mesh::Mesh;

/// The weight of every vertex (0 for vertices no face uses).
///
/// - [`Weighting::LongestEdge`]: the longest incident edge, the paper's example; a vertex on
///   large faces stands for more surface.
/// - [`Weighting::Curvature`]: Rossignac–Borrel's `1 − cos θ`, θ the largest angle between the
///   normals of two faces around the vertex (approximated by each face against the vertex's
///   average normal), times the longest incident edge: sharp corners win.
/// - [`Weighting::Uniform`]: 1 for every referenced vertex.
pub fn vertex_weights(mesh: &Mesh, weighting: Weighting) -> Vec<f32> {
    weights_of(mesh, weighting, false).expect("the mesh was validated")
}

/// [`vertex_weights`] of a mesh of triangles that was not validated: the face pass checks, as
/// it goes, that every offset is three corners on and every index names a vertex, and gives
/// `None` if not (issue 33, the face pass validates; [`Mesh::validate`] then names the fault).
/// The caller has checked that `mesh.triangles()` is some.
pub(crate) fn checked_triangle_weights(mesh: &Mesh, weighting: Weighting) -> Option<Vec<f32>> {
    weights_of(mesh, weighting, true)
}

fn weights_of(mesh: &Mesh, weighting: Weighting, check: bool) -> Option<Vec<f32>> {
    // A vertex used only by faces of zero size still counts: its longest edge is raised to a
    // tiny weight so that barycentres stay defined (curvature raises its product instead).
    let floor = match weighting {
        Weighting::Curvature => 0.0,
        _ => f32::MIN_POSITIVE,
    };
    let longest = longest_edges(mesh, floor, check)?;
    Some(weigh(mesh, weighting, longest))
}

fn weigh(mesh: &Mesh, weighting: Weighting, longest: Vec<f32>) -> Vec<f32> {
    match weighting {
        Weighting::LongestEdge => longest,
        Weighting::Uniform => longest
            .par_iter()
            .map(|&l| if l > 0.0 { 1.0 } else { 0.0 })
            .collect(),
        Weighting::Curvature => {
            let normals: Vec<Vec3> = mesh
                .faces()
                .map(|f| Vec3::from_array(face_normal(mesh, f)))
                .collect();
            let mut avg = vec![Vec3::ZERO; mesh.vertex_count()];
            for (f, face) in mesh.faces().enumerate() {
                for &v in face {
                    avg[v as usize] += normals[f];
                }
            }
            let mut min_cos = vec![1f32; mesh.vertex_count()];
            for (f, face) in mesh.faces().enumerate() {
                for &v in face {
                    let a = unit(avg[v as usize]);
                    let c = a.dot(normals[f]);
                    min_cos[v as usize] = min_cos[v as usize].min(c);
                }
            }
            let mut w: Vec<f32> = longest
                .iter()
                .zip(&min_cos)
                .map(|(l, c)| l * (1.0 - c.clamp(-1.0, 1.0)))
                .collect();
            mark_referenced(mesh, &mut w, f32::MIN_POSITIVE);
            w
        }
    }
}

/// The longest edge incident to each vertex, at least `floor` for a vertex some face uses, 0
/// for the others.
///
/// Every core walks its blocks of faces ([`crate::blocks`]) and raises the vertices' maxima
/// with atomic compare-and-swap: a maximum does not depend on the order it is taken in, so
/// neither does the result. Squared lengths are kept as their bits plus one (non-negative
/// floats order as their bits; 0 marks a vertex no face uses) and rooted once per vertex.
///
/// `check`: the mesh is triangles (`mesh.triangles()` is some) not yet validated; every block
/// checks its offsets (face `f` starts at corner `3 f`) and indices (below the vertex count)
/// as it reads them, and `None` comes back if any fails.
fn longest_edges(mesh: &Mesh, floor: f32, check: bool) -> Option<Vec<f32>> {
    let longest: Vec<AtomicU32> = (0..mesh.vertex_count())
        .map(|_| AtomicU32::new(0))
        .collect();
    let p = &mesh.positions;
    let single = blocks::single_thread();
    let raise = |v: u32, bits: u32| {
        let slot = &longest[v as usize];
        let old = slot.load(Relaxed);
        if single {
            // Branch-free: whether an edge raises the maximum is a coin toss the predictor
            // loses half the time.
            slot.store(old.max(bits), Relaxed);
        } else if bits > old {
            slot.fetch_max(bits, Relaxed);
        }
    };
    let edge = |a: u32, b: u32| {
        let bits = dist2(p[a as usize], p[b as usize]).to_bits() + 1;
        raise(a, bits);
        raise(b, bits);
    };
    if check && mesh.triangles().is_none() {
        return None;
    }
    let faulty = AtomicBool::new(false);
    let n = p.len();
    if let Some(triangles) = mesh.triangles() {
        // Each corner takes the longer of its two edges: three raises a triangle, not six.
        blocks::ranges(triangles.len()).for_each(|r| {
            if check {
                // Offsets and indices: branch-free over the block, then one test.
                let offsets = &mesh.face_offsets[r.clone()];
                // (3 f fits a u32: the last offset, a u32, is 3 × the face count.)
                let start = 3 * r.start as u32;
                let off = offsets
                    .iter()
                    .zip((start..).step_by(3))
                    .fold(0u32, |bad, (&o, want)| bad | (o ^ want));
                let top = triangles[r.clone()]
                    .as_flattened()
                    .iter()
                    .fold(0u32, |m, &v| m.max(v));
                if off != 0 || top as usize >= n {
                    faulty.store(true, Relaxed);
                    return;
                }
            }
            for &[a, b, c] in &triangles[r] {
                let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
                let ab = dist2(pa, pb).to_bits() + 1;
                let bc = dist2(pb, pc).to_bits() + 1;
                let ca = dist2(pc, pa).to_bits() + 1;
                raise(a, ab.max(ca));
                raise(b, ab.max(bc));
                raise(c, bc.max(ca));
            }
        });
    } else {
        blocks::ranges(mesh.face_count()).for_each(|r| {
            for f in r {
                let face = mesh.face(f);
                for (i, &a) in face.iter().enumerate() {
                    edge(a, face[(i + 1) % face.len()]);
                }
            }
        });
    }
    if faulty.into_inner() {
        return None;
    }
    Some(
        longest
            .into_par_iter()
            .map(|b| match b.into_inner() {
                0 => 0.0,
                b => f32::from_bits(b - 1).sqrt().max(floor),
            })
            .collect(),
    )
}

/// Raises every referenced vertex's weight to at least `floor`.
fn mark_referenced(mesh: &Mesh, w: &mut [f32], floor: f32) {
    for &v in &mesh.face_indices {
        let x = &mut w[v as usize];
        *x = x.max(floor);
    }
}

/// The unit normal of a polygon (Newell's method; zero for a degenerate face).
pub(crate) fn face_normal(mesh: &Mesh, face: &[u32]) -> [f32; 3] {
    let corner = |i: usize| Vec3::from_array(mesh.positions[face[i % face.len()] as usize]);
    let mut n = Vec3::ZERO;
    for i in 0..face.len() {
        let (p, q) = (corner(i), corner(i + 1));
        let (d, e) = (p - q, p + q);
        n += Vec3::new(d.y * e.z, d.z * e.x, d.x * e.y);
    }
    unit(n).to_array()
}

/// `v / |v|`, zero for a zero `v` (divided, not multiplied by the reciprocal: the normals keep
/// the bits they always had).
fn unit(v: Vec3) -> Vec3 {
    let l = v.length();
    if l > 0.0 { v / l } else { Vec3::ZERO }
}

fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    Vec3::from_array(a).distance_squared(Vec3::from_array(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_triangles() -> Mesh {
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [5.0, 5.0, 5.0],
            ],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m
    }

    #[test]
    fn longest_edge_and_unreferenced() {
        let w = vertex_weights(&two_triangles(), Weighting::LongestEdge);
        assert_eq!(w[0], 2.0);
        assert!((w[1] - 5f32.sqrt()).abs() < 1e-6);
        assert!((w[2] - 5f32.sqrt()).abs() < 1e-6);
        assert_eq!(w[3], 0.0);
        let u = vertex_weights(&two_triangles(), Weighting::Uniform);
        assert_eq!(u, vec![1.0, 1.0, 1.0, 0.0]);
    }

    #[test]
    fn triangles_and_polygons_take_every_incident_edge() {
        // A unit square as two triangles (the diagonal is every corner's longest edge but for
        // the two corners it misses) and as one quad (no diagonal: every longest edge is 1);
        // vertex 4 is used by neither.
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let mut tris = Mesh {
            positions: [&square[..], &[[9.0, 9.0, 9.0]]].concat(),
            ..Mesh::default()
        };
        tris.push_face(&[0, 1, 2]);
        tris.push_face(&[0, 2, 3]);
        assert!(tris.triangles().is_some());
        let d = 2f32.sqrt();
        assert_eq!(
            vertex_weights(&tris, Weighting::LongestEdge),
            vec![d, 1.0, d, 1.0, 0.0]
        );
        let mut quad = Mesh {
            positions: tris.positions.clone(),
            ..Mesh::default()
        };
        quad.push_face(&[0, 1, 2, 3]);
        assert!(quad.triangles().is_none());
        assert_eq!(
            vertex_weights(&quad, Weighting::LongestEdge),
            vec![1.0, 1.0, 1.0, 1.0, 0.0]
        );
    }

    #[test]
    fn curvature_is_zero_on_a_plane_and_positive_on_a_ridge() {
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 1.0],
            ],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[1, 0, 3]);
        let w = vertex_weights(&m, Weighting::Curvature);
        assert!(w[0] > 0.01 && w[1] > 0.01);
        let w = vertex_weights(&two_triangles(), Weighting::Curvature);
        assert!(w[0] <= f32::MIN_POSITIVE);
    }
}
