//! Subdivision surfaces (paper 002: Catmull–Clark on the CPU by the factored scheme, section
//! 5.4; the GPU part, section 6), split as OpenSubdiv splits it: a **topology phase** that
//! builds each level's faces and a [`StencilTable`] once per cage topology, and an **apply
//! phase** that evaluates the tables on vertex data (positions, primvars, animation frames).

#![warn(missing_docs)]

pub mod stencil;

pub use stencil::StencilTable;
