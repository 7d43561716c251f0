//! The boundary corner rule every scheme reads. It lives below the schemes and the adjacency
//! ([`crate::topology`]) so that none of them imports another scheme's file for it.

/// How boundary vertices of one face (valence 2) behave, as OpenSubdiv's
/// `VTX_BOUNDARY_EDGE_ONLY` / `VTX_BOUNDARY_EDGE_AND_CORNER` and Blender's "Smooth, keep
/// corners" option.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Boundary {
    /// Boundary curves are smooth (B-spline) everywhere, corners included.
    #[default]
    EdgeOnly,
    /// Boundary vertices with a single face are corners: they keep their position.
    EdgeAndCorner,
}
