//! `codec.compress`, `codec.decompress` and `codec.view`: the progressive lossless codec of
//! paper 003 (`tessd-codec`), on files (`.tsc` out, any mesh format in) or arrays, and its
//! view-dependent decoding for a moving camera.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Instant, SystemTime};

use serde_json::json;
use tessd_codec::{Camera, CodecError, Params, Tsc, ViewSession};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_mesh::Mesh;

use super::common::{check_stage_options, file_dropped, write_mesh_file};
use super::mesh_arrays::{input_mesh, mesh_to_arrays};
use super::params::camera::{parse_size, vec3_param};
use super::params::paths::output_path;
use super::params::scalars::{u32_param, u64_param};

/// A codec error as the protocol names it: bad parameters are the request's fault, a corrupt
/// file the input's, the rest I/O.
fn codec_error(e: CodecError) -> OpError {
    let code = match e {
        CodecError::Parameter { .. } => ErrorCode::InvalidRequest,
        CodecError::Input(_) => ErrorCode::InvalidMesh,
        CodecError::Corrupt { .. } => ErrorCode::InvalidMesh,
        CodecError::Io { .. } => ErrorCode::Io,
        CodecError::Cancelled => return OpError::cancelled(),
    };
    OpError::new(code, e.to_string())
}

/// [`codec_error`], with a failure to write the output (the codec's `context`) naming the
/// output file (`writing out.tsc: No space left on device`).
fn output_error(e: CodecError, context: &str, output: &std::path::Path) -> OpError {
    match e {
        CodecError::Io { context: c, source } if c == context => write_error(output, source),
        e => codec_error(e),
    }
}

/// `codec.compress`: params `input` (a mesh file, or `positions` / `face_indices` arrays),
/// `output` (the `.tsc` file, written atomically), `bits` (12), `cell_split` (4), `min_cell`
/// (50 000, and a split's children must hold an eighth of it on average), `root_bits` (7),
/// `ahead` (0: bits of geometry ahead of the connectivity, §6.4).
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
        ahead: u32_param(&request, "ahead", defaults.ahead)?,
    };
    params.validate().map_err(codec_error)?;
    let output = output_path(&request)?
        .ok_or_else(|| OpError::request("parameter `output` (the .tsc file) is required"))?;
    ctx.progress(0.0, "read", "")?;
    // PLY and OBJ files are streamed in passes (out of core); anything else is read first
    let input = request.str_param("input")?.map(|p| request.resolve(p));
    let streamed = input
        .as_deref()
        .is_some_and(tessd_codec::source::streamable);
    let progress = |f: f64| ctx.progress(0.02 + 0.96 * f, "code", "").is_ok();
    let (file, temp) = temp_output(&output)?;
    let mut file = std::io::BufWriter::with_capacity(1 << 20, file);
    // The codec holds positions and triangles: everything else the input carries is dropped.
    let (report, read_ms, dropped) = if streamed {
        let path = input.expect("streamed inputs are paths");
        let mut src = tessd_codec::source::open(&path).map_err(codec_error)?;
        let dropped = src.carried_names();
        let report = tessd_codec::compress_source(&mut *src, params, &mut file, &progress);
        (report, 0.0, dropped)
    } else {
        let mesh = input_mesh(&mut request, ctx)?;
        let read_ms = started.elapsed().as_secs_f64() * 1e3;
        let tris = mesh.fan_triangles();
        let report = tessd_codec::compress(&mesh.positions, &tris, params, &mut file, &progress);
        (report, read_ms, mesh.carried_names())
    };
    let report = report.map_err(|e| output_error(e, "writing the compressed file", &output))?;
    ctx.progress(0.99, "write", "")?;
    let file = file.into_inner().map_err(|e| {
        OpError::new(
            ErrorCode::Io,
            format!("writing {}: {}", output.display(), e.error()),
        )
    })?;
    persist(temp, file, &output)?;
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
            "dropped_attributes": dropped,
        }),
        files: vec![output],
        ..Response::default()
    })
}

