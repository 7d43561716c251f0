//! The streaming readers (PLY ascii / binary of either byte order, OBJ) give the same file as the
//! same mesh compressed from memory after `tessd-mesh` read it: the out-of-core path and the
//! in-memory path agree byte for byte, and bad files are clear errors naming the element.

use std::io::{Cursor, Write};
use std::path::Path;

use tessd_codec::source::{ObjFile, PlyFile, open};
use tessd_codec::{CodecError, Params, compress, compress_source};

fn in_memory(path: &Path, params: Params) -> Vec<u8> {
    let mesh = tessd_mesh::io::read_path(path, &Default::default()).unwrap();
    let tris = mesh.fan_triangles();
    let mut out = Cursor::new(Vec::new());
    compress(&mesh.positions, &tris, params, &mut out, &|_| true).unwrap();
    out.into_inner()
}

fn streamed(path: &Path, params: Params) -> Result<Vec<u8>, CodecError> {
    let mut src = open(path)?;
    let mut out = Cursor::new(Vec::new());
    compress_source(&mut *src, params, &mut out, &|_| true)?;
    Ok(out.into_inner())
}

#[test]
fn streamed_files_compress_like_the_mesh_in_memory() {
    let params = Params {
        min_cell: 2000,
        ..Params::default()
    };
    for name in [
        "bun_zipper.ply",
        "stanford_bunny.obj",
        "fandisk.obj",
        "spot_quadrangulated.obj",
        "suzanne.obj",
    ] {
        let path = tessd_testdata::shared(&format!("mesh/{name}"));
        assert_eq!(
            streamed(&path, params).unwrap(),
            in_memory(&path, params),
            "{name}"
        );
    }
}

/// A PLY of `positions` and `faces` in `format` (with an extra scalar per vertex and per face
/// to skip), written by hand.
fn write_ply(path: &Path, format: &str, positions: &[[f32; 3]], faces: &[Vec<u32>]) {
    let mut f = std::fs::File::create(path).unwrap();
    write!(
        f,
        "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face {}\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n",
        positions.len(),
        faces.len()
    )
    .unwrap();
    let big = format == "binary_big_endian";
    let put32 = |f: &mut std::fs::File, b: [u8; 4]| {
        let b = if big { [b[3], b[2], b[1], b[0]] } else { b };
        f.write_all(&b).unwrap();
    };
    for p in positions {
        if format == "ascii" {
            writeln!(f, "{} {} {} 7", p[0], p[1], p[2]).unwrap();
        } else {
            for c in p {
                put32(&mut f, c.to_le_bytes());
            }
            f.write_all(&[7]).unwrap();
        }
    }
    for face in faces {
        if format == "ascii" {
            let idx: Vec<String> = face.iter().map(|i| i.to_string()).collect();
            writeln!(f, "{} {} 0.5", face.len(), idx.join(" ")).unwrap();
        } else {
            f.write_all(&[face.len() as u8]).unwrap();
            for &i in face {
                put32(&mut f, (i as i32).to_le_bytes());
            }
            put32(&mut f, 0.5f32.to_le_bytes());
        }
    }
}

#[test]
fn binary_and_ascii_ply_of_either_byte_order_read_alike() {
    let mesh = tessd_mesh::io::read_path(
        &tessd_testdata::shared("mesh/spot_quadrangulated.obj"),
        &Default::default(),
    )
    .unwrap();
    let faces: Vec<Vec<u32>> = mesh.faces().map(|f| f.to_vec()).collect();
    let dir = tempfile::tempdir().unwrap();
    let params = Params {
        min_cell: 1000,
        ..Params::default()
    };
    let mut files = Vec::new();
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let path = dir.path().join(format!("{format}.ply"));
        write_ply(&path, format, &mesh.positions, &faces);
        files.push(streamed(&path, params).unwrap());
    }
    assert_eq!(files[0], files[1]);
    assert_eq!(files[0], files[2]);
    let obj = tessd_testdata::shared("mesh/spot_quadrangulated.obj");
    assert_eq!(files[0], in_memory(&obj, params));
}

#[test]
fn bad_files_name_the_element() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("bad.ply");
    write_ply(
        &ply,
        "binary_little_endian",
        &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[vec![0, 1, 2], vec![0, 1, 9]],
    );
    let e = streamed(&ply, Params::default()).unwrap_err().to_string();
    assert!(e.contains("face 1 uses vertex 9"), "{e}");
    // truncated: the last face cut
    let bytes = std::fs::read(&ply).unwrap();
    std::fs::write(&ply, &bytes[..bytes.len() - 6]).unwrap();
    let e = streamed(&ply, Params::default()).unwrap_err().to_string();
    assert!(e.contains("ends inside face 1"), "{e}");
    write_ply(
        &ply,
        "ascii",
        &[[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[vec![0, 1, 2]],
    );
    let e = streamed(&ply, Params::default()).unwrap_err().to_string();
    assert!(e.contains("vertex 1") && e.contains("non-finite"), "{e}");
    let obj = dir.path().join("bad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 -4\n").unwrap();
    let e = streamed(&obj, Params::default()).unwrap_err().to_string();
    assert!(e.contains("line 5"), "{e}");
    assert!(ObjFile::open(&dir.path().join("missing.obj")).is_err());
    assert!(
        PlyFile::open(&obj)
            .unwrap_err()
            .to_string()
            .contains("not a PLY file")
    );
}
