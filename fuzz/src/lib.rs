//! What the fuzz targets share.

use tessd_mesh::io::{Format, ReadOptions, read};

/// Feeds `data` to the in-memory reader of `format` (`tessd_mesh::io::read`), the input's
/// length known as `read_path` knows a file's. Must hold: an `Ok` mesh is valid
/// (`Mesh::validate`), an error has a message.
pub fn read_mesh(format: Format, data: &[u8]) {
    let options = ReadOptions::default().with_input_len(data.len() as u64);
    match read(data, format, "<fuzz>", &options) {
        Ok(mesh) => mesh.validate().expect("a mesh read is valid"),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}
