//! Format versions (issue 34 item 6): a file of the previous format is refused with a message
//! naming its version, before any length check, so even a truncated old file says what it is;
//! the version-2 head is small.

use std::io::Cursor;

use tessd_codec::{CodecError, Params, Tsc, compress, format};

/// suzanne.obj at 10 bits, written by the version-1 tessd (commit 6598afde): 2 759 bytes.
const V1: &[u8] = include_bytes!("data/suzanne_v1_p10.tsc");

fn refusal(bytes: &[u8]) -> (u64, String) {
    match Tsc::open(bytes) {
        Err(CodecError::Corrupt { offset, why }) => (offset, why),
        Err(e) => panic!("not a corrupt-file error: {e}"),
        Ok(_) => panic!("an old file of {} bytes was opened", bytes.len()),
    }
}

#[test]
fn a_version_1_file_is_refused_naming_its_version() {
    assert_eq!(&V1[..4], b"TSC\x1a");
    assert_eq!(u16::from_le_bytes([V1[4], V1[5]]), 1);
    let (offset, why) = refusal(V1);
    assert_eq!(offset, 4);
    assert_eq!(
        why,
        "written by format version 1 (an older tessd); this reader reads version 3: compress \
         the mesh again"
    );
    let shown = Tsc::open(V1).err().unwrap().to_string();
    assert!(shown.contains("byte offset 4"), "{shown}");
    // the version is read before the length: the first 6 bytes are enough to name it
    for len in [6, 9, 40, 127] {
        assert_eq!(refusal(&V1[..len]), (offset, why.clone()), "{len} bytes");
    }
}

/// suzanne.obj at 10 bits, written by the version-2 tessd (commit 38cf6e1e): 1 852 bytes. Its
/// layout is version 3's, its connectivity contexts are not: read, it would decode to garbage.
const V2: &[u8] = include_bytes!("data/suzanne_v2_p10.tsc");

#[test]
fn a_version_2_file_is_refused_naming_its_version() {
    assert_eq!(&V2[..4], b"TSC\x1a");
    assert_eq!(u16::from_le_bytes([V2[4], V2[5]]), 2);
    let (offset, why) = refusal(V2);
    assert_eq!(offset, 4);
    assert_eq!(
        why,
        "written by format version 2 (an older tessd); this reader reads version 3: compress \
         the mesh again"
    );
    for len in [6, 9, 40] {
        assert_eq!(refusal(&V2[..len]), (offset, why.clone()), "{len} bytes");
    }
    // the same file with version 3 in its head opens (the layout is the same): only the version
    // keeps its old codes from being decoded
    let mut relabelled = V2.to_vec();
    relabelled[4..6].copy_from_slice(&format::VERSION.to_le_bytes());
    assert!(Tsc::open(&relabelled).is_ok());
}

#[test]
fn a_newer_version_and_a_bad_magic_are_refused() {
    let mut newer = V1.to_vec();
    newer[4..6].copy_from_slice(&(format::VERSION + 1).to_le_bytes());
    assert!(refusal(&newer).1.contains("a newer tessd"));
    let mut bad = V1.to_vec();
    bad[1] = b'X';
    assert_eq!(refusal(&bad).0, 0);
    assert!(refusal(&V1[..3]).1.contains("shorter than magic"));
}

#[test]
fn the_version_2_head_and_trailer_are_small_and_exact() {
    let path = tessd_testdata::shared("mesh/suzanne.obj");
    let mesh = tessd_mesh::io::read_path(&path, &Default::default()).unwrap();
    let tris: Vec<[u32; 3]> = mesh.faces().map(|f| [f[0], f[1], f[2]]).collect();
    let params = Params {
        bits: 10,
        ..Params::default()
    };
    let mut file = Cursor::new(Vec::new());
    let report = compress(&mesh.positions, &tris, params, &mut file, &|_| true).unwrap();
    let bytes = file.into_inner();
    let tsc = Tsc::open(&bytes).unwrap();
    let h = &tsc.header;
    assert_eq!(u16::from_le_bytes([bytes[4], bytes[5]]), format::VERSION);
    // f32 origin (the OBJ's floats), f64 step, min_cell in 2 bytes
    assert!(h.head_len <= 32, "a {}-byte head", h.head_len);
    assert!(h.index.1 <= 32, "a {}-byte trailer for one cell", h.index.1);
    assert_eq!(h.index.0 + h.index.1, bytes.len() as u64);
    // the grid comes back exact
    assert_eq!(h.grid, report.grid);
    assert_eq!(h.params, params);
    assert_eq!(
        (h.vertices, h.triangles),
        (report.vertices, report.triangles)
    );
    assert_eq!(
        (h.input_vertices, h.input_triangles),
        (report.input_vertices, report.input_triangles)
    );
}
