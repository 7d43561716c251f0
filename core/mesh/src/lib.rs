//! # tessd-mesh — the polygon mesh every other stage consumes
//!
//! The first stage of the mesh pipeline (`mesh → simplify / subdiv / codec`): an indexed
//! polygon mesh that keeps n-gons (quads matter for subdivision), with optional face-varying
//! normals and UVs, per-edge creases, face groups (a material or a CAD face id), sharp edges
//! and generic float [`attribute`]s on points, corners or faces.
//!
//! [`io`] reads and writes OBJ, PLY, STL and OFF (streaming, bounded allocation, errors that
//! name the line or element; writes are atomic), and [`stats`] computes counts and topology
//! (edges, boundaries, non-manifold edges, components) in linear time.
//!
//! ```
//! use tessd_mesh::Mesh;
//! let mut m = Mesh::default();
//! m.positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
//! m.push_face(&[0, 1, 2, 3]);
//! m.validate().unwrap();
//! assert_eq!(m.triangle_count(), 2);
//! ```
#![warn(missing_docs)]

pub mod allocation;
pub mod attribute;
mod block_scan;
mod error;
pub mod io;
mod mesh;
pub mod process;
pub mod stats;

pub use attribute::{Attribute, Domain};
pub use error::MeshError;
pub use mesh::{Crease, FaceVarying, Mesh};
