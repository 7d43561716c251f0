//! tessd's mesh codec: lossless, progressive and out-of-core, after Jamin, Gandoin & Akkouche,
//! *Compression out-of-core pour la visualisation interactive de maillages volumineux*
//! (REFIG 2009, paper 003), itself built on Gandoin & Devillers' kd-tree coder (GD02).
//!
//! The pipeline follows the paper's sections, one step per module:
//!
//! | step | module | paper |
//! |---|---|---|
//! | quantisation to `p` bits in the cubic box | [`quantize`] | §5.1 |
//! | streaming mesh readers (PLY, OBJ) | [`source`] | §5.1 |
//! | nSP-tree: cells, precisions, duplication | [`nsp_tree`] | §5.1 |
//! | out-of-core partition: RWP points, tree by passes, RWI | [`partition`] | §5.1, §5.2a |
//! | the complex on the kd-tree's leaves | [`complex`] | §3, §5.2a |
//! | a cell's complex: a leaf's, children's union | `cell_complex` | §5.2a, §5.2d |
//! | kd cells: keys, halves, sides | [`kd_cell`] | §3 |
//! | kd split / merge codes, interleaved | [`kd_coder`] | §3, §5.2b |
//! | a split's context (neighbours' centroid) | `split_context` | §3, §5.3 |
//! | connectivity codes of a split and their contexts | `connectivity` | §3, §5.3 |
//! | values ↔ halves and preimage masks | `coding` | §3 |
//! | symbols and their contexts | [`symbols`] | §5.3 |
//! | adaptive binary models, fresh per cell | `adaptive` | §5.3 |
//! | the binary range coder | `binary_coder` | §5.3 |
//! | symbols as binary decisions, one pass per cell | [`entropy`] | §5.2c, §5.3 |
//! | file layout, index at the end | [`format`](mod@format) | §5.1, §5.3 |
//! | compression pipeline, multi-core | [`encode`] | §5.2, §5.4 |
//! | decoding | [`decode`] | §6.1 |
//! | full decoding to PLY in bounded memory | [`ply_out`] | §5, §6.1 |
//! | view-dependent refinement, borders between precisions | [`view`] | §6.2, §6.3 |
//! | geometry ahead of connectivity (`--ahead`) | [`ahead`] | §6.4 |

mod adaptive;
pub mod ahead;
mod binary_coder;
mod cell_complex;
mod coding;
pub mod complex;
mod connectivity;
#[cfg(test)]
mod connectivity_study;
pub mod decode;
pub mod encode;
pub mod entropy;
pub mod error;
pub mod format;
pub mod kd_cell;
pub mod kd_coder;
pub mod nsp_tree;
pub mod partition;
pub mod ply_out;
mod positional_io;
pub mod quantize;
pub mod source;
mod split_context;
mod star_cache;
pub mod symbols;
mod varint;
pub mod view;

pub use decode::{Decoded, Tsc};
pub use encode::{CompressReport, compress, compress_source};
pub use error::CodecError;
pub use nsp_tree::Params;
pub use quantize::Quantizer;
pub use view::{Camera, ViewMesh, ViewSession};
