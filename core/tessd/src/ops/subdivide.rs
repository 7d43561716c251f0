//! `subdivide`: uniform refinement (`tessd-subdiv`): the topology phase builds stencil tables
//! once, the apply phase evaluates them on the cage; the refined mesh as a file or arrays.
//!
//! Parameters are described in docs/protocol.md ("subdivide").

use super::common::{as_u64, bool_param, check_mesh_output, stem, write_mesh_file};
use super::mesh_arrays::{input_mesh, mesh_to_arrays, output_path};
use serde_json::json;
use std::time::Instant;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_subdiv::{Boundary, Refiner, Scheme, SubdivError, SubdivOptions, UvInterpolation};

/// The largest `levels` accepted (the memory estimate refuses most meshes well before).
pub const MAX_LEVELS: u64 = 10;

/// Maps a refinement error to its protocol code.
pub fn subdiv_error(e: SubdivError) -> OpError {
    let code = match e {
        SubdivError::TooLarge { .. } => ErrorCode::TooLarge,
        SubdivError::InvalidOption(_) => ErrorCode::InvalidRequest,
        _ => ErrorCode::InvalidMesh,
    };
    OpError::new(code, e.to_string())
}

/// Reads `scheme`, `levels`, `boundary`, `uv_interpolation` and `normals`.
///
/// # Errors
/// `invalid_request` naming the parameter.
pub fn parse_options(request: &Request) -> Result<SubdivOptions, OpError> {
    let name = request.str_param("scheme")?.unwrap_or("catmull-clark");
    let scheme = Scheme::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Scheme::ALL.iter().map(|s| s.name()).collect();
        OpError::request(format!(
            "`scheme` must be one of {}, got {name:?}",
            names.join(", ")
        ))
    })?;
    let levels = match request.params.get("levels") {
        None => 1,
        Some(v) => as_u64(v)
            .filter(|n| (1..=MAX_LEVELS).contains(n))
            .ok_or_else(|| {
                OpError::request(format!(
                    "`levels` must be an integer from 1 to {MAX_LEVELS}, got {v}"
                ))
            })?,
    };
    let boundary = match request.str_param("boundary")?.unwrap_or("edge-only") {
        "edge-only" => Boundary::EdgeOnly,
        "edge-and-corner" => Boundary::EdgeAndCorner,
        other => {
            return Err(OpError::request(format!(
                "`boundary` must be \"edge-only\" or \"edge-and-corner\", got {other:?}"
            )));
        }
    };
    let uv_interpolation = match request.str_param("uv_interpolation")? {
        None => UvInterpolation::default(),
        Some(name) => UvInterpolation::from_name(name).ok_or_else(|| {
            let names: Vec<&str> = UvInterpolation::ALL.iter().map(|u| u.name()).collect();
            OpError::request(format!(
                "`uv_interpolation` must be one of {}, got {name:?}",
                names.join(", ")
            ))
        })?,
    };
    Ok(SubdivOptions {
        scheme,
        levels: levels as u32,
        boundary,
        uv_interpolation,
        normals: bool_param(request, "normals")?.unwrap_or(true),
        ..SubdivOptions::default()
    })
}

/// The operation.
///
/// # Errors
/// Bad options (`invalid_request`), bad cages (`invalid_mesh`, naming the element), outputs
/// estimated too large (`too_large`, before allocating), `io` when writing fails.
pub fn run(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let options = parse_options(&request)?;
    let gpu = bool_param(&request, "gpu")?.unwrap_or(false);
    let output = output_path(&request)?;
    if let Some(path) = output.as_deref() {
        check_mesh_output(path)?;
    }
    let cage = input_mesh(&request, ctx)?;
    ctx.progress(0.2, "topology", "")?;
    let t = Instant::now();
    let refiner = Refiner::new(&cage, &options).map_err(subdiv_error)?;
    let topology_ms = t.elapsed().as_secs_f64() * 1e3;
    ctx.progress(0.6, "apply", "")?;
    let t = Instant::now();
    let (positions, device) = if gpu {
        let (p, device) = gpu_apply(&refiner, &cage.positions)?;
        (p, Some(device))
    } else {
        let p = refiner
            .apply_positions(&cage.positions, "the cage")
            .map_err(subdiv_error)?;
        (p, None)
    };
    let apply_ms = t.elapsed().as_secs_f64() * 1e3;
    let mesh = refiner
        .mesh_with(&cage, positions, &options)
        .map_err(subdiv_error)?;
    let mut result = json!({
        "scheme": options.scheme.name(),
        "levels": options.levels,
        "uv_interpolation": mesh.uvs.as_ref().map(|_| options.uv_interpolation.name()),
        "cage_vertices": cage.vertex_count(),
        "cage_faces": cage.face_count(),
        "vertices": mesh.vertex_count(),
        "faces": mesh.face_count(),
        "topology_ms": topology_ms,
        "apply_ms": apply_ms,
        "gpu": device,
    });
    match output {
        Some(path) => {
            ctx.progress(0.8, "write", "")?;
            let name = match request.str_param("name")? {
                Some(n) => n.to_string(),
                None => stem(Some(&path), "mesh"),
            };
            write_mesh_file(&request, &mesh, &path, &name)?;
            ctx.progress(1.0, "done", "")?;
            result["output"] = json!(path.display().to_string());
            Ok(Response {
                result,
                files: vec![path],
                ..Response::default()
            })
        }
        None => Ok(Response {
            result,
            arrays: mesh_to_arrays(mesh),
            files: Vec::new(),
        }),
    }
}

/// The apply phase on the GPU (wgpu compute, `shaders/stencil_apply.wgsl`): uploads the tables,
/// evaluates every level on the device, reads the last back. Returns the positions and the
/// adapter's description.
fn gpu_apply(
    refiner: &Refiner,
    positions: &[[f32; 3]],
) -> Result<(Vec<[f32; 3]>, String), OpError> {
    let gpu_error =
        |e: tessd_gpu::GpuError| OpError::new(ErrorCode::Unsupported, format!("GPU apply: {e}"));
    let gpu = tessd_gpu::GpuStencils::new().map_err(gpu_error)?;
    let tables = gpu.upload(&refiner.tables).map_err(gpu_error)?;
    let flat = gpu
        .apply(&tables, positions.as_flattened(), 3)
        .map_err(gpu_error)?;
    let out = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    Ok((out, gpu.adapter_info()))
}
