//! Inputs the fuzzer found (fuzz/fuzz_targets/mesh_stream.rs: the codec's streaming readers),
//! each run as the target runs it: the file opened, then each pass walked.

use std::path::{Path, PathBuf};
use tessd_mesh::io::stream::{MeshSource, open};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(name)
}

/// Writes `bytes` as `name` in a fresh folder and opens it.
fn open_bytes(
    name: &str,
    bytes: &[u8],
) -> (tempfile::TempDir, Result<Box<dyn MeshSource>, String>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let source = open(&path).map_err(|e| e.to_string());
    (dir, source)
}

fn vertices(source: &mut dyn MeshSource) -> Result<Vec<[f32; 3]>, String> {
    let mut out = Vec::new();
    source
        .vertices(&mut |p| out.push(p))
        .map_err(|e| e.to_string())?;
    Ok(out)
}

const XYZ: &str = "property float x\nproperty float y\nproperty float z\n";

#[test]
fn the_fuzzers_file_is_refused_at_once() {
    // A 2 KiB file whose first element, `veAtex`, has 4 294 967 295 110 records and (its
    // property line malformed) no properties: the vertex pass walked every one of them, a hang
    // of hours. Binary records without properties are now skipped in one step, and the vertex
    // element behind them declares more records than the file holds.
    let err = open(&data("stream_huge_element.ply"))
        .err()
        .expect("refused");
    let message = err.to_string();
    assert!(
        message.contains("element vertex declares 188 records of at least 18 bytes, but 1557"),
        "{message}"
    );
}

#[test]
fn counts_beyond_the_file_are_refused_naming_the_element() {
    for (format, least) in [("ascii", 1), ("binary_little_endian", 12)] {
        let header =
            format!("ply\nformat {format} 1.0\nelement vertex 4000000000000\n{XYZ}end_header\n");
        let mut bytes = header.into_bytes();
        bytes.extend_from_slice(&[0; 12]);
        let (_dir, source) = open_bytes("v.ply", &bytes);
        let message = source.err().expect("refused");
        assert!(
            message.contains(&format!(
                "element vertex declares 4000000000000 records of at least {least} bytes, but 12 bytes follow the header"
            )),
            "{message}"
        );
    }
}

#[test]
fn binary_elements_without_properties_cost_nothing() {
    // Legal, if odd: records of no bytes. Skipped in one step, whatever their count.
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\nelement junk 4000000000000\nelement vertex 1\n\
         {XYZ}end_header\n"
    )
    .into_bytes();
    for x in [1.0f32, 2.0, 3.0] {
        bytes.extend_from_slice(&x.to_le_bytes());
    }
    let (_dir, source) = open_bytes("j.ply", &bytes);
    let mut source = source.unwrap();
    assert_eq!(source.vertex_count(), 1);
    assert_eq!(vertices(source.as_mut()).unwrap(), [[1.0, 2.0, 3.0]]);
}

#[test]
fn a_file_that_holds_its_counts_still_reads() {
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let text = format!(
        "ply\nformat ascii 1.0\nelement vertex 3\n{XYZ}element face 1\n\
         property list uchar int vertex_indices\nend_header\n{body}"
    );
    let (_dir, source) = open_bytes("t.ply", text.as_bytes());
    let mut source = source.unwrap();
    assert_eq!(vertices(source.as_mut()).unwrap().len(), 3);
    let mut tris = Vec::new();
    source.triangles(&mut |t| tris.push(t)).unwrap();
    assert_eq!(tris, [[0, 1, 2]]);
}
