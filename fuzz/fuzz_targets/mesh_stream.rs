//! Feeds bytes, written to a file, to the streaming mesh readers the codec's out-of-core
//! compressor uses (`tessd_mesh::io::stream::open`: `PlyFile` when the bytes start with `ply`,
//! else `ObjFile`), then walks the vertex pass and the triangle pass twice each.
//!
//! Must hold: no panic, no hang, no allocation beyond what the file holds; a vertex pass that
//! succeeds hands over exactly `vertex_count` positions; a triangle pass that succeeds hands
//! over only indices below it; a second walk of each pass gives the same result (passes
//! re-read the file, they do not remember it); an error has a message.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::PathBuf;
use std::sync::OnceLock;
use tessd_mesh::io::stream::{MeshSource, open};

/// One file per process for each format, rewritten for every input.
fn path(ply: bool) -> &'static PathBuf {
    static PATHS: OnceLock<[PathBuf; 2]> = OnceLock::new();
    let paths = PATHS.get_or_init(|| {
        let dir = std::env::temp_dir();
        let pid = std::process::id();
        [
            dir.join(format!("tessd-fuzz-stream-{pid}.obj")),
            dir.join(format!("tessd-fuzz-stream-{pid}.ply")),
        ]
    });
    &paths[usize::from(ply)]
}

/// One walk of the vertex pass: the count and a hash of the positions' bits, or the error.
fn vertices(source: &mut dyn MeshSource) -> Result<(u64, u64), String> {
    let (mut n, mut h) = (0u64, DefaultHasher::new());
    source
        .vertices(&mut |p| {
            n += 1;
            p.map(f32::to_bits).hash(&mut h);
        })
        .map_err(|e| e.to_string())?;
    Ok((n, h.finish()))
}

/// One walk of the triangle pass, checking each index against the vertex count.
fn triangles(source: &mut dyn MeshSource) -> Result<(u64, u64), String> {
    let limit = source.vertex_count();
    let (mut n, mut h) = (0u64, DefaultHasher::new());
    source
        .triangles(&mut |t| {
            assert!(t.iter().all(|&i| u64::from(i) < limit), "{t:?} >= {limit}");
            n += 1;
            t.hash(&mut h);
        })
        .map_err(|e| e.to_string())?;
    Ok((n, h.finish()))
}

fuzz_target!(|data: &[u8]| {
    let path = path(data.starts_with(b"ply"));
    std::fs::write(path, data).expect("write the input");
    let mut source = match open(path) {
        Ok(source) => source,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    let first = vertices(source.as_mut());
    if let Ok((n, _)) = first {
        assert_eq!(n, source.vertex_count());
    }
    assert_eq!(first, vertices(source.as_mut()));
    let tris = triangles(source.as_mut());
    assert_eq!(tris, triangles(source.as_mut()));
    if let Err(message) = first.and(tris) {
        assert!(!message.is_empty());
    }
});
