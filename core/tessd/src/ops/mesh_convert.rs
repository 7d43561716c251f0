//! `mesh.convert`: re-encodes a mesh into another format (OBJ, PLY, STL, OFF, or a USD
//! stage for `.usda`), or returns it as arrays; `dropped_attributes` names what the output
//! format could not hold.

use super::common::{check_mesh_output, check_stage_options, file_dropped, stem, write_mesh_file};
use super::mesh_arrays::{input_mesh, mesh_to_arrays};
use super::params::paths::output_path;
use serde_json::json;
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

/// The operation: writes `params.output` (format from its extension, atomically) or, without
/// it, returns the mesh as arrays.
///
/// # Errors
/// As the input deserves; `unsupported` for an unknown output extension; `io` when writing
/// fails (no partial file remains).
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let output = output_path(&request)?;
    if let Some(path) = output.as_deref() {
        // Refuse an unknown format before reading a large input.
        check_mesh_output(path)?;
        // Bad stage options are refused before the work, not when writing.
        check_stage_options(&request)?;
    }
    let mesh = input_mesh(&mut request, ctx)?;
    ctx.progress(0.5, "write", "")?;
    let counts = json!({"vertices": mesh.vertex_count(), "faces": mesh.face_count()});
    match output {
        Some(path) => {
            // A USD stage gets `params.up_axis`, `params.meters_per_unit` and the prim name
            // `params.name` (default: the file stem).
            let name = match request.str_param("name")? {
                Some(n) => n.to_string(),
                None => stem(Some(&path), "mesh"),
            };
            write_mesh_file(&request, &mesh, &path, &name)?;
            ctx.progress(1.0, "done", "")?;
            let mut result = counts;
            result["output"] = json!(path.display().to_string());
            result["dropped_attributes"] = json!(file_dropped(&mesh, &path));
            // What the file holds when a reader counts it: STL's triangles, PLY's vertices
            // split at UV / normal seams.
            if let Ok(format) = tessd_mesh::io::Format::from_path(&path) {
                let w = tessd_mesh::io::written_counts(&mesh, format);
                result["written"] = json!({
                    "vertices": w.vertices,
                    "faces": w.faces,
                    "triangulated": w.triangulated,
                    "split_vertices": w.split_vertices,
                });
            }
            Ok(Response {
                result,
                files: vec![path],
                ..Response::default()
            })
        }
        None => Ok(Response {
            // Arrays carry everything the mesh holds.
            result: {
                let mut r = counts;
                r["dropped_attributes"] = json!([]);
                r
            },
            arrays: mesh_to_arrays(mesh),
            files: Vec::new(),
        }),
    }
}
