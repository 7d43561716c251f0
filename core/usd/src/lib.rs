//! # tessd-usd — USD ASCII (`.usda`) output and input for tessd meshes
//!
//! The export stage of the pipeline: it turns [`tessd_mesh::Mesh`]es into a USD stage that
//! Blender, usdview, Omniverse and any other USD consumer open as is. It is a pure writer (no
//! USD library needed): the text is streamed in chunks, so a 10 M-triangle mesh never becomes
//! one giant string, and files are written atomically with [`write_usda_file`].
//!
//! It also reads `.usda` stages back as meshes ([`reader`]: [`read_usda`], [`parse_usda`]):
//! every `Mesh` prim with its transforms applied, the variant sets (a LOD chain's levels as
//! [`UsdStage::variant_panels`]) and what a viewer shows by default ([`UsdStage::composed`]).
//! References and payloads to local `.usda` files are followed. Binary crate files (`.usdc`)
//! and `.usdz` packages are refused with a clear error.
//!
//! Each stage has one root `Xform` (kind `component`, the layer's `defaultPrim`) with:
//!
//! - one `Mesh` prim ([`write_mesh_stage`]), or several with their transforms
//!   ([`write_stage`], e.g. several Blender objects), or
//! - a variant set `LOD` with one variant per level of detail ([`write_lod_variants`]), or
//! - the levels of detail as the ordered children of a prim with the native `UsdLod` schema's
//!   `LODRootAPI` (usd-core 26.8+), with a `LODScreenSizeHeuristic` beside it and only the
//!   default level visible ([`write_lod_schema`]).
//!
//! A `Mesh` prim gets `points`, `faceVertexCounts`, `faceVertexIndices`, its `extent`,
//! `orientation = "rightHanded"`, `subdivisionScheme` (`"none"` unless the mesh is a
//! subdivision cage), normals and UVs as indexed face-varying primvars (`primvars:normals`,
//! `primvars:st`), creases (`creaseIndices` / `creaseLengths` / `creaseSharpnesses`, one edge
//! per crease, the crease value written as the USD/OpenSubdiv sharpness unchanged) and its
//! face groups as `GeomSubset`s of the `materialBind` family (a `partition` of the faces), and
//! its generic attributes as primvars (`vertex`, `faceVarying` or `uniform` interpolation by
//! domain; see `primvars.rs`). Sharp edges have no USD form ([`dropped_by_usd`]).
//! Prim names are sanitized into valid USD identifiers ([`sanitize_identifier`]) and made
//! unique among siblings.
//!
//! Floats are written in their shortest round-trip form; meshes are validated
//! ([`tessd_mesh::Mesh::validate`]) before anything is written, so NaN or infinity never reach
//! the file.
//!
//! ```
//! use tessd_mesh::Mesh;
//! use tessd_usd::{write_mesh_stage, MeshPrimOptions, StageOptions, UpAxis};
//!
//! let mut quad = Mesh::default();
//! quad.positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
//! quad.push_face(&[0, 1, 2, 3]);
//!
//! let stage = StageOptions::default().with_up_axis(UpAxis::Z).with_meters_per_unit(0.001);
//! let prim = MeshPrimOptions::default().with_name("Plate");
//! let mut text = Vec::new();
//! write_mesh_stage(&mut text, &quad, &stage, &prim).unwrap();
//! let text = String::from_utf8(text).unwrap();
//! assert!(text.starts_with("#usda 1.0\n"));
//! assert!(text.contains("def Mesh \"Plate\""));
//! assert!(text.contains("point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]"));
//! ```
#![warn(missing_docs)]

mod compose;
mod error;
mod file;
mod names;
mod options;
mod primvars;
pub mod reader;
mod usda_mesh;
mod usda_out;
mod usda_parse;
mod usda_spec;
mod usda_tokens;
mod writer;
mod xform_ops;

pub use error::UsdError;
pub use file::write_usda_file;
pub use names::sanitize_identifier;
pub use options::{
    LodSchemaOptions, MeshPrim, MeshPrimOptions, StageOptions, SubdivisionScheme, UpAxis,
};
pub use primvars::dropped_by_usd;
pub use reader::{UsdLodRoot, UsdMesh, UsdStage, UsdVariantSet, parse_usda, read_usda};
pub use writer::{write_lod_schema, write_lod_variants, write_mesh_stage, write_stage};

#[cfg(test)]
mod tests;
