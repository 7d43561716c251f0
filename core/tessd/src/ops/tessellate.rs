//! `tessellate`: trimmed tessellation of a B-Rep document (`tessd-tessellate`): the document
//! from a file or inline (arrays by reference resolved as for `brep.load`), validated, each
//! face tessellated to `tolerance` (world units, or a length with a unit suffix) and `angle`,
//! shared edges discretised once; the mesh (a face group per B-Rep face, `face<id>`) as a file
//! (`.usda` with a GeomSubset per face, `.obj`, `.ply`, ...) or arrays.
//!
//! Parameters are described in docs/protocol.md ("tessellate").

use super::brep_load::{brep_error, request_document};
use super::common::{check_mesh_output, plain_number, stem, write_mesh_file};
use super::mesh_arrays::{mesh_to_arrays, output_path};
use serde_json::{Value, json};
use tessd_brep::{Document, Units};
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_tessellate::{Options, TessellateError};

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
                "mm" => Units::Millimetres.meters_per_unit(),
                "cm" => Units::Centimetres.meters_per_unit(),
                "m" => Units::Metres.meters_per_unit(),
                "in" => Units::Inches.meters_per_unit(),
                _ => return Err(bad()),
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
    let value = request_document(&mut request)?;
    let doc = Document::from_value(&value).map_err(brep_error)?;
    drop(value);
    let tolerance = match request.params.get("tolerance") {
        None | Some(Value::Null) => {
            return Err(OpError::request(
                "`tolerance` (the chordal tolerance, a length) is required",
            ));
        }
        Some(v) => parse_length("tolerance", v, doc.units)?,
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
    ctx.progress(0.05, "validate", "")?;
    let total = doc.faces.len();
    let progress = |done: usize, total: usize| {
        let _ = ctx.progress(
            0.05 + 0.85 * done as f64 / total.max(1) as f64,
            "faces",
            &format!("face {done} of {total}"),
        );
    };
    let t =
        tessd_tessellate::tessellate_with_progress(&doc, &Options { tolerance, angle }, &progress)
            .map_err(|e| match e {
                TessellateError::Invalid(e) => brep_error(e),
                TessellateError::Options(m) => OpError::request(m),
            })?;
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
        "empty_faces": stats.empty_faces,
        "time_ms": stats.time_ms,
        "groups": t.mesh.group_names,
    });
    match output {
        Some(path) => {
            ctx.progress(0.9, "write", "")?;
            let name = match request.str_param("name")? {
                Some(n) => n.to_string(),
                None => stem(Some(&path), "part"),
            };
            write_mesh_file(&request, &t.mesh, &path, &name)?;
            ctx.progress(1.0, "done", "")?;
            result["output"] = json!(path.display().to_string());
            Ok(Response {
                result,
                files: vec![path],
                ..Response::default()
            })
        }
        None => {
            ctx.progress(1.0, "done", "")?;
            Ok(Response {
                result,
                arrays: mesh_to_arrays(t.mesh),
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
    }
}
