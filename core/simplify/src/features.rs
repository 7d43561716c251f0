//! Boundary and feature vertices, for the option that keeps them from merging with interior
//! vertices (beyond the paper: clustering otherwise pulls open borders and sharp CAD edges
//! inwards).

use crate::weights::face_normal;
use tessd_mesh::Mesh;

/// 1 for a vertex on a boundary edge (used by one face), a non-manifold edge (three or more
/// faces) or a feature edge (dihedral angle above `angle_deg`); 0 otherwise.
pub fn feature_classes(mesh: &Mesh, angle_deg: f64) -> Vec<u8> {
    // Every directed edge, keyed by its undirected vertex pair, with its face.
    let mut edges: Vec<(u64, u32)> = Vec::with_capacity(mesh.face_indices.len());
    for (f, face) in mesh.faces().enumerate() {
        for i in 0..face.len() {
            let (a, b) = (face[i], face[(i + 1) % face.len()]);
            if a != b {
                edges.push(((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), f as u32));
            }
        }
    }
    edges.sort_unstable();
    let normals: Vec<[f32; 3]> = mesh.faces().map(|f| face_normal(mesh, f)).collect();
    let cos_limit = angle_deg.to_radians().cos() as f32;
    let mut class = vec![0u8; mesh.vertex_count()];
    let mut i = 0;
    while i < edges.len() {
        let j = i + edges[i..].iter().take_while(|e| e.0 == edges[i].0).count();
        let feature = match j - i {
            2 => {
                let (n1, n2) = (
                    normals[edges[i].1 as usize],
                    normals[edges[i + 1].1 as usize],
                );
                n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2] < cos_limit
            }
            _ => true,
        };
        if feature {
            class[(edges[i].0 >> 32) as usize] = 1;
            class[(edges[i].0 & 0xffff_ffff) as usize] = 1;
        }
        i = j;
    }
    class
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_square_boundary_and_folded_edge() {
        // Two triangles forming a square: all four vertices are on the boundary.
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[0, 2, 3]);
        assert_eq!(feature_classes(&m, 60.0), vec![1, 1, 1, 1]);
    }
}
