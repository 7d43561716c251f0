//! Feeds bytes to the PLY reader (`tessd_mesh::io::read`: ASCII and binary in either byte
//! order, as the header says) from memory, the input's length known as `read_path` knows a
//! file's.
//!
//! Must hold: no panic, no hang, no allocation beyond what the input can hold; an `Ok` mesh
//! is valid (`Mesh::validate`), an error has a message.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tessd_mesh::io::{Format, ReadOptions, read};

fuzz_target!(|data: &[u8]| {
    let options = ReadOptions::default().with_input_len(data.len() as u64);
    match read(data, Format::Ply, "<fuzz>", &options) {
        Ok(mesh) => mesh.validate().expect("a mesh read is valid"),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
});