/// Meshes with more vertices and triangles than this are decoded into a PLY file in bounded
/// memory (the in-memory decode holds about 100 bytes per element).
const STREAMED_DECODE_ELEMENTS: u64 = 4_000_000;

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
    // Bad stage options are refused before the work, not when writing.
    check_stage_options(&request)?;
    ctx.progress(0.0, "read", "")?;
    let tsc = Tsc::open_file(&input).map_err(codec_error)?;
    let p = tsc.header.params.bits;
    let is_ply = output
        .as_deref()
        .and_then(|o| o.extension())
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    // the whole of a large file into a PLY: streamed in bounded memory (two decoding passes);
    // a small one is decoded once in memory
    let large = tsc.header.triangles + tsc.header.vertices > STREAMED_DECODE_ELEMENTS;
    if is_ply && large && max_bits.is_none_or(|b| b >= p) {
        let path = output.expect("checked above");
        let (file, temp) = temp_output(&path)?;
        let mut file = std::io::BufWriter::with_capacity(1 << 20, file);
        let progress = |f: f64| ctx.progress(0.02 + 0.96 * f, "decode", "").is_ok();
        let report = tsc
            .write_ply(&mut file, &progress)
            .map_err(|e| output_error(e, "writing the decoded mesh", &path))?;
        let file = file.into_inner().map_err(|e| {
            OpError::new(
                ErrorCode::Io,
                format!("writing {}: {}", path.display(), e.error()),
            )
        })?;
        persist(temp, file, &path)?;
        ctx.progress(1.0, "done", "")?;
        return Ok(Response {
            result: json!({
                "vertices": report.vertices,
                "triangles": report.triangles,
                "bits": p,
                "bytes_read": tsc.bytes_len(),
                "file_bytes": tsc.bytes_len(),
                "nsp_cells": report.cells,
                "output": path.display().to_string(),
                "dropped_attributes": [],
                "elapsed_ms": started.elapsed().as_secs_f64() * 1e3,
            }),
            files: vec![path],
            ..Response::default()
        });
    }
    ctx.progress(0.1, "decode", "")?;
    let decoded = tsc.decode(max_bits).map_err(codec_error)?;
    let mesh = to_mesh(&decoded.positions, &decoded.triangles);
    let result = json!({
        "vertices": mesh.positions.len(),
        "triangles": decoded.triangles.len(),
        "isolated_points": decoded.isolated.len(),
        "bits": decoded.bits,
        "bytes_read": decoded.bytes_read,
        "file_bytes": tsc.bytes_len(),
        "nsp_cells": decoded.cells,
    });
    ctx.progress(0.9, "write", "")?;
    let mut response = mesh_response(&request, mesh, output, result)?;
    ctx.progress(1.0, "done", "")?;
    response.result["elapsed_ms"] = json!(started.elapsed().as_secs_f64() * 1e3);
    Ok(response)
}

