//! `mesh.stats`: counts, bounds, face-size histogram and topology of a mesh.

use super::mesh_arrays::input_mesh;
use serde_json::{Map, Value, json};
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_mesh::stats::MeshStats;

/// The operation: reads the input mesh and returns [`stats_json`] of it.
///
/// # Errors
/// As [`input_mesh`], or `cancelled`.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let mesh = input_mesh(&mut request, ctx)?;
    ctx.progress(0.5, "topology", "")?;
    let stats = tessd_mesh::stats::compute(&mesh);
    ctx.progress(1.0, "done", "")?;
    Ok(Response::json(stats_json(&stats)))
}

/// The JSON form of mesh statistics (the `tessd stats --json` output too).
pub fn stats_json(s: &MeshStats) -> Value {
    let histogram: Map<String, Value> = s
        .face_size_histogram
        .iter()
        .map(|(k, v)| (k.to_string(), Value::from(*v)))
        .collect();
    let bounds = match s.bounds {
        Some((lo, hi)) => json!({"min": lo, "max": hi}),
        None => Value::Null,
    };
    json!({
        "vertices": s.vertices,
        "stored_vertices": s.stored_vertices,
        "unreferenced_vertices": s.unreferenced_vertices,
        "faces": s.faces,
        "triangles": s.triangles,
        "edges": s.edges,
        "bounds": bounds,
        "face_sizes": histogram,
        "boundary_edges": s.boundary_edges,
        "boundary_loops": s.boundary_loops,
        "non_manifold_edges": s.non_manifold_edges,
        "components": s.components,
    })
}
