//! Feeds bytes to the OBJ reader (`tessd_mesh::io::read`: positions, n-gons, `vt`/`vn`,
//! groups) from memory, the input's length known as `read_path` knows a file's.
//!
//! Must hold: no panic, no hang, no allocation beyond what the input can hold; an `Ok` mesh
//! is valid (`Mesh::validate`), an error has a message.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tessd_mesh::io::Format;

fuzz_target!(|data: &[u8]| tessd_fuzz::read_mesh(Format::Obj, data));
