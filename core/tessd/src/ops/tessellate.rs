//! `tessellate`: trimmed tessellation of a B-Rep document (`tessd-tessellate`): the document
//! from a file or inline (arrays by reference resolved as for `brep.load`), validated, each
//! face tessellated to `tolerance` (world units, a length with a unit suffix, or a percentage
//! of the part's bounding-box diagonal) and `angle`, shared edges discretised once; the mesh (a face group per B-Rep face, `face<id>`) as a file
//! (`.usda` with a GeomSubset per face, `.obj`, `.ply`, ...) or arrays.
//!
//! Positions far from the origin: f32 arrays are relative to an `origin` (chosen only when f32
//! would not hold the tolerance there), or f64 on request; a `.usda` carries the origin as the
//! mesh prim's `xformOp:translate`; OBJ, PLY and OFF, which cannot carry one, get absolute f64
//! coordinates; binary STL (f32 only) gets absolute f32 ones and a warning.
//!
//! Parameters are described in docs/protocol.md ("tessellate").

use super::common::{check_mesh_output, is_usda, stage_options_in, stem};
use super::library_errors::{brep_error, mesh_error, usd_error};
use super::mesh_arrays::mesh_to_arrays;
use super::params::brep_input::request_brep;
use super::params::lengths::parse_tolerance;
use super::params::paths::output_path;
// Re-exported where they lived: the fuzz target `brep` takes them from here.
pub use super::params::lengths::{Tolerance, absolute_tolerance};
use serde_json::{Value, json};
use std::path::Path;

use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_tessellate::origin::SPACING_FRACTION;
use tessd_tessellate::{Options, Origin, TessellateError, Tessellation};
use tessd_usd::{MeshPrim, MeshPrimOptions, StageOptions};

/// Parses `origin`: `"auto"` (the default, also for null), `"none"`, or `[x, y, z]` (finite
/// numbers, document units).
///
/// # Errors
/// `invalid_request` naming `origin` and the value for anything else.
pub fn parse_origin(v: Option<&Value>) -> Result<Origin, OpError> {
    let bad = |v: &Value| {
        OpError::request(format!(
            "`origin` must be \"auto\", \"none\" or [x, y, z] (finite numbers in the document's units), got {v}"
        ))
    };
    match v {
        None | Some(Value::Null) => Ok(Origin::Auto),
        Some(Value::String(s)) if s == "auto" => Ok(Origin::Auto),
        Some(Value::String(s)) if s == "none" => Ok(Origin::None),
        Some(v @ Value::Array(items)) if items.len() == 3 => {
            let mut o = [0.0; 3];
            for (k, item) in items.iter().enumerate() {
                o[k] = item
                    .as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(v))?;
            }
            Ok(Origin::At(o))
        }
        Some(v) => Err(bad(v)),
    }
}

/// Whether the arrays' `positions` are f64 (`positions: "f64"`) rather than f32 (`"f32"`, the
/// default).
///
/// # Errors
/// `invalid_request` for another value.
pub fn parse_positions(v: Option<&Value>) -> Result<bool, OpError> {
    match v {
        None | Some(Value::Null) => Ok(false),
        Some(Value::String(s)) if s == "f32" => Ok(false),
        Some(Value::String(s)) if s == "f64" => Ok(true),
        Some(v) => Err(OpError::request(format!(
            "`positions` must be \"f32\" (relative to `origin`) or \"f64\", got {v}"
        ))),
    }
}

/// Writes the tessellation to `path`: a `.usda` (stage options `stage`) with the f32 points
/// relative to the origin and the origin as the prim's `xformOp:translate`; OBJ, PLY, OFF with
/// absolute f64 coordinates
/// when the points are shifted (as before, f32, when not); STL with absolute f32 ones. Returns
/// the warnings that go with the file.
fn write_output(
    stage: &StageOptions,
    t: &Tessellation,
    path: &Path,
    name: &str,
    tolerance: f64,
    units: &str,
) -> Result<Vec<String>, OpError> {
    let placement = &t.placement;
    if is_usda(path) {
        let mut prim =
            MeshPrim::new(&t.mesh).with_options(MeshPrimOptions::default().with_name(name));
        if placement.shifted() {
            prim = prim.with_translate(placement.origin);
        }
        tessd_usd::write_usda_file(path, |w| tessd_usd::write_stage(w, stage, &[prim]))
            .map_err(usd_error)?;
        return Ok(t.warnings.clone());
    }
    if !placement.shifted() {
        tessd_mesh::io::write_path(&t.mesh, path).map_err(mesh_error)?;
        return Ok(t.warnings.clone());
    }
    tessd_mesh::io::write_path_f64(&t.mesh, &t.points, path).map_err(mesh_error)?;
    let stl = matches!(
        tessd_mesh::io::Format::from_path(path),
        Ok(tessd_mesh::io::Format::Stl)
    );
    if stl && placement.spacing >= SPACING_FRACTION * tolerance {
        return Ok(vec![format!(
            "binary STL holds f32 positions only and no origin: they are written absolute, up to \
             {:.3e} {units} from the world origin, where the f32 spacing, {:.3e} {units}, is {:.1} % \
             of the tolerance; write .usda, .obj, .ply or .off for exact positions",
            placement.largest,
            placement.spacing,
            100.0 * placement.spacing / tolerance
        )]);
    }
    Ok(Vec::new())
}

