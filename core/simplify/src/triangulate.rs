//! Optional triangulation (Belblidia & Perrin, section 2): polygons are split into triangles
//! before merging so that no warped polygon appears once their vertices move.

use tessd_mesh::{FaceVarying, Mesh};

/// Fan-triangulates every face with more than three corners, carrying face groups and
/// face-varying attributes. Fans suit the convex polygons meshes mostly hold; a concave
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
    };
    out.face_offsets.push(0);
    // The input corner of each output corner, to carry face-varying data.
    let mut corner_src: Vec<u32> = Vec::with_capacity(3 * tris);
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
        }
    }
    out.normals = mesh.normals.as_ref().map(|a| carry(a, &corner_src));
    out.uvs = mesh.uvs.as_ref().map(|a| carry(a, &corner_src));
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
}
