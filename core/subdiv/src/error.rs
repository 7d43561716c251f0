//! Why a cage cannot be refined.

use thiserror::Error;

/// A refinement error; each names the offending element.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SubdivError {
    /// An edge shared by more than two faces.
    #[error(
        "edge ({a}, {b}) is shared by {faces} faces; subdivision needs a manifold mesh (at most 2 faces per edge)"
    )]
    NonManifoldEdge {
        /// First vertex.
        a: u32,
        /// Second vertex.
        b: u32,
        /// Faces using it.
        faces: usize,
    },
    /// A face that uses one vertex twice, or has fewer than 3 corners.
    #[error("face {face} is degenerate: {why}")]
    DegenerateFace {
        /// The face.
        face: usize,
        /// What is wrong with it.
        why: String,
    },
    /// The scheme needs triangles (Loop, Butterfly, √3).
    #[error("the {scheme} scheme needs a triangle mesh; face {face} has {corners} corners")]
    NotTriangles {
        /// Scheme name.
        scheme: &'static str,
        /// First offending face.
        face: usize,
        /// Its corner count.
        corners: usize,
    },
    /// The refined mesh would not fit the memory limit; estimated before allocating.
    #[error(
        "{levels} levels would make about {faces} faces and need about {bytes} bytes, above the limit of {limit} bytes"
    )]
    TooLarge {
        /// Levels asked for.
        levels: u32,
        /// Estimated faces at the last level.
        faces: u64,
        /// Estimated bytes of tables and output.
        bytes: u64,
        /// The limit.
        limit: u64,
    },
    /// An option out of range.
    #[error("{0}")]
    InvalidOption(String),
    /// Vertex data that does not fit the cage (an animation frame with another vertex count).
    #[error("{what} has {got} vertices; the cage has {expected}")]
    VertexCount {
        /// Which data.
        what: String,
        /// Its vertex count.
        got: usize,
        /// The cage's.
        expected: usize,
    },
    /// A mesh that breaks the mesh model's invariants (index out of range, NaN...).
    #[error("{0}")]
    InvalidMesh(String),
    /// A vertex no face uses (subdivision has no rule for it).
    #[error(
        "vertex {vertex} is isolated (no face uses it); remove loose vertices before subdividing"
    )]
    IsolatedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A crease names an edge the mesh does not have.
    #[error("crease {index} is on ({a}, {b}), which is not an edge of the mesh")]
    CreaseNotAnEdge {
        /// Index in the crease list.
        index: usize,
        /// First vertex.
        a: u32,
        /// Second vertex.
        b: u32,
    },
}
