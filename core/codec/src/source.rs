//! Where a compression reads its mesh from, in passes (paper 003 §5.1: the points are read and
//! quantised before the triangles are distributed): `tessd-mesh`'s streaming readers, so that a
//! PLY or OBJ file is never held whole.

pub use tessd_mesh::io::stream::{MeshSource, ObjFile, PlyFile, Slices, streamable};

use crate::error::CodecError;

/// A mesh reading error as the codec reports it: the input's fault, or I/O.
pub fn mesh_error(e: tessd_mesh::MeshError) -> CodecError {
    match e {
        tessd_mesh::MeshError::Io { path, source } => {
            CodecError::io(format!("reading {path}"), source)
        }
        other => CodecError::Input(other.to_string()),
    }
}

/// Opens a streaming reader for a PLY or OBJ file.
pub fn open(path: &std::path::Path) -> Result<Box<dyn MeshSource>, CodecError> {
    tessd_mesh::io::stream::open(path).map_err(mesh_error)
}
