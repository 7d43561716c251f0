//! Vertex weights (Belblidia & Perrin, section 2, "pondération des sommets"): a number per
//! vertex saying how much it matters geometrically. The barycentre representative averages with
//! these weights; the heaviest-vertex representative picks the largest.

use crate::options::Weighting;
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
    // Squared lengths first (one square root per vertex at the end, not one per edge).
    let mut longest = vec![0f32; mesh.vertex_count()];
    let p = &mesh.positions;
    let mut edge = |a: u32, b: u32| {
        let (a, b) = (a as usize, b as usize);
        let l = dist2(p[a], p[b]);
        longest[a] = longest[a].max(l);
        longest[b] = longest[b].max(l);
    };
    for w in mesh.face_offsets.windows(2) {
        let face = &mesh.face_indices[w[0] as usize..w[1] as usize];
        if let [a, b, c] = *face {
            edge(a, b);
            edge(b, c);
            edge(c, a);
        } else {
            for (i, &a) in face.iter().enumerate() {
                edge(a, face[(i + 1) % face.len()]);
            }
        }
    }
    longest.iter_mut().for_each(|l| *l = l.sqrt());
    match weighting {
        Weighting::LongestEdge => {
            // A vertex used only by faces of zero size still counts: give it a tiny weight so
            // that barycentres stay defined.
            mark_referenced(mesh, &mut longest, f32::MIN_POSITIVE);
            longest
        }
        Weighting::Uniform => {
            let mut w = vec![0f32; mesh.vertex_count()];
            mark_referenced(mesh, &mut w, 1.0);
            w
        }
        Weighting::Curvature => {
            let normals: Vec<[f32; 3]> = mesh.faces().map(|f| face_normal(mesh, f)).collect();
            let mut avg = vec![[0f32; 3]; mesh.vertex_count()];
            for (f, face) in mesh.faces().enumerate() {
                for &v in face {
                    for k in 0..3 {
                        avg[v as usize][k] += normals[f][k];
                    }
                }
            }
            let mut min_cos = vec![1f32; mesh.vertex_count()];
            for (f, face) in mesh.faces().enumerate() {
                for &v in face {
                    let a = normalize(avg[v as usize]);
                    let c = dot(a, normals[f]);
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

/// Raises every referenced vertex's weight to at least `floor`.
fn mark_referenced(mesh: &Mesh, w: &mut [f32], floor: f32) {
    for &v in &mesh.face_indices {
        let x = &mut w[v as usize];
        *x = x.max(floor);
    }
}

/// The unit normal of a polygon (Newell's method; zero for a degenerate face).
pub(crate) fn face_normal(mesh: &Mesh, face: &[u32]) -> [f32; 3] {
    let mut n = [0f32; 3];
    for i in 0..face.len() {
        let p = mesh.positions[face[i] as usize];
        let q = mesh.positions[face[(i + 1) % face.len()] as usize];
        n[0] += (p[1] - q[1]) * (p[2] + q[2]);
        n[1] += (p[2] - q[2]) * (p[0] + q[0]);
        n[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    normalize(n)
}

fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(v: [f32; 3]) -> [f32; 3] {
    let l = dot(v, v).sqrt();
    if l > 0.0 {
        [v[0] / l, v[1] / l, v[2] / l]
    } else {
        [0.0; 3]
    }
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
