//! Optional triangulation (Belblidia & Perrin, section 2): polygons are split into triangles
//! before merging so that no warped polygon appears once their vertices move.

use tessd_mesh::{Domain, FaceVarying, Mesh};

/// Fan-triangulates every face with more than three corners, carrying face groups,
/// face-varying data, generic attributes and sharp edges. Fans suit the convex polygons meshes mostly hold; a concave
/// polygon may get overlapping triangles, which clustering tolerates.
pub fn triangulate(mesh: &Mesh) -> Mesh {
    let tris = mesh.triangle_count();
    let mut out = Mesh {
        positions: mesh.positions.clone(),
        face_offsets: Vec::with_capacity(tris + 1),
        face_indices: Vec::with_capacity(3 * tris),
        normals: None,
        uvs: None,
        creases: mesh.creases.clone(),
        face_groups: Vec::new(),
        group_names: mesh.group_names.clone(),
        attributes: Vec::new(),
        sharp_edges: mesh.sharp_edges.clone(),
    };
    out.face_offsets.push(0);
    // The input corner of each output corner, to carry face-varying data.
    let mut corner_src: Vec<u32> = Vec::with_capacity(3 * tris);
    // The input face of each triangle, only when face attributes need it.
    let face_attributes = mesh.attributes.iter().any(|a| a.domain == Domain::Face);
    let mut face_src: Vec<u32> = Vec::with_capacity(if face_attributes { tris } else { 0 });
    for (f, w) in mesh.face_offsets.windows(2).enumerate() {
        let (s, e) = (w[0], w[1]);
        for k in s + 1..e - 1 {
            for c in [s, k, k + 1] {
                out.face_indices.push(mesh.face_indices[c as usize]);
                corner_src.push(c);
            }
            out.face_offsets.push(out.face_indices.len() as u32);
            if !mesh.face_groups.is_empty() {
                out.face_groups.push(mesh.face_groups[f]);
            }
            if face_attributes {
                face_src.push(f as u32);
            }
        }
    }
    out.normals = mesh.normals.as_ref().map(|a| carry(a, &corner_src));
    out.uvs = mesh.uvs.as_ref().map(|a| carry(a, &corner_src));
    // A corner keeps its value, a triangle its polygon's; points are not touched.
    out.attributes = mesh
        .attributes
        .iter()
        .map(|a| match a.domain {
            Domain::Point => a.clone(),
            Domain::Corner => a.gather(corner_src.iter().copied()),
            Domain::Face => a.gather(face_src.iter().copied()),
        })
        .collect();
    out
}

/// The attribute with its corners re-gathered through `corner_src`.
fn carry<T: Clone>(a: &FaceVarying<T>, corner_src: &[u32]) -> FaceVarying<T> {
    FaceVarying {
        values: a.values.clone(),
        indices: corner_src.iter().map(|&c| a.indices[c as usize]).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pentagon_becomes_three_triangles_with_its_group_and_uvs() {
        let mut m = Mesh {
            positions: vec![[0.0; 3]; 5],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2, 3, 4]);
        m.face_groups = vec![0];
        m.group_names = vec!["steel".into()];
        m.uvs = Some(FaceVarying {
            values: vec![[0.0; 2]; 5],
            indices: vec![4, 3, 2, 1, 0],
        });
        let t = triangulate(&m);
        t.validate().unwrap();
        assert_eq!(t.face_indices, vec![0, 1, 2, 0, 2, 3, 0, 3, 4]);
        assert_eq!(t.face_groups, vec![0, 0, 0]);
        assert_eq!(t.uvs.unwrap().indices, vec![4, 3, 2, 4, 2, 1, 4, 1, 0]);
    }

    #[test]
    fn corners_keep_their_values_and_triangles_their_polygons() {
        use tessd_mesh::Attribute;
        let mut m = Mesh {
            positions: vec![[0.0; 3]; 6],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[1, 3, 4, 5, 2]);
        m.attributes = vec![
            Attribute::new("c", Domain::Corner, 1, (0..8).map(|c| c as f32).collect()),
            Attribute::new("f", Domain::Face, 2, vec![7.0, 8.0, 9.0, 10.0]),
            Attribute::new("p", Domain::Point, 1, vec![1.0; 6]),
        ];
        m.sharp_edges = vec![[1, 2]];
        let t = triangulate(&m);
        t.validate().unwrap();
        assert_eq!(
            t.attributes[0].values,
            [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 3.0, 5.0, 6.0, 3.0, 6.0, 7.0]
        );
        assert_eq!(
            t.attributes[1].values,
            [7.0, 8.0, 9.0, 10.0, 9.0, 10.0, 9.0, 10.0]
        );
        assert_eq!(t.attributes[2], m.attributes[2]);
        assert_eq!(t.sharp_edges, m.sharp_edges);
    }
}
