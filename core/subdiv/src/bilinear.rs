//! Placeholder: this scheme is being written.

use crate::catmull_clark::Boundary;
use crate::error::SubdivError;
use crate::level::Level;
use crate::topology::{Faces, Topology};

/// One level of this scheme (not written yet).
///
/// # Errors
/// Always, for now.
pub fn refine(_faces: &Faces, _topo: &Topology, _boundary: Boundary) -> Result<Level, SubdivError> {
    Err(SubdivError::InvalidOption(
        "scheme not implemented yet".to_string(),
    ))
}
