//! Stanford PLY writing (reading is `ply.rs`): binary little-endian, `float x y z`, plus
//! `nx ny nz` / `s t` when the mesh has normals / UVs (one value per vertex, as PLY stores
//! them: a vertex whose corners carry several, at a UV seam or a sharp normal, is split into
//! one vertex per distinct value, as exporters do; the added vertices follow the mesh's own),
//! and faces as `list uchar int` (`uint` count when a face has more than 255 corners).
//! Blender reads `s t`, MeshLab reads them too.

use super::source::BUF_SIZE;
use super::{per_vertex, split_at_seams};
use crate::Mesh;
use std::io::Write;

/// Writes `mesh` as binary PLY; with `f64_positions`, those as `double` x, y, z. Normals and
/// UVs are per vertex in PLY: a vertex whose corners carry several is split first
/// ([`split_at_seams`]).
pub(crate) fn write(
    mesh: &Mesh,
    w: &mut impl Write,
    f64_positions: Option<&[[f64; 3]]>,
) -> std::io::Result<()> {
    let Some(split) = split_at_seams(mesh) else {
        let normals = mesh.normals.as_ref().and_then(|n| per_vertex(mesh, n));
        let uvs = mesh.uvs.as_ref().and_then(|t| per_vertex(mesh, t));
        return write_vertices(mesh, w, f64_positions, normals, uvs);
    };
    let copies = |v: &u32| *v as usize;
    let positions: Vec<[f32; 3]> = mesh
        .positions
        .iter()
        .copied()
        .chain(split.source.iter().map(|v| mesh.positions[copies(v)]))
        .collect();
    let f64_split: Option<Vec<[f64; 3]>> = f64_positions.map(|f| {
        f.iter()
            .copied()
            .chain(split.source.iter().map(|v| f[copies(v)]))
            .collect()
    });
    let split_mesh = Mesh {
        positions,
        face_offsets: mesh.face_offsets.clone(),
        face_indices: split.face_indices,
        ..Mesh::default()
    };
    write_vertices(
        &split_mesh,
        w,
        f64_split.as_deref(),
        split.normals,
        split.uvs,
    )
}