/// The operation.
///
/// # Errors
/// `invalid_request` for missing, conflicting or bad parameters; `io` when the file cannot be
/// read or the output written; `invalid_brep` for a document the validator refuses;
/// `unsupported` for an output format tessd cannot write; `cancelled`.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let output = output_path(&request)?;
    if let Some(path) = output.as_deref() {
        check_mesh_output(path)?;
    }
    let doc = request_brep(&mut request)?;
    let asked = match request.params.get("tolerance") {
        None | Some(Value::Null) => {
            return Err(OpError::request(
                "`tolerance` (the chordal tolerance, a length or a percentage of the part's bounding-box diagonal) is required",
            ));
        }
        Some(v) => parse_tolerance(v, doc.units)?,
    };
    let angle = match request.f64_param("angle")? {
        None => Options::DEFAULT_ANGLE,
        Some(a) if a.is_finite() && a > 0.0 && a < std::f64::consts::PI => a,
        Some(a) => {
            return Err(OpError::request(format!(
                "`angle` must be a number of radians between 0 and π, got {a}"
            )));
        }
    };
    let origin = parse_origin(request.params.get("origin"))?;
    let f64_positions = parse_positions(request.params.get("positions"))?;
    if f64_positions && output.is_some() {
        return Err(OpError::request(
            "`positions: \"f64\"` applies to the mesh returned as arrays; with `output` the file's format decides (a .usda gets the origin as its xformOp:translate, OBJ / PLY / OFF absolute f64 coordinates)",
        ));
    }
    // f64 positions need no shift: "auto" is then the world origin.
    let origin = match (f64_positions, origin) {
        (true, Origin::Auto) => Origin::None,
        (_, o) => o,
    };
    let (tolerance, diagonal) = absolute_tolerance(asked, &doc)?;
    // A stage's metres per unit follow the document's units (mm: 0.001) unless the request
    // names its own.
    let stage = stage_options_in(&request, doc.units.meters_per_unit())?;
    ctx.progress(0.05, "validate", "")?;
    let total = doc.faces.len();
    // A cancelled job's progress call fails: the remaining faces are skipped.
    let progress = |done: usize, total: usize| {
        ctx.progress(
            0.05 + 0.85 * done as f64 / total.max(1) as f64,
            "faces",
            &format!("face {done} of {total}"),
        )
        .is_ok()
    };
    let options = Options {
        tolerance,
        angle,
        origin,
    };
    let t =
        tessd_tessellate::tessellate_with_progress(&doc, &options, &progress).map_err(
            |e| match e {
                TessellateError::Invalid(e) => brep_error(e),
                TessellateError::Options(m) => OpError::request(m),
                e @ TessellateError::Face(..) => {
                    OpError::new(ErrorCode::InvalidBrep, e.to_string())
                }
                TessellateError::Cancelled => match ctx.checkpoint() {
                    Err(e) => e,
                    Ok(()) => OpError::new(ErrorCode::Cancelled, "cancelled"),
                },
            },
        )?;
    ctx.checkpoint()?;
    let stats = &t.stats;
    let mut result = json!({
        "units": doc.units.name(),
        "tolerance": tolerance,
        "angle": angle,
        "faces": total,
        "edges": stats.edges,
        "triangles": stats.triangles,
        "vertices": stats.vertices,
        "refined_points": stats.refined_points,
        "merged_by_file_tolerance": stats.merged_by_file_tolerance,
        "largest_file_tolerance_merge": stats.largest_file_tolerance_merge,
        "origin": t.placement.origin,
        "positions": if f64_positions { "f64" } else { "f32" },
        "empty_faces": stats.empty_faces,
        "time_ms": stats.time_ms,
        "groups": t.mesh.group_names,
    });
    if let (Tolerance::Percent(p), Some(d)) = (asked, diagonal) {
        result["tolerance_relative"] = json!(p / 100.0);
        result["diagonal"] = json!(d);
    }
    match output {
        Some(path) => {
            ctx.progress(0.9, "write", "")?;
            let name = match request.str_param("name")? {
                Some(n) => n.to_string(),
                None => stem(Some(&path), "part"),
            };
            let units = doc.units.name();
            let warnings = write_output(&stage, &t, &path, &name, tolerance, units)?;
            ctx.progress(1.0, "done", "")?;
            result["output"] = json!(path.display().to_string());
            // The B-Rep faces are face groups: PLY, STL and OFF cannot hold them.
            result["dropped_attributes"] = json!(super::common::file_dropped(&t.mesh, &path));
            if is_usda(&path) {
                result["meters_per_unit"] = json!(stage.meters_per_unit);
                result["up_axis"] = json!(stage.up_axis.token());
            }
            if !is_usda(&path) && t.placement.shifted() {
                // OBJ, PLY, OFF and STL hold absolute coordinates.
                result["origin"] = json!([0.0, 0.0, 0.0]);
            }
            result["warnings"] = json!(warnings);
            Ok(Response {
                result,
                files: vec![path],
                ..Response::default()
            })
        }
        None => {
            ctx.progress(1.0, "done", "")?;
            let arrays = if f64_positions {
                // The f32 warnings do not concern f64 positions.
                result["warnings"] = json!([]);
                let o = t.placement.origin;
                let rows: Vec<[f64; 3]> = t
                    .points
                    .iter()
                    .map(|p| [p[0] - o[0], p[1] - o[1], p[2] - o[2]])
                    .collect();
                let mut arrays = mesh_to_arrays(t.mesh);
                arrays[0] = OwnedArray::rows("positions", rows);
                arrays
            } else {
                result["warnings"] = json!(t.warnings);
                mesh_to_arrays(t.mesh)
            };
            Ok(Response {
                result,
                arrays,
                files: Vec::new(),
            })
        }
    }
}
