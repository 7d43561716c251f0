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

use super::brep_load::{brep_error, request_brep};
use super::common::{check_mesh_output, is_usda, plain_number, stage_options_in, stem};
use super::library_errors::{mesh_error, usd_error};
use super::mesh_arrays::{mesh_to_arrays, output_path};
use serde_json::{Value, json};
use std::path::Path;
use tessd_brep::{Document, Units};
use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_tessellate::origin::SPACING_FRACTION;
use tessd_tessellate::{Options, Origin, TessellateError, Tessellation};
use tessd_usd::{MeshPrim, MeshPrimOptions, StageOptions};

/// Parses a length: a positive number (document units) or a string holding one, optionally
/// with a unit suffix (`"0.1mm"`, `"0.01 in"`, `"2cm"`, `"0.001m"`) converted into `units`.
///
/// # Errors
/// `invalid_request` naming `what` for anything else.
pub fn parse_length(what: &str, v: &Value, units: Units) -> Result<f64, OpError> {
    let bad = || {
        OpError::request(format!(
            "`{what}` must be a positive length: a number in the document's units ({}) or a string such as \"0.1mm\" (mm, cm, m, in), got {v}",
            units.name()
        ))
    };
    let x = match v {
        Value::Number(n) => n.as_f64().ok_or_else(bad)?,
        Value::String(s) => {
            let s = s.trim();
            let split = s
                .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
                .unwrap_or(s.len());
            let (digits, unit) = (s[..split].trim(), s[split..].trim());
            let x = plain_number(digits).ok_or_else(bad)?;
            let metres = match unit {
                "" => units.meters_per_unit(),
                name => Units::from_name(name).ok_or_else(bad)?.meters_per_unit(),
            };
            x * metres / units.meters_per_unit()
        }
        _ => return Err(bad()),
    };
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(bad())
    }
}

/// A chordal tolerance as a request gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// A length in the document's units.
    Length(f64),
    /// A percentage of the part's bounding-box diagonal (`"0.05%"` is `Percent(0.05)`).
    Percent(f64),
}

/// Parses `tolerance`: a length as [`parse_length`] reads it, or a string holding a positive
/// percentage (`"0.05%"`, `" 0.05 % "`) of the part's bounding-box diagonal.
///
/// # Errors
/// `invalid_request` naming `tolerance` and the value for anything else (zero, negative, NaN or
/// infinite percentages included).
pub fn parse_tolerance(v: &Value, units: Units) -> Result<Tolerance, OpError> {
    if let Some(digits) = v.as_str().and_then(|s| s.trim().strip_suffix('%')) {
        return match plain_number(digits.trim_end()) {
            Some(p) if p.is_finite() && p > 0.0 => Ok(Tolerance::Percent(p)),
            _ => Err(OpError::request(format!(
                "`tolerance` must be a positive percentage of the part's bounding-box diagonal, such as \"0.05%\", got {v}"
            ))),
        };
    }
    parse_length("tolerance", v, units)
        .map(Tolerance::Length)
        .map_err(|_| {
            OpError::request(format!(
                "`tolerance` must be a positive length (a number in the document's units, {}, or a string such as \"0.1mm\": mm, cm, m, in) or a percentage of the part's bounding-box diagonal such as \"0.05%\", got {v}",
                units.name()
            ))
        })
}

