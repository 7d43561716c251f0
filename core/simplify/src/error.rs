//! The error type of this crate.

use thiserror::Error;

/// Why a simplification failed.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SimplifyError {
    /// The input mesh breaks an invariant.
    #[error("{0}")]
    InvalidMesh(#[from] tessd_mesh::MeshError),
    /// The mesh has no faces.
    #[error("the mesh has no faces to simplify")]
    Empty,
    /// An option is out of range (the message names it and its value).
    #[error("{0}")]
    InvalidOption(String),
    /// Cancelled from outside.
    #[error("cancelled")]
    Cancelled,
}
