//! Atomic file output.

use std::io::Write;
use std::path::Path;

use crate::UsdError;
use crate::error::STREAM;

/// Writes a `.usda` file atomically: `write` streams the stage into a temporary file in the
/// same folder, which is renamed over `path` only when everything succeeded, so readers never
/// see a partial stage and a failure leaves no file behind (and an existing `path` untouched).
///
/// ```no_run
/// # fn main() -> Result<(), tessd_usd::UsdError> {
/// use tessd_usd::{write_mesh_stage, write_usda_file, MeshPrimOptions, StageOptions};
/// let mesh = tessd_mesh::Mesh::default();
/// let (stage, prim) = (StageOptions::default(), MeshPrimOptions::default());
/// write_usda_file("out.usda".as_ref(), |w| write_mesh_stage(w, &mesh, &stage, &prim))?;
/// # Ok(()) }
/// ```
///
/// # Errors
/// Whatever `write` returns, and [`UsdError::Io`] (naming `path`) when the temporary file cannot
/// be created, written, synced or renamed.
pub fn write_usda_file<F>(path: &Path, write: F) -> Result<(), UsdError>
where
    F: FnOnce(&mut dyn Write) -> Result<(), UsdError>,
{
    write_atomic(path, write)
}

/// The mesh crate's temp-file-and-rename, with stream errors re-labelled with the file's path.
fn write_atomic<F>(path: &Path, write: F) -> Result<(), UsdError>
where
    F: FnOnce(&mut dyn Write) -> Result<(), UsdError>,
{
    tessd_mesh::io::write_atomic(path, |w| {
        write(w).map_err(|e| match e {
            UsdError::Io { path: p, source } if p == STREAM => UsdError::Io {
                path: path.display().to_string(),
                source,
            },
            e => e,
        })
    })
}