/// A decoded mesh for the host: f32 positions, one face per triangle (`tessd view`'s `.tsc`
/// worker shows its views through it too).
pub fn to_mesh(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Mesh {
    let mut mesh = Mesh {
        positions: positions.iter().map(|p| p.map(|x| x as f32)).collect(),
        ..Mesh::default()
    };
    for t in triangles {
        mesh.push_face(t);
    }
    mesh
}

/// The response holding a decoded mesh: written to `output` (atomically), or as arrays.
fn mesh_response(
    request: &Request,
    mesh: Mesh,
    output: Option<PathBuf>,
    mut result: serde_json::Value,
) -> Result<Response, OpError> {
    Ok(match output {
        Some(path) => {
            write_mesh_file(request, &mesh, &path, "mesh")?;
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
    })
}

/// Which file a kept session decodes: its path, size and modification time (a rewritten file
/// starts a new session).
type SessionKey = (PathBuf, u64, Option<SystemTime>);

/// View sessions kept between `codec.view` requests, most recent last.
static SESSIONS: Mutex<Vec<(SessionKey, Arc<Mutex<ViewSession>>)>> = Mutex::new(Vec::new());

/// How many files keep their decoder states between views.
const KEPT_SESSIONS: usize = 4;

/// The kept session of `path`, or a new one (the oldest is dropped past [`KEPT_SESSIONS`]).
fn session(path: &std::path::Path) -> Result<Arc<Mutex<ViewSession>>, OpError> {
    let io =
        |e: std::io::Error| OpError::new(ErrorCode::Io, format!("reading {}: {e}", path.display()));
    let meta = std::fs::metadata(path).map_err(io)?;
    let key: SessionKey = (path.to_path_buf(), meta.len(), meta.modified().ok());
    let mut sessions = SESSIONS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(k) = sessions.iter().position(|(k, _)| *k == key) {
        let entry = sessions.remove(k);
        let s = entry.1.clone();
        sessions.push(entry);
        return Ok(s);
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let tsc = Tsc::from_shared(Arc::from(bytes)).map_err(codec_error)?;
    let s = Arc::new(Mutex::new(ViewSession::new(Arc::new(tsc))));
    sessions.retain(|(k, _)| k.0 != key.0);
    sessions.push((key, s.clone()));
    if sessions.len() > KEPT_SESSIONS {
        sessions.remove(0);
    }
    Ok(s)
}

/// `codec.view`: params `input` (a `.tsc` file), `eye`, `target`, `up` ([x, y, z]), `fov`
/// (vertical, degrees, default 30), `size` ("WxH" or [w, h]), `pixel_error` (default 1),
/// `output` (a mesh file; without it the mesh comes back as arrays). The decoder states of the
/// file are kept between requests, so a moving camera refines from the previous view
/// (paper 003 §6.2).
///
/// # Errors
/// `invalid_request` for a bad camera; `invalid_mesh` naming the byte offset of a corrupt file;
/// `io` when reading or writing fails.
pub fn view(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    let started = Instant::now();
    let input = request
        .str_param("input")?
        .map(|p| request.resolve(p))
        .ok_or_else(|| OpError::request("parameter `input` (the .tsc file) is required"))?;
    let need = |key: &str| {
        vec3_param(&request, key)?
            .ok_or_else(|| OpError::request(format!("parameter `{key}` ([x, y, z]) is required")))
    };
    let (width, height) = parse_size(request.params.get("size"))?;
    check_stage_options(&request)?;
    let camera = Camera {
        eye: need("eye")?,
        target: need("target")?,
        up: need("up")?,
        fov: request.f64_param("fov")?.unwrap_or(30.0),
        width,
        height,
    };
    let pixel_error = request.f64_param("pixel_error")?.unwrap_or(1.0);
    let output = output_path(&request)?;
    ctx.progress(0.0, "open", "")?;
    let session = session(&input)?;
    let mut session = session.lock().unwrap_or_else(|e| e.into_inner());
    ctx.progress(0.1, "refine", "")?;
    let view = session.view(&camera, pixel_error).map_err(codec_error)?;
    let decode_ms = started.elapsed().as_secs_f64() * 1e3;
    let file_bytes = session.file().bytes_len();
    drop(session);
    let mesh = to_mesh(&view.positions, &view.triangles);
    let result = json!({
        "vertices": view.positions.len(),
        "triangles": view.triangles.len(),
        "cells": view.cells.len(),
        "cell_bits": view.cells.iter().map(|&(_, b)| b).collect::<Vec<_>>(),
        "bytes_read": view.bytes_read,
        "file_bytes": file_bytes,
        "symbols": view.symbols,
        "decode_ms": decode_ms,
    });
    ctx.progress(0.9, "write", "")?;
    let mut response = mesh_response(&request, mesh, output, result)?;
    ctx.progress(1.0, "done", "")?;
    response.result["elapsed_ms"] = json!(started.elapsed().as_secs_f64() * 1e3);
    Ok(response)
}

/// A temporary file beside `dest` ([`tessd_mesh::io::TempOutput`]: never through a symbolic
/// link, renamed over `dest` once complete, removed when dropped unused), so that a failure or
/// a kill never leaves half a file where the user's file was.
fn temp_output(
    dest: &std::path::Path,
) -> Result<(std::fs::File, tessd_mesh::io::TempOutput), OpError> {
    if dest.file_name().is_none() {
        return Err(OpError::request(format!(
            "`output` {} is not a file path",
            dest.display()
        )));
    }
    tessd_mesh::io::TempOutput::create(dest).map_err(|e| write_error(dest, e))
}

/// Flushes `file` to disk and renames it over `dest`.
fn persist(
    temp: tessd_mesh::io::TempOutput,
    file: std::fs::File,
    dest: &std::path::Path,
) -> Result<(), OpError> {
    temp.commit(file, true).map_err(|e| write_error(dest, e))
}

/// An `io` error naming the destination (its temporary file is an implementation detail).
fn write_error(dest: &std::path::Path, e: std::io::Error) -> OpError {
    OpError::new(ErrorCode::Io, format!("writing {}: {e}", dest.display()))
}