/// Writes `mesh`'s positions and faces as binary PLY with the given per-vertex normals and UVs.
fn write_vertices(
    mesh: &Mesh,
    w: &mut impl Write,
    f64_positions: Option<&[[f64; 3]]>,
    normals: Option<Vec<[f32; 3]>>,
    uvs: Option<Vec<[f32; 2]>>,
) -> std::io::Result<()> {
    let big_faces = mesh.face_offsets.windows(2).any(|w| w[1] - w[0] > 255);
    let index_type = if mesh.positions.len() > i32::MAX as usize {
        "uint"
    } else {
        "int"
    };
    let mut h =
        String::from("ply\nformat binary_little_endian 1.0\ncomment written by tessd-mesh\n");
    h += &format!("element vertex {}\n", mesh.positions.len());
    h += if f64_positions.is_some() {
        "property double x\nproperty double y\nproperty double z\n"
    } else {
        "property float x\nproperty float y\nproperty float z\n"
    };
    if normals.is_some() {
        h += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if uvs.is_some() {
        h += "property float s\nproperty float t\n";
    }
    h += &format!("element face {}\n", mesh.face_count());
    h += &format!(
        "property list {} {index_type} vertex_indices\nend_header\n",
        if big_faces { "uint" } else { "uchar" }
    );
    w.write_all(h.as_bytes())?;

    let mut buf = Vec::with_capacity(BUF_SIZE + 64);
    for (v, p) in mesh.positions.iter().enumerate() {
        let n = normals.as_ref().map(|n| n[v]);
        let t = uvs.as_ref().map(|t| t[v]);
        match f64_positions {
            Some(f) => {
                for c in f[v] {
                    buf.extend_from_slice(&c.to_le_bytes());
                }
            }
            None => {
                for c in p {
                    buf.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        for c in n.iter().flatten().chain(t.iter().flatten()) {
            buf.extend_from_slice(&c.to_le_bytes());
        }
        spill(&mut buf, w, false)?;
    }
    for face in mesh.faces() {
        if big_faces {
            buf.extend_from_slice(&(face.len() as u32).to_le_bytes());
        } else {
            buf.push(face.len() as u8);
        }
        for &i in face {
            buf.extend_from_slice(&i.to_le_bytes());
            spill(&mut buf, w, false)?;
        }
    }
    spill(&mut buf, w, true)
}

/// Writes the staging buffer out when full (or when `force`).
fn spill(buf: &mut Vec<u8>, w: &mut impl Write, force: bool) -> std::io::Result<()> {
    if force || buf.len() >= BUF_SIZE {
        w.write_all(buf)?;
        buf.clear();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::io::{Format, ReadOptions, read};
    use crate::{Mesh, MeshError};

    fn parse(bytes: &[u8]) -> Result<Mesh, MeshError> {
        let o = ReadOptions::default().with_input_len(bytes.len() as u64);
        read(bytes, Format::Ply, "t.ply", &o)
    }

    #[test]
    fn binary_round_trip_keeps_per_vertex_normals() {
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.normals = Some(crate::FaceVarying {
            values: vec![[0.0, 0.0, 1.0]],
            indices: vec![0; 3],
        });
        let mut out = Vec::new();
        crate::io::write(&m, &mut out, Format::Ply).unwrap();
        let back = parse(&out).unwrap();
        assert_eq!(back.positions, m.positions);
        assert_eq!(back.normals.unwrap().values, [[0.0, 0.0, 1.0]; 3]);
    }

    /// A quad split into two triangles whose UVs meet at a seam along the diagonal, with a
    /// normal per face: PLY gets a vertex per distinct (UV, normal) and reads them back.
    #[test]
    fn seams_split_vertices_and_read_back() {
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[0, 2, 3]);
        // The second face's UVs are shifted by 0.5 on vertices 0 and 2 (a seam); vertex 3 has
        // one UV only.
        m.uvs = Some(crate::FaceVarying {
            values: vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 1.0],
                [0.5, 0.0],
                [1.5, 1.0],
                [0.0, 1.0],
            ],
            indices: vec![0, 1, 2, 3, 4, 5],
        });
        let counts = crate::io::written_counts(&m, Format::Ply);
        assert_eq!((counts.vertices, counts.split_vertices), (6, 2));
        assert!(crate::io::dropped_by_format(&m, Format::Ply).is_empty());
        let mut out = Vec::new();
        crate::io::write(&m, &mut out, Format::Ply).unwrap();
        assert!(String::from_utf8_lossy(&out).contains("property float s\nproperty float t\n"));
        let back = parse(&out).unwrap();
        assert_eq!(back.vertex_count(), 6);
        assert_eq!(back.face(0), &[0, 1, 2]);
        assert_eq!(back.face(1), &[4, 5, 3]);
        assert_eq!(back.positions[4], m.positions[0]);
        assert_eq!(back.positions[5], m.positions[2]);
        // Every corner keeps its UV.
        let uv = |mesh: &Mesh, c: usize| {
            let t = mesh.uvs.as_ref().unwrap();
            t.values[t.indices[c] as usize]
        };
        for c in 0..6 {
            assert_eq!(uv(&back, c), uv(&m, c), "corner {c}");
        }
        // Written again, the read-back mesh needs no split: one UV per vertex.
        assert_eq!(
            crate::io::written_counts(&back, Format::Ply).split_vertices,
            0
        );
    }

    #[test]
    fn big_faces_use_a_uint_count() {
        let mut m = Mesh {
            positions: (0..300).map(|i| [i as f32, (i * i) as f32, 0.0]).collect(),
            ..Mesh::default()
        };
        m.push_face(&(0..300).collect::<Vec<u32>>());
        let mut out = Vec::new();
        crate::io::write(&m, &mut out, Format::Ply).unwrap();
        assert!(String::from_utf8_lossy(&out).contains("property list uint int vertex_indices"));
        assert_eq!(parse(&out).unwrap(), m);
    }
}
