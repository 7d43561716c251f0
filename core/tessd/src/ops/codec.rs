//! `codec.compress` and `codec.decompress`: the progressive lossless codec of paper 003
//! (`tessd-codec`), on files (`.tsc` out, any mesh format in) or arrays.

use std::io::Write;
use std::time::Instant;

use serde_json::json;
use tessd_codec::{CodecError, Params, Tsc};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_mesh::Mesh;

use super::common::{file_dropped, u64_param, write_mesh_file};
use super::mesh_arrays::{input_mesh, mesh_error, mesh_to_arrays, output_path};

/// A codec error as the protocol names it: bad parameters are the request's fault, a corrupt
/// file the input's, the rest I/O.
fn codec_error(e: CodecError) -> OpError {
    let code = match e {
        CodecError::Parameter { .. } => ErrorCode::InvalidRequest,
        CodecError::Input(_) => ErrorCode::InvalidMesh,
        CodecError::Corrupt { .. } => ErrorCode::InvalidMesh,
        CodecError::Io { .. } => ErrorCode::Io,
    };
    OpError::new(code, e.to_string())
}

/// A `u32` parameter with a default.
fn u32_param(request: &Request, key: &str, default: u32) -> Result<u32, OpError> {
    match u64_param(request, key)? {
        None => Ok(default),
        Some(v) => u32::try_from(v)
            .map_err(|_| OpError::request(format!("parameter `{key}` is too large: {v}"))),
    }
}

/// The fan triangulation of every face (the codec takes triangles).
fn triangles(mesh: &Mesh) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(mesh.triangle_count());
    for f in mesh.faces() {
        for i in 1..f.len() - 1 {
            out.push([f[0], f[i], f[i + 1]]);
        }
    }
    out
}

/// `codec.compress`: params `input` (a mesh file, or `positions` / `face_indices` arrays),
/// `output` (the `.tsc` file, written atomically), `bits` (12), `cell_split` (4), `min_cell`
/// (8000), `root_bits` (7).
///
/// # Errors
/// `invalid_request` for parameters out of range or no output; `invalid_mesh` for a mesh the
/// codec cannot take (NaN, bad index); `io` when writing fails (nothing is left behind).
pub fn compress(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    let started = Instant::now();
    let defaults = Params::default();
    let params = Params {
        bits: u32_param(&request, "bits", defaults.bits)?,
        cell_split: u32_param(&request, "cell_split", defaults.cell_split)?,
        min_cell: u64_param(&request, "min_cell")?.unwrap_or(defaults.min_cell),
        root_bits: u32_param(&request, "root_bits", defaults.root_bits)?,
    };
    params.validate().map_err(codec_error)?;
    let output = output_path(&request)?
        .ok_or_else(|| OpError::request("parameter `output` (the .tsc file) is required"))?;
    ctx.progress(0.0, "read", "")?;
    let mesh = input_mesh(&mut request, ctx)?;
    let read_ms = started.elapsed().as_secs_f64() * 1e3;
    let tris = triangles(&mesh);
    let mut file = std::io::Cursor::new(Vec::new());
    let mut cancelled = false;
    let report = tessd_codec::compress(&mesh.positions, &tris, params, &mut file, &mut |f| {
        cancelled |= ctx.progress(0.05 + 0.9 * f, "code", "").is_err();
    })
    .map_err(codec_error)?;
    if cancelled {
        return Err(OpError::cancelled());
    }
    ctx.progress(0.95, "write", "")?;
    let bytes = file.into_inner();
    tessd_mesh::io::write_atomic(&output, |w: &mut dyn Write| {
        w.write_all(&bytes)
            .map_err(|source| tessd_mesh::MeshError::Io {
                path: output.display().to_string(),
                source,
            })
    })
    .map_err(mesh_error)?;
    ctx.progress(1.0, "done", "")?;
    let families: serde_json::Map<String, serde_json::Value> = tessd_codec::symbols::ALL
        .iter()
        .map(|f| {
            (
                format!("{f:?}"),
                json!(report.family_bits[*f as usize] / report.input_vertices.max(1) as f64),
            )
        })
        .collect();
    Ok(Response {
        result: json!({
            "output": output.display().to_string(),
            "input_vertices": report.input_vertices,
            "input_triangles": report.input_triangles,
            "vertices": report.vertices,
            "triangles": report.triangles,
            "bytes": report.bytes,
            "bits_per_vertex": 8.0 * report.bytes as f64 / report.input_vertices.max(1) as f64,
            "bits_per_vertex_by_family": families,
            "nsp_cells": report.nsp_cells,
            "duplicated_simplices": report.duplicated_simplices,
            "origin": report.grid.origin,
            "step": report.grid.step,
            "bits": params.bits,
            "read_ms": read_ms,
            "steps_ms": {"partition": report.steps_ms[0], "codes": report.steps_ms[1], "final": report.steps_ms[2]},
            "elapsed_ms": started.elapsed().as_secs_f64() * 1e3,
        }),
        files: vec![output],
        ..Response::default()
    })
}

/// `codec.decompress`: params `input` (a `.tsc` file), `output` (a mesh file; without it the
/// mesh comes back as arrays), `max_bits` (decode only that prefix of the refinement).
///
/// # Errors
/// `invalid_mesh` naming the byte offset of a corrupt file; `io` when reading or writing fails.
pub fn decompress(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    let started = Instant::now();
    let input = request
        .str_param("input")?
        .map(|p| request.resolve(p))
        .ok_or_else(|| OpError::request("parameter `input` (the .tsc file) is required"))?;
    let max_bits = u64_param(&request, "max_bits")?.map(|b| b.min(u32::MAX as u64) as u32);
    let output = output_path(&request)?;
    ctx.progress(0.0, "read", "")?;
    let bytes = std::fs::read(&input)
        .map_err(|e| OpError::new(ErrorCode::Io, format!("reading {}: {e}", input.display())))?;
    let tsc = Tsc::open(&bytes).map_err(codec_error)?;
    ctx.progress(0.1, "decode", "")?;
    let decoded = tsc.decode(max_bits).map_err(codec_error)?;
    let mut mesh = Mesh {
        positions: decoded
            .positions
            .iter()
            .map(|p| p.map(|x| x as f32))
            .collect(),
        ..Mesh::default()
    };
    for t in &decoded.triangles {
        mesh.push_face(t);
    }
    let mut result = json!({
        "vertices": mesh.positions.len(),
        "triangles": decoded.triangles.len(),
        "isolated_points": decoded.isolated.len(),
        "bits": decoded.bits,
        "bytes_read": decoded.bytes_read,
        "file_bytes": bytes.len(),
        "nsp_cells": decoded.cells,
    });
    ctx.progress(0.9, "write", "")?;
    let response = match output {
        Some(path) => {
            write_mesh_file(&request, &mesh, &path, "mesh")?;
            result["output"] = json!(path.display().to_string());
            result["dropped_attributes"] = json!(file_dropped(&mesh, &path));
            Response {
                result,
                files: vec![path],
                ..Response::default()
            }
        }
        None => Response {
            result,
            arrays: mesh_to_arrays(mesh),
            files: Vec::new(),
        },
    };
    ctx.progress(1.0, "done", "")?;
    let mut response = response;
    response.result["elapsed_ms"] = json!(started.elapsed().as_secs_f64() * 1e3);
    Ok(response)
}
