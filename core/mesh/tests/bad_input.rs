//! Malformed and hostile inputs: exact error messages, no allocation driven by headers,
//! no partial output files; plus a hand-made big-endian PLY.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use tessd_mesh::io::{self, Format, ReadOptions};
use tessd_mesh::{Mesh, MeshError};

fn opts(len: Option<usize>) -> ReadOptions {
    let mut o = ReadOptions::default();
    o.input_len = len.map(|l| l as u64);
    o
}

fn read_mem(bytes: &[u8], format: Format, known_len: bool) -> Result<Mesh, MeshError> {
    let name = format!("t.{}", format.extension());
    io::read(
        bytes,
        format,
        &name,
        &opts(known_len.then_some(bytes.len())),
    )
}

fn err(bytes: &[u8], format: Format) -> String {
    read_mem(bytes, format, true).unwrap_err().to_string()
}

/// A `w`×`h` grid of vertices split into triangles.
fn grid(w: u32, h: u32) -> Mesh {
    let mut m = Mesh {
        positions: (0..w * h)
            .map(|i| [(i % w) as f32, (i / w) as f32, (i % 7) as f32])
            .collect(),
        ..Mesh::default()
    };
    for y in 0..h - 1 {
        for x in 0..w - 1 {
            let v = y * w + x;
            m.push_face(&[v, v + 1, v + w + 1]);
            m.push_face(&[v, v + w + 1, v + w]);
        }
    }
    m
}

// ---------------------------------------------------------------------------------------- PLY

#[test]
fn truncated_binary_ply_names_the_face() {
    let m = grid(40, 30); // 2262 triangles
    let mut bytes = Vec::new();
    io::write(&m, &mut bytes, Format::Ply).unwrap();
    let header = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let faces_at = header + 12 * m.positions.len();
    let cut = &bytes[..faces_at + 13 * 1234 + 5];
    for known in [true, false] {
        match read_mem(cut, Format::Ply, known).unwrap_err() {
            MeshError::Parse { line, message, .. } => {
                assert_eq!((line, message.as_str()), (0, "face 1234: file ends"));
            }
            other => panic!("{other}"),
        }
    }
    assert_eq!(err(cut, Format::Ply), "t.ply: face 1234: file ends");
    assert_eq!(
        err(&bytes[..header + 12 * 77 + 3], Format::Ply),
        "t.ply: vertex 77: file ends"
    );

    // Through a file too.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.ply");
    std::fs::write(&path, cut).unwrap();
    let e = io::read_path(&path, &ReadOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("{}: face 1234: file ends", path.display())
    );
    assert_eq!(e.code(), "invalid_mesh");
}

#[test]
fn hostile_ply_counts_do_not_allocate() {
    let head = |faces: &str, format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face {faces}\nproperty list uchar int vertex_indices\n\
             end_header\n"
        )
    };
    // Above the element limit: refused from the header alone.
    let mut bytes = head("4000000000", "binary_little_endian").into_bytes();
    bytes.extend_from_slice(&[0u8; 36]);
    let e = read_mem(&bytes, Format::Ply, true).unwrap_err();
    assert!(matches!(e, MeshError::TooLarge(_)), "{e:?}");
    assert_eq!(
        e.to_string(),
        "t.ply: PLY header declares 4000000000 face elements; the limit is 2147483648"
    );
    assert_eq!(e.code(), "too_large");
    // Under the limit but far beyond the data, in every encoding, length known or not: the
    // reader reserves what the input can hold (a 2e9-face reservation would abort the test).
    for format in ["binary_little_endian", "binary_big_endian", "ascii"] {
        let mut bytes = head("2000000000", format).into_bytes();
        if format == "ascii" {
            bytes.extend_from_slice(b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        } else {
            bytes.extend_from_slice(&[0u8; 36]);
            bytes.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
            if format == "binary_big_endian" {
                let n = bytes.len();
                bytes[n - 12..].copy_from_slice(&[0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 2]);
            }
        }
        for known in [true, false] {
            let e = read_mem(&bytes, Format::Ply, known).unwrap_err();
            assert!(
                e.to_string().ends_with("face 1: file ends"),
                "{format}: {e}"
            );
        }
    }
    // A tighter caller limit.
    let o = ReadOptions::default().with_max_elements(2);
    let e = io::read(head("1", "ascii").as_bytes(), Format::Ply, "t.ply", &o).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.ply: PLY header declares 3 vertex elements; the limit is 2"
    );
}

