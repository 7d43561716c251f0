//! Small meshes the unit tests share.

use crate::topology::Faces;
use tessd_mesh::Mesh;

/// A cube, outward quads, vertices at the corners of [0, 1]³.
pub fn cube() -> Mesh {
    let mut m = Mesh {
        positions: (0..8)
            .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
            .collect(),
        ..Mesh::default()
    };
    for f in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        m.push_face(&f);
    }
    m
}

/// Six triangles around vertex 0; ring 1..=6.
pub fn hex_fan() -> Faces {
    let mut indices = Vec::new();
    for i in 0..6u32 {
        indices.extend_from_slice(&[0, 1 + i, 1 + (i + 1) % 6]);
    }
    Faces {
        offsets: (0..=6).map(|f| 3 * f).collect(),
        indices,
        vertex_count: 7,
    }
}
