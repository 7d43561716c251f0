//! `simplify`: vertex clustering (`tessd-simplify`) with a regular grid, a quality goal or a
//! complexity goal; the result as a file or arrays, and optionally the partition's cells.
//!
//! The parameters are described in docs/protocol.md ("simplify"); this module also parses
//! the settings the `lod` operation shares.

use super::common::{check_mesh_output, check_stage_options, file_dropped, stem, write_mesh_file};
use super::library_errors::{mesh_error, simplify_error};
use super::mesh_arrays::{input_mesh, mesh_to_arrays};
use super::params::clustering::{MethodKind, base_options};
use super::params::lengths::lengths_in_model_units;
use super::params::paths::output_path;
use super::params::scalars::bool_param;
use serde_json::{Value, json};
use std::path::Path;
use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_simplify::{Cell, GridSize, Length, Method, Report, SimplifyError};

/// Why a complexity goal was missed by more than 1 %, or `None` when it was met (or the
/// method had no vertex target).
pub fn target_note(r: &Report) -> Option<String> {
    let target = r.target_vertices?;
    let got = r.output_vertices;
    if got.abs_diff(target) as f64 <= 0.01 * target as f64 {
        return None;
    }
    Some(if target < 3 {
        format!(
            "the output has {got} vertices, not the {target} asked for: a face needs 3 distinct \
             vertices, so an output of fewer than 3 vertices would have no faces at all"
        )
    } else {
        format!(
            "the output has {got} vertices, not the {target} asked for: the partition could get \
             no closer (a face survives only with 3 distinct clusters, so the vertices that \
             remain move in steps as cells split)"
        )
    })
}

/// The report's figures as JSON, with [`target_note`] and [`Report::twist_note`] as `note`
/// (joined by "; "; `null` when there is none) and `dropped_attributes`: simplification
/// carries everything a mesh holds (normals, UVs, creases, face groups, sharp edges, generic
/// attributes), so the list starts empty; a file output adds what its format cannot hold.
pub fn report_json(r: &Report) -> Value {
    let notes: Vec<String> = target_note(r).into_iter().chain(r.twist_note()).collect();
    json!({
        "dropped_attributes": [],
        "note": (!notes.is_empty()).then(|| notes.join("; ")),
        "polygon_twist": r.polygon_twist,
        "twisted_polygons": r.polygon_twist.map(|_| r.twisted_polygons),
        "input_vertices": r.input_vertices,
        "input_faces": r.input_faces,
        "output_vertices": r.output_vertices,
        "output_faces": r.output_faces,
        "clusters": r.clusters,
        "degenerate_faces": r.degenerate_faces,
        "duplicate_faces": r.duplicate_faces,
        "max_displacement": r.max_displacement,
        "surface_error": r.surface_error,
        "refinement_rounds": r.refinement_rounds,
        "uncovered_faces": r.uncovered_faces,
        "tolerance": r.tolerance,
        "target_vertices": r.target_vertices,
    })
}

/// Parameters that only one method takes.
const METHOD_PARAMS: [(&str, MethodKind); 4] = [
    ("cells", MethodKind::Grid),
    ("cell_size", MethodKind::Grid),
    ("max_error", MethodKind::Quality),
    ("target_vertices", MethodKind::Complexity),
];

/// The method and its goal from `method` and its parameter; also the name of that parameter.
fn parse_method(request: &Request) -> Result<(MethodKind, Method, &'static str), OpError> {
    let kind = match request.str_param("method")? {
        Some(m) => MethodKind::parse(m)?,
        None => {
            return Err(OpError::request(
                "`method` is required: \"grid\", \"quality\" or \"complexity\"",
            ));
        }
    };
    for (key, owner) in METHOD_PARAMS {
        if owner != kind && request.params.get(key).is_some_and(|v| !v.is_null()) {
            return Err(OpError::request(format!(
                "`{key}` applies to method \"{}\", not \"{}\"",
                owner.name(),
                kind.name()
            )));
        }
    }
    let get = |k: &str| request.params.get(k).filter(|v| !v.is_null());
    let (method, what) = match kind {
        MethodKind::Grid => match (get("cells"), get("cell_size")) {
            (Some(v), None) => (kind.goal("cells", v)?, "cells"),
            (None, Some(v)) => match v.as_f64() {
                Some(s) if s.is_finite() && s > 0.0 => {
                    (Method::Grid(GridSize::CellSize(s)), "cell_size")
                }
                _ => {
                    return Err(OpError::request(format!(
                        "`cell_size` must be a positive number, got {v}"
                    )));
                }
            },
            (Some(_), Some(_)) => {
                return Err(OpError::request(
                    "give either `cells` or `cell_size` for method \"grid\", not both",
                ));
            }
            (None, None) => {
                return Err(OpError::request(
                    "method \"grid\" needs `cells` (cells per axis) or `cell_size`",
                ));
            }
        },
        MethodKind::Quality => match get("max_error") {
            Some(v) => (kind.goal("max_error", v)?, "max_error"),
            None => {
                return Err(OpError::request(
                    "method \"quality\" needs `max_error` (a distance, or a percentage of the \
                     largest side of the bounding box such as \"1%\")",
                ));
            }
        },
        MethodKind::Complexity => match get("target_vertices") {
            Some(v) => (kind.goal("target_vertices", v)?, "target_vertices"),
            None => {
                return Err(OpError::request(
                    "method \"complexity\" needs `target_vertices` (a count, or a percentage \
                     of the input's vertices such as \"20%\")",
                ));
            }
        },
    };
    Ok((kind, method, what))
}