#[test]
fn ply_index_and_size_errors() {
    let ply = |face: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n0 1 0\n{face}\n"
        )
    };
    assert_eq!(
        err(ply("3 0 1 3").as_bytes(), Format::Ply),
        "t.ply:13: face 0: vertex index 3 is out of range; the file has 3 vertices"
    );
    assert_eq!(
        err(ply("2 0 1").as_bytes(), Format::Ply),
        "t.ply:13: face 0 has 2 vertices; a face needs at least 3"
    );
    assert_eq!(
        err(ply("3 0 1 x").as_bytes(), Format::Ply),
        "t.ply:13: face 0: bad number 'x'"
    );
    // Binary fast path: negative index.
    let mut bytes = ply("").into_bytes();
    bytes.truncate(bytes.len() - 19); // the ASCII vertex and face lines
    let s = String::from_utf8(bytes)
        .unwrap()
        .replace("ascii", "binary_little_endian");
    let mut bytes = s.into_bytes();
    bytes.extend_from_slice(&[0u8; 36]);
    bytes.push(3);
    for i in [0i32, 1, -2] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    assert_eq!(
        err(&bytes, Format::Ply),
        "t.ply: face 0: vertex index -2 is out of range; the file has 3 vertices"
    );
    let n = bytes.len();
    bytes[n - 13] = 2;
    assert_eq!(
        err(&bytes[..n - 4], Format::Ply),
        "t.ply: face 0 has 2 vertices; a face needs at least 3"
    );
    // A caller limit below the file's counts.
    bytes[n - 13] = 3;
    bytes[n - 4..].copy_from_slice(&2i32.to_le_bytes());
    read_mem(&bytes, Format::Ply, true).unwrap();
    let o = ReadOptions::default().with_max_elements(2);
    let e = io::read(&bytes[..], Format::Ply, "t.ply", &o).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.ply: PLY header declares 3 vertex elements; the limit is 2"
    );
}

/// Writes `v` big-endian.
fn be(out: &mut Vec<u8>, v: &[u8]) {
    out.extend_from_slice(v);
}