/// The absolute tolerance `asked` means for `doc`, with, for a percentage, the bounding-box
/// diagonal it was taken of.
///
/// # Errors
/// `invalid_request` naming `tolerance` and the value when a percentage has no geometry to be
/// taken of (no faces, or a box of zero size); `invalid_brep` when that is because the
/// document does not validate.
pub fn absolute_tolerance(asked: Tolerance, doc: &Document) -> Result<(f64, Option<f64>), OpError> {
    let p = match asked {
        Tolerance::Length(x) => return Ok((x, None)),
        Tolerance::Percent(p) => p,
    };
    let diagonal = doc.bounding_box().map_or(0.0, |b| b.diagonal());
    let tolerance = p / 100.0 * diagonal;
    if tolerance.is_finite() && tolerance > 0.0 {
        return Ok((tolerance, Some(diagonal)));
    }
    if let Some(e) = doc.errors().into_iter().next() {
        return Err(brep_error(e));
    }
    if diagonal.is_finite() && diagonal > 0.0 {
        return Err(OpError::request(format!(
            "`tolerance` \"{p}%\" of the part's {diagonal} {} diagonal is not a finite length",
            doc.units.name()
        )));
    }
    Err(OpError::request(format!(
        "`tolerance` \"{p}%\" is a percentage of the part's bounding-box diagonal, but the document ({} faces) has no extent to take it of (diagonal {diagonal} {})",
        doc.faces.len(),
        doc.units.name()
    )))
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use tessd_ipc::error::ErrorCode;

    #[test]
    fn lengths() {
        let mm = Units::Millimetres;
        let ok = |v: Value, u: Units| parse_length("tolerance", &v, u).unwrap();
        assert_eq!(ok(json!(0.1), mm), 0.1);
        assert_eq!(ok(json!("0.1"), mm), 0.1);
        assert!((ok(json!("0.1mm"), mm) - 0.1).abs() < 1e-12);
        assert!((ok(json!("1 cm"), mm) - 10.0).abs() < 1e-12);
        assert!((ok(json!("0.1mm"), Units::Metres) - 1e-4).abs() < 1e-15);
        assert!((ok(json!("1in"), mm) - 25.4).abs() < 1e-12);
        assert!((ok(json!("1e-1mm"), mm) - 0.1).abs() < 1e-12);
        for bad in [
            json!("0.1ft"),
            json!("-1mm"),
            json!(0),
            json!("mm"),
            json!(true),
        ] {
            let e = parse_length("tolerance", &bad, mm).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest, "{bad}");
        }
        // `trim.classify` shares parse_length: a percentage is not a length there.
        assert!(parse_length("tolerance", &json!("0.05%"), mm).is_err());
    }

    #[test]
    fn tolerances() {
        let mm = Units::Millimetres;
        let ok = |v: Value| parse_tolerance(&v, mm).unwrap();
        assert_eq!(ok(json!("0.05%")), Tolerance::Percent(0.05));
        assert_eq!(ok(json!(" 0.05 % ")), Tolerance::Percent(0.05));
        assert_eq!(ok(json!("5e-2%")), Tolerance::Percent(0.05));
        assert_eq!(ok(json!("2%")), Tolerance::Percent(2.0));
        assert_eq!(ok(json!(0.1)), Tolerance::Length(0.1));
        assert_eq!(ok(json!("0.1")), Tolerance::Length(0.1));
        match ok(json!("0.1mm")) {
            Tolerance::Length(x) => assert!((x - 0.1).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
        match parse_tolerance(&json!("1cm"), Units::Metres).unwrap() {
            Tolerance::Length(x) => assert!((x - 0.01).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        for (bad, shown) in [
            (json!("0%"), r#""0%""#),
            (json!("-0.05%"), r#""-0.05%""#),
            (json!("NaN%"), r#""NaN%""#),
            (json!("inf%"), r#""inf%""#),
            (json!("1e400%"), r#""1e400%""#),
            (json!("%"), r#""%""#),
            (json!("0.05%%"), r#""0.05%%""#),
            (json!("abc%"), r#""abc%""#),
            (json!("0.05 %mm"), r#""0.05 %mm""#),
            (json!("0.1ft"), r#""0.1ft""#),
            (json!(-1), "-1"),
            (json!(0), "0"),
            (json!(true), "true"),
        ] {
            let e = parse_tolerance(&bad, mm).unwrap_err();
            assert_eq!(e.code, ErrorCode::InvalidRequest, "{bad}");
            assert!(e.message.starts_with("`tolerance` "), "{}", e.message);
            assert!(
                e.message.ends_with(&format!("got {shown}")),
                "{}",
                e.message
            );
        }
        assert_eq!(
            parse_tolerance(&json!("0%"), mm).unwrap_err().message,
            r#"`tolerance` must be a positive percentage of the part's bounding-box diagonal, such as "0.05%", got "0%""#
        );
    }

    fn plate(scale: f64) -> Document {
        // A 40 × 30 plane face at z = 10 (times `scale`): a 50 diagonal.
        Document::from_value(&json!({
            "format": "tessd-brep", "version": 1, "units": "mm",
            "faces": [{"id": 0, "surface": {"type": "plane", "origin": [0, 0, 10.0 * scale],
                       "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]},
                       "bounds": [0, 40.0 * scale, 0, 30.0 * scale]}]
        }))
        .unwrap()
    }

    #[test]
    fn percent_of_the_diagonal() {
        let (t, d) = absolute_tolerance(Tolerance::Percent(0.05), &plate(1.0)).unwrap();
        assert!((d.unwrap() - 50.0).abs() < 1e-12 && (t - 0.025).abs() < 1e-12);
        let (t, d) = absolute_tolerance(Tolerance::Percent(0.05), &plate(1e-3)).unwrap();
        assert!((d.unwrap() - 0.05).abs() < 1e-15 && (t - 2.5e-5).abs() < 1e-15);
        assert_eq!(
            absolute_tolerance(Tolerance::Length(0.1), &plate(1e-3)).unwrap(),
            (0.1, None)
        );
        let mut empty = plate(1.0);
        empty.faces.clear();
        let e = absolute_tolerance(Tolerance::Percent(0.05), &empty).unwrap_err();
        assert_eq!(e.code, ErrorCode::InvalidRequest);
        assert!(
            e.message
                .starts_with(r#"`tolerance` "0.05%" is a percentage"#)
                && e.message.contains("0 faces"),
            "{}",
            e.message
        );
        // A face of zero size does not validate: that error, not the missing extent.
        let e = absolute_tolerance(Tolerance::Percent(1.0), &plate(0.0)).unwrap_err();
        assert_eq!(e.code, ErrorCode::InvalidBrep, "{}", e.message);
    }
}
