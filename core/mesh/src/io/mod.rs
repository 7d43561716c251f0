//! Readers and writers. STUB — being implemented (see the brief); signatures are the contract.

use crate::{Mesh, MeshError};
use std::path::Path;

/// Mesh file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// STL.
    Stl,
    /// OFF.
    Off,
}

impl Format {
    /// The format for a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, MeshError> {
        let _ = path;
        todo!()
    }
}

/// Limits for reading untrusted files.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct ReadOptions {
    /// Largest number of vertices, faces or corners accepted.
    pub max_elements: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions { max_elements: 1 << 31 }
    }
}

/// Reads a mesh file, format from the extension.
pub fn read_path(path: &Path, options: &ReadOptions) -> Result<Mesh, MeshError> {
    let _ = (path, options);
    todo!()
}

/// Writes a mesh file atomically, format from the extension.
pub fn write_path(mesh: &Mesh, path: &Path) -> Result<(), MeshError> {
    let _ = (mesh, path);
    todo!()
}