#[test]
fn big_endian_ply_made_by_hand() {
    let header = "ply\nformat binary_big_endian 1.0\ncomment made by hand\n\
        element vertex 4\nproperty double x\nproperty float32 y\nproperty int16 z\n\
        property uchar red\nproperty list uint8 int32 junk\nproperty float nx\nproperty float ny\n\
        property float nz\nproperty float texture_u\nproperty float texture_v\n\
        element face 2\nproperty uint16 flags\nproperty list ushort uint vertex_indices\n\
        property list uchar float texcoord\nelement material 1\nproperty float shine\nend_header\n";
    let mut b = header.as_bytes().to_vec();
    let pos: [[f64; 3]; 4] = [
        [0.5, -1.25, 3.0],
        [2.0, 0.0, -4.0],
        [1e10, 3.5, 7.0],
        [-0.0, 1.0, 0.0],
    ];
    for (i, p) in pos.iter().enumerate() {
        be(&mut b, &p[0].to_be_bytes());
        be(&mut b, &(p[1] as f32).to_be_bytes());
        be(&mut b, &(p[2] as i16).to_be_bytes());
        b.push(200); // red
        b.push(i as u8); // junk list of i ints
        for k in 0..i {
            be(&mut b, &(k as i32 * -7).to_be_bytes());
        }
        for c in [0.0f32, 0.0, 1.0, i as f32 / 4.0, 1.0 - i as f32 / 4.0] {
            be(&mut b, &c.to_be_bytes());
        }
    }
    for face in [&[0u32, 1, 2][..], &[0, 2, 3, 1][..]] {
        be(&mut b, &0xbeefu16.to_be_bytes());
        be(&mut b, &(face.len() as u16).to_be_bytes());
        for &v in face {
            be(&mut b, &v.to_be_bytes());
        }
        b.push(2);
        be(&mut b, &0.5f32.to_be_bytes());
        be(&mut b, &0.25f32.to_be_bytes());
    }
    be(&mut b, &9.5f32.to_be_bytes());
    for known in [true, false] {
        let m = read_mem(&b, Format::Ply, known).unwrap();
        assert_eq!(
            m.positions,
            [
                [0.5, -1.25, 3.0],
                [2.0, 0.0, -4.0],
                [1e10, 3.5, 7.0],
                [-0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(m.face_offsets, [0, 3, 7]);
        assert_eq!(m.face_indices, [0, 1, 2, 0, 2, 3, 1]);
        let n = m.normals.as_ref().unwrap();
        assert_eq!(n.values, [[0.0, 0.0, 1.0]; 4]);
        assert_eq!(n.indices, m.face_indices);
        let t = m.uvs.as_ref().unwrap();
        assert_eq!(
            t.values,
            [[0.0, 1.0], [0.25, 0.75], [0.5, 0.5], [0.75, 0.25]]
        );
    }
    // Truncated inside the trailing element.
    let e = err(&b[..b.len() - 2], Format::Ply);
    assert_eq!(e, "t.ply: material 0: file ends");
}

// ---------------------------------------------------------------------------------------- OBJ

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn obj_index_errors_name_line_and_index() {
    let cases = [
        (
            "f 1 2 4\n",
            "t.obj:4: vertex index 4 is out of range; the file has 3 vertices",
        ),
        (
            "f 1 0 2\n",
            "t.obj:4: vertex index 0 is invalid; OBJ indices start at 1",
        ),
        (
            "f -1 -2 -4\n",
            "t.obj:4: vertex index -4 is out of range; 3 vertices are defined before it",
        ),
        (
            "vt 0 0\nf 1/1 2/1 3/2\n",
            "t.obj:5: texture coordinate index 2 is out of range; the file has 1 texture coordinates",
        ),
        (
            "f 1//1 2//1 3//1\n",
            "t.obj:4: normal index 1 is out of range; the file has 0 normals",
        ),
        ("f 1 2 x\n", "t.obj:4: bad vertex index 'x' in 'f'"),
        ("f 1 2 3/1/1/1\n", "t.obj:4: bad face corner '3/1/1/1'"),
        ("f 1 2 /1\n", "t.obj:4: bad face corner '/1'"),
        (
            "f 1 2\n",
            "t.obj:4: face has 2 vertices; a face needs at least 3",
        ),
    ];
    for (tail, want) in cases {
        assert_eq!(
            err(format!("{TRI}{tail}").as_bytes(), Format::Obj),
            want,
            "{tail}"
        );
    }
    // The out-of-range index is reported at its own line even with later lines.
    let text = format!("{TRI}f 1 2 3\nf 1 2 9\nf 1 2 3\n# end\n");
    assert_eq!(
        err(text.as_bytes(), Format::Obj),
        "t.obj:5: vertex index 9 is out of range; the file has 3 vertices"
    );
}

#[test]
fn obj_bad_numbers_name_the_line() {
    let mut text = String::new();
    for i in 0..11 {
        text += &format!("v {i} 0 0\n");
    }
    text += "v 1 abc 0\n";
    assert_eq!(
        err(text.as_bytes(), Format::Obj),
        "t.obj:12: bad coordinate 'abc' in 'v'"
    );
    assert_eq!(
        err(b"vn 1 0 1e\n", Format::Obj),
        "t.obj:1: bad coordinate '1e' in 'vn'"
    );
    assert_eq!(
        err(b"vt\n", Format::Obj),
        "t.obj:1: 'vt' needs a u coordinate"
    );
}

#[test]
fn obj_nan_is_rejected_by_validation() {
    let e = read_mem(
        format!("v nan 0 0\n{TRI}f 2 3 4\n").as_bytes(),
        Format::Obj,
        true,
    );
    let e = e.unwrap_err();
    assert!(matches!(e, MeshError::Invalid(_)));
    assert_eq!(
        e.to_string(),
        "vertex 0 has a non-finite coordinate x = NaN"
    );
    let e = err(b"v 0 1e39 0\n", Format::Obj);
    assert_eq!(e, "vertex 0 has a non-finite coordinate y = inf");
}

#[test]
fn obj_file_ending_mid_line() {
    // A complete last line without a newline is fine...
    let m = read_mem(format!("{TRI}f 1 2 3").as_bytes(), Format::Obj, true).unwrap();
    assert_eq!(m.face(0), &[0, 1, 2]);
    // ...a cut one is not.
    assert_eq!(
        err(format!("{TRI}f 1 2").as_bytes(), Format::Obj),
        "t.obj:4: face has 2 vertices; a face needs at least 3"
    );
    assert_eq!(
        err(b"v 0 0 0\nv 1 0", Format::Obj),
        "t.obj:2: 'v' needs 3 coordinates, got 2"
    );
    // A continuation at the very end of the file.
    let m = read_mem(format!("{TRI}f 1 2 3 \\").as_bytes(), Format::Obj, true).unwrap();
    assert_eq!(m.face_count(), 1);
}

// ---------------------------------------------------------------------------------------- STL

fn stl_of(m: &Mesh) -> Vec<u8> {
    let mut bytes = Vec::new();
    io::write(m, &mut bytes, Format::Stl).unwrap();
    bytes
}

#[test]
fn stl_with_a_wrong_binary_count() {
    let m = grid(3, 2); // 4 triangles
    let mut bytes = stl_of(&m);
    assert_eq!(bytes.len(), 84 + 4 * 50);
    bytes[80..84].copy_from_slice(&10u32.to_le_bytes());
    assert_eq!(
        err(&bytes, Format::Stl),
        "t.stl: binary STL header declares 10 triangles (584 bytes) but the file has 284 bytes"
    );
    let e = read_mem(&bytes, Format::Stl, false).unwrap_err();
    assert_eq!(e.to_string(), "t.stl: triangle 4: file ends");
    bytes[80..84].copy_from_slice(&3u32.to_le_bytes());
    let e = read_mem(&bytes, Format::Stl, false).unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.stl: binary STL has data after its 3 triangles"
    );
    assert_eq!(
        err(b"abc", Format::Stl),
        "t.stl: not an STL file: 3 bytes, shorter than a binary STL header"
    );

    // Through a file, whose size is known from its metadata.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.STL");
    std::fs::write(&path, &bytes).unwrap();
    let e = io::read_path(&path, &ReadOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .ends_with("declares 3 triangles (234 bytes) but the file has 284 bytes")
    );
}

#[test]
fn stl_ascii_errors() {
    assert_eq!(
        err(b"solid x\nfacet\nvertex 1 2\n", Format::Stl),
        "t.stl:3: 'vertex' needs 3 coordinates, got 2"
    );
    assert_eq!(
        err(b"solid x\nvertex 1 2 3\n", Format::Stl),
        "t.stl:2: 'vertex' outside a facet"
    );
    assert_eq!(
        err(b"solid x\nfacet\nvertex 1 2 3\n", Format::Stl),
        "t.stl:3: file ends inside a facet"
    );
    assert_eq!(
        err(b"solid x\nfoo\n", Format::Stl),
        "t.stl:2: unexpected 'foo' in an ASCII STL"
    );
    let m = read_mem(b"solid empty\nendsolid empty\n", Format::Stl, true).unwrap();
    assert_eq!((m.vertex_count(), m.face_count()), (0, 0));
}

// ---------------------------------------------------------------------------------------- OFF

#[test]
fn off_errors() {
    assert_eq!(
        err(b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", Format::Off),
        "t.off:6: face 1: file ends"
    );
    assert_eq!(
        err(b"OFF\n1 0 0\n0 x 0\n", Format::Off),
        "t.off:3: vertex 0: bad coordinate 'x'"
    );
    assert_eq!(
        err(b"OFF\n1 0 0\n0 0\n", Format::Off),
        "t.off:3: vertex 0: expected 3 values, got 2"
    );
    assert_eq!(
        err(b"OFF\n-1 0 0\n", Format::Off),
        "t.off:2: bad vertex count '-1'"
    );
    assert_eq!(
        err(b"PLY\n", Format::Off),
        "t.off:1: not an OFF file: expected 'OFF', got 'PLY'"
    );
    assert_eq!(
        err(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", Format::Off),
        "t.off:6: face 0: expected 4 vertex indices, got 3"
    );
    let e = err(b"OFF\n3000000000 0 0\n", Format::Off);
    assert_eq!(
        e,
        "t.off: OFF header declares 3000000000 vertices; the limit is 2147483648"
    );
}

// ---------------------------------------------------------------------------------------- misc

#[test]
fn limits_cancel_and_io_errors() {
    let o = ReadOptions::default().with_max_elements(2);
    let e = io::read(TRI.as_bytes(), Format::Obj, "t.obj", &o).unwrap_err();
    assert_eq!(e.to_string(), "t.obj: 'v' records exceed the limit of 2");

    let o = ReadOptions::default().with_cancel(Arc::new(AtomicBool::new(true)));
    let e = io::read(TRI.as_bytes(), Format::Obj, "t.obj", &o).unwrap_err();
    assert!(matches!(e, MeshError::Cancelled));
    assert_eq!(e.code(), "cancelled");

    let e = io::read_path(Path::new("/nonexistent/x.obj"), &ReadOptions::default()).unwrap_err();
    assert_eq!(e.code(), "io");
    assert!(e.to_string().starts_with("/nonexistent/x.obj: "), "{e}");
    let e = io::read_path(Path::new("x.3ds"), &ReadOptions::default()).unwrap_err();
    assert_eq!(e.code(), "unsupported");
}

#[test]
fn invalid_meshes_are_not_written() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = grid(2, 2);
    m.push_face(&[0, 1, 7]);
    for ext in ["obj", "ply", "stl", "off"] {
        let path = dir.path().join(format!("bad.{ext}"));
        let e = io::write_path(&m, &path).unwrap_err();
        assert_eq!(
            e.to_string(),
            "face 2 uses vertex 7; the mesh has 4 vertices"
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let e = io::write_path(&grid(2, 2), &dir.path().join("x.dae")).unwrap_err();
    assert_eq!(e.code(), "unsupported");
}

/// The bulk paths of binary PLY (whole buffers of xyz records and of triangles, range-checked
/// by a max per buffer) still name the face and index at fault, far into the file and after a
/// quad that interrupts the run of triangles; and a NaN deep in the vertices names the vertex.
#[test]
fn binary_ply_bulk_paths_name_the_element() {
    let faces = 20_000u32;
    let ply = |bad_face: Option<u32>, nan_vertex: Option<usize>| {
        let mut m = Mesh {
            positions: (0..faces + 3).map(|i| [i as f32, 1.0, 2.0]).collect(),
            ..Mesh::default()
        };
        for f in 0..faces {
            if f == 7_000 {
                m.push_face(&[f, f + 1, f + 2, f + 3]);
            } else {
                m.push_face(&[f, f + 1, f + 2]);
            }
        }
        // Written valid (the writer validates), then broken in place.
        let mut bytes = Vec::new();
        io::write(&m, &mut bytes, Format::Ply).unwrap();
        let body = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        if let Some(v) = nan_vertex {
            let at = body + 12 * v + 8;
            bytes[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        }
        if let Some(f) = bad_face {
            // Every face before `f` is a triangle of 13 bytes but face 7000, a quad of 17.
            let start =
                body + 12 * (faces as usize + 3) + 13 * f as usize + 4 * (f > 7_000) as usize;
            assert_eq!(bytes[start], 3);
            bytes[start + 5..start + 9].copy_from_slice(&(faces + 3).to_le_bytes());
        }
        bytes
    };
    let m = read_mem(&ply(None, None), Format::Ply, true).unwrap();
    assert_eq!((m.face_count(), m.triangle_count()), (20_000, 20_001));
    assert_eq!(m.face(7_000), [7_000, 7_001, 7_002, 7_003]);
    assert_eq!(
        err(&ply(Some(15_321), None), Format::Ply),
        "t.ply: face 15321: vertex index 20003 is out of range; the file has 20003 vertices"
    );
    assert_eq!(
        err(&ply(Some(2), None), Format::Ply),
        "t.ply: face 2: vertex index 20003 is out of range; the file has 20003 vertices"
    );
    assert_eq!(
        err(&ply(None, Some(12_345)), Format::Ply),
        "vertex 12345 has a non-finite coordinate z = NaN"
    );
}