/// The cells as `cells_min` and `cells_max` arrays (f32, [C, 3]).
pub fn cell_arrays(cells: &[Cell]) -> Vec<OwnedArray> {
    vec![
        OwnedArray::rows("cells_min", cells.iter().map(|c| c.min).collect()),
        OwnedArray::rows("cells_max", cells.iter().map(|c| c.max).collect()),
    ]
}

/// Writes the cells to `path`: an OBJ of wire boxes (12 `l` lines per cell) for `.obj`, else
/// a mesh of closed boxes in the format of the extension (a USD stage for `.usda`).
fn write_partition(request: &Request, cells: &[Cell], path: &Path) -> Result<(), OpError> {
    let obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if obj {
        tessd_mesh::io::write_atomic(path, |w| {
            tessd_simplify::partition_boxes::write_wire_obj(cells, w).map_err(|source| {
                tessd_mesh::MeshError::Io {
                    path: path.display().to_string(),
                    source,
                }
            })
        })
        .map_err(mesh_error)
    } else {
        let boxes = tessd_simplify::partition_boxes::boxes_mesh(cells);
        write_mesh_file(request, &boxes, path, "partition")
    }
}

/// Removes files an operation wrote before a later step failed, so that a failed request
/// leaves nothing behind.
pub fn remove_all(files: &[std::path::PathBuf]) {
    for f in files {
        let _ = std::fs::remove_file(f);
    }
}

/// The operation.
///
/// # Errors
/// `invalid_request` for missing or invalid settings (naming the parameter and value),
/// `invalid_mesh` for a mesh that breaks an invariant or has no faces, `unsupported` for an
/// output format tessd cannot write, `io`, `cancelled`.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    lengths_in_model_units(&mut request, &["max_error", "cell_size"])?;
    let (kind, method, what) = parse_method(&request)?;
    let partition_path = request
        .str_param("partition_output")?
        .map(|p| request.resolve(p));
    let want_cells = bool_param(&request, "partition")?.unwrap_or(false);
    let options =
        base_options(&request, method, ctx)?.with_partition(want_cells || partition_path.is_some());
    let output = output_path(&request)?;
    // Refuse unknown formats before reading a large input.
    for path in output.iter().chain(&partition_path) {
        check_mesh_output(path)?;
    }
    let name = match request.str_param("name")? {
        Some(n) => n.to_string(),
        None => stem(output.as_deref(), "mesh"),
    };
    check_stage_options(&request)?;
    let mesh = input_mesh(&mut request, ctx)?;
    ctx.progress(0.05, "simplify", "")?;
    let mut progress = |f: f64, stage: &str| ctx.progress(0.05 + 0.85 * f, stage, "").is_ok();
    let simplified =
        tessd_simplify::simplify(&mesh, &options, &mut progress).map_err(|e| {
            match (e, method) {
                (SimplifyError::InvalidOption(_), Method::Quality(Length::Relative(f))) => {
                    OpError::request(format!(
                        "`max_error` of {}% is relative to the largest side of the bounding box, \
                     which is 0 for this mesh (its vertices coincide); give an absolute distance",
                        f * 100.0
                    ))
                }
                (e, _) => simplify_error(e, what),
            }
        })?;
    drop(mesh);
    ctx.progress(0.9, "write", "")?;

    let mut result = report_json(&simplified.report);
    result["method"] = json!(kind.name());
    let mut files = Vec::new();
    let mut arrays = Vec::new();
    if options.keep_partition {
        result["cells"] = json!(simplified.cells.len());
    }
    if let Some(path) = &partition_path {
        write_partition(&request, &simplified.cells, path)?;
        result["partition_output"] = json!(path.display().to_string());
        files.push(path.clone());
    }
    match output {
        Some(path) => {
            if let Err(e) = write_mesh_file(&request, &simplified.mesh, &path, &name) {
                remove_all(&files);
                return Err(e);
            }
            result["output"] = json!(path.display().to_string());
            result["dropped_attributes"] = json!(file_dropped(&simplified.mesh, &path));
            files.push(path);
        }
        None => arrays = mesh_to_arrays(simplified.mesh),
    }
    if want_cells {
        arrays.extend(cell_arrays(&simplified.cells));
    }
    // The files are written: a cancel arriving now is too late to undo them.
    let _ = ctx.progress(1.0, "done", "");
    Ok(Response {
        result,
        arrays,
        files,
    })
}
