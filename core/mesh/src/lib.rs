//! # tessd-mesh — the polygon mesh every other stage consumes
//!
//! The first stage of the mesh pipeline (`mesh → simplify / subdiv / codec`): an indexed
//! polygon mesh that keeps n-gons (quads matter for subdivision), with optional face-varying
//! normals and UVs, per-edge creases and face groups (a material or a CAD face id).
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

mod error;
pub mod io;
mod mesh;
pub mod stats;

pub use error::MeshError;
pub use mesh::{Crease, FaceVarying, Mesh};
