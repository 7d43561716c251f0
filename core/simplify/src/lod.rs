//! LOD chains: several goals on one mesh in one call. The preparation (triangulation,
//! weights, bounds, feature classes) is done once and shared by all levels; each level is then
//! simplified from the original, so a level's error bound holds against the input, not
//! against the level before it.

use crate::options::{Method, ProgressFn, SimplifyOptions};
use crate::{Prepared, Simplified, SimplifyError, needs_triangles};
use tessd_mesh::Mesh;

/// Simplifies `mesh` once per goal in `levels` (in the given order), with the other settings
/// of `options`. `progress` sees the whole chain as 0..1.
///
/// # Errors
/// As [`crate::simplify`], for the first level that fails.
pub fn lod_chain(
    mesh: &Mesh,
    levels: &[Method],
    options: &SimplifyOptions,
    progress: &mut ProgressFn,
) -> Result<Vec<Simplified>, SimplifyError> {
    let force_triangles = levels.iter().any(|&m| needs_triangles(m));
    let prepared = Prepared::new(mesh, options, force_triangles)?;
    let n = levels.len().max(1) as f64;
    levels
        .iter()
        .enumerate()
        .map(|(i, &method)| {
            let mut level = options.clone();
            level.method = method;
            let mut scaled = |f: f64, stage: &str| progress((i as f64 + f) / n, stage);
            prepared.run(&level, &mut scaled)
        })
        .collect()
}
