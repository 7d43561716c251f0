//! `mesh.convert`: re-encodes a mesh into another format (OBJ, PLY, STL, OFF, or a USD
//! stage for `.usda`), or returns it as arrays.

use super::mesh_arrays::{input_mesh, mesh_error, mesh_to_arrays, output_path};
use serde_json::json;
use std::path::Path;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

/// The operation: writes `params.output` (format from its extension, atomically) or, without
/// it, returns the mesh as arrays.
///
/// # Errors
/// As the input deserves; `unsupported` for an unknown output extension; `io` when writing
/// fails (no partial file remains).
pub fn run(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let output = output_path(&request)?;
    if let Some(path) = output.as_deref().filter(|p| !is_usda(p)) {
        // Refuse an unknown format before reading a large input.
        tessd_mesh::io::Format::from_path(path).map_err(mesh_error)?;
    }
    let mesh = input_mesh(&request, ctx)?;
    ctx.progress(0.5, "write", "")?;
    let counts = json!({"vertices": mesh.vertex_count(), "faces": mesh.face_count()});
    match output {
        Some(path) => {
            if is_usda(&path) {
                write_usda(&request, &mesh, &path)?;
            } else {
                tessd_mesh::io::write_path(&mesh, &path).map_err(mesh_error)?;
            }
            ctx.progress(1.0, "done", "")?;
            let mut result = counts;
            result["output"] = json!(path.display().to_string());
            Ok(Response {
                result,
                files: vec![path],
                ..Response::default()
            })
        }
        None => Ok(Response {
            result: counts,
            arrays: mesh_to_arrays(mesh),
            files: Vec::new(),
        }),
    }
}

fn is_usda(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("usda"))
}

/// Writes the mesh as a USD stage; `params.up_axis` (`"Y"`/`"Z"`, default Z) and
/// `params.meters_per_unit` (default 1) describe the host's conventions, `params.name` names
/// the prim (default: the file stem).
fn write_usda(request: &Request, mesh: &tessd_mesh::Mesh, path: &Path) -> Result<(), OpError> {
    use tessd_usd::{MeshPrimOptions, StageOptions, UpAxis};
    let up = match request.str_param("up_axis")? {
        None | Some("Z") | Some("z") => UpAxis::Z,
        Some("Y") | Some("y") => UpAxis::Y,
        Some(other) => {
            return Err(OpError::request(format!(
                "`up_axis` must be \"Y\" or \"Z\", got {other:?}"
            )));
        }
    };
    let mut stage = StageOptions::default().with_up_axis(up);
    if let Some(m) = request.f64_param("meters_per_unit")? {
        stage = stage.with_meters_per_unit(m);
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = request.str_param("name")?.map_or(stem, str::to_string);
    let prim = MeshPrimOptions::default().with_name(name);
    tessd_usd::write_usda_file(path, |w| {
        tessd_usd::write_mesh_stage(w, mesh, &stage, &prim)
    })
    .map_err(usd_error)
}

/// Maps a USD-writer error onto the protocol's codes.
pub fn usd_error(e: tessd_usd::UsdError) -> OpError {
    let code = match e.code() {
        "invalid_mesh" => ErrorCode::InvalidMesh,
        "too_large" => ErrorCode::TooLarge,
        "io" => ErrorCode::Io,
        _ => ErrorCode::InvalidRequest,
    };
    OpError::new(code, e.to_string())
}
