//! Topology statistics. STUB — being implemented (see the brief).

use crate::Mesh;

/// Counts and topology figures of a mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshStats {
    /// Referenced vertices.
    pub vertices: u64,
}

/// Computes the statistics of a valid mesh.
pub fn compute(mesh: &Mesh) -> MeshStats {
    let _ = mesh;
    todo!()
}
