//! `trim.classify`: builds paper 000's trim structure (`tessd-trim`) for faces of a B-Rep
//! document at a world tolerance ε and classifies (u, v) points on or off each face with the
//! CPU classifier, the reference for the GPU one. Hosts use it to test points against trims;
//! the OCP cross-check (tests/brep/test_classify.py) uses it as our side of the comparison.
//! With it come the structure's figures (tables 1, 3 and 4 of the paper) per face, and
//! warnings: a face whose trims could not be fitted within ε_uv (section 3.1) is built and
//! classified all the same, its fit error reported in a sentence per face and in the
//! result's `warnings` (issue 20: tolerances are estimates, reported, never refused).
//!
//! Parameters are described in docs/protocol.md ("trim.classify").

use super::library_errors::brep_error;
use super::params::brep_input::{array_as_f64, request_brep};
use super::params::lengths::parse_length;
use serde_json::{Value, json};
use std::time::Instant;
use tessd_brep::Document;
use tessd_ipc::arrays::{DType, OwnedArray};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};
use tessd_trim::TrimStructure;

/// The operation.
///
/// # Errors
/// `invalid_request` for missing or bad parameters (unknown face ids, a `uv` array of the
/// wrong shape or dtype, a bad footprint); `invalid_brep` for a document the validator
/// refuses or a non-finite point (naming face and point); `io`; `cancelled`.
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let doc = request_brep(&mut request)?;
    if let Some(e) = doc.errors().into_iter().next() {
        return Err(brep_error(e));
    }
    let eps = match request.params.get("tolerance") {
        None | Some(Value::Null) => {
            return Err(OpError::request(
                "`tolerance` (the world tolerance ε of the trim approximation, a length) is required",
            ));
        }
        Some(v) => parse_length("tolerance", v, doc.units)?,
    };
    let faces = face_indices(&request, &doc)?;
    let footprint = footprint(&request)?;
    let (uv, points) = read_points(&request, faces.len())?;

    let mut on = vec![0u8; faces.len() * points];
    let mut reports = Vec::with_capacity(faces.len());
    let mut warnings: Vec<String> = Vec::new();
    let mut classify_s = 0.0;
    for (k, &fi) in faces.iter().enumerate() {
        ctx.progress(
            0.05 + 0.95 * k as f64 / faces.len().max(1) as f64,
            "faces",
            &format!("face {} of {}", k + 1, faces.len()),
        )?;
        let face = &doc.faces[fi];
        let trim = TrimStructure::build(face, eps)
            .map_err(|e| OpError::new(ErrorCode::InvalidBrep, e.to_string()))?;
        let pts = &uv[k * points..(k + 1) * points];
        if let Some(i) = pts
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(OpError::new(
                ErrorCode::InvalidBrep,
                format!(
                    "`uv`: point {i} of face {} is not finite: {:?}",
                    face.id, pts[i]
                ),
            ));
        }
        let start = Instant::now();
        for (o, p) in on[k * points..(k + 1) * points].iter_mut().zip(pts) {
            *o = u8::from(trim.classify_at(p[0], p[1], footprint).on);
        }
        classify_s += start.elapsed().as_secs_f64();
        let s = &trim.stats;
        let face_warnings = trim.warnings();
        warnings.extend(face_warnings.iter().cloned());
        reports.push(json!({
            "id": face.id,
            "eps_uv": trim.tolerance.eps_uv,
            "eps_uv_samples": trim.tolerance.samples,
            "quadratics": s.quadratics,
            "lines": s.lines,
            "nodes": s.nodes,
            "separating_lines": s.separating_lines,
            "max_depth": s.max_depth,
            "failures": s.failures,
            "k_i": s.k_i,
            "bytes": s.bytes,
            "max_fit_error_uv": s.max_fit_error_uv,
            "build_ms": s.build_time.as_secs_f64() * 1e3,
            "warnings": face_warnings,
        }));
    }
    ctx.progress(1.0, "done", "")?;
    let total = faces.len() * points;
    let result = json!({
        "tolerance": eps,
        "units": doc.units.name(),
        "points": total,
        "on": on.iter().filter(|&&x| x == 1).count(),
        "classify_ms": classify_s * 1e3,
        "points_per_second": if classify_s > 0.0 { total as f64 / classify_s } else { 0.0 },
        "faces": reports,
        "warnings": warnings,
    });
    Ok(Response {
        result,
        arrays: vec![OwnedArray::new(
            "on",
            vec![faces.len() as u64, points as u64],
            on,
        )],
        files: Vec::new(),
    })
}

/// Indices into `doc.faces` of the faces named by `faces` (a list of ids), else all faces.
fn face_indices(request: &Request, doc: &Document) -> Result<Vec<usize>, OpError> {
    let Some(v) = request.params.get("faces").filter(|v| !v.is_null()) else {
        return Ok((0..doc.faces.len()).collect());
    };
    let bad = || OpError::request(format!("`faces` must be a list of face ids, got {v}"));
    let ids = v.as_array().ok_or_else(bad)?;
    ids.iter()
        .map(|id| {
            let id = id.as_u64().ok_or_else(bad)?;
            doc.faces.iter().position(|f| f.id == id).ok_or_else(|| {
                OpError::request(format!("`faces`: the document has no face with id {id}"))
            })
        })
        .collect()
}

/// The optional `footprint` [du, dv] (parameter units, ≥ 0) of the multiresolution stop.
fn footprint(request: &Request) -> Result<[f64; 2], OpError> {
    let Some(v) = request.params.get("footprint").filter(|v| !v.is_null()) else {
        return Ok([0.0, 0.0]);
    };
    let f: Option<Vec<f64>> = v
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect());
    match f.as_deref() {
        Some(&[du, dv]) if du >= 0.0 && dv >= 0.0 && du.is_finite() && dv.is_finite() => {
            Ok([du, dv])
        }
        _ => Err(OpError::request(format!(
            "`footprint` must be [du, dv], two finite numbers ≥ 0, got {v}"
        ))),
    }
}

/// The array `uv`: f64 or f32, shape [faces, points, 2] (or [points, 2] for one face), as
/// rows and the points per face.
fn read_points(request: &Request, faces: usize) -> Result<(Vec<[f64; 2]>, usize), OpError> {
    let desc = request.arrays.desc("uv").ok_or_else(|| {
        OpError::request("array `uv` (the points, [faces, points, 2]) is required")
    })?;
    if !matches!(desc.dtype, DType::F64 | DType::F32) {
        return Err(OpError::request(format!(
            "array `uv` must be f64 or f32, got {}",
            desc.dtype.name()
        )));
    }
    let (data, shape) = array_as_f64("uv", &request.arrays)?;
    let points = match shape.as_slice() {
        [f, n, 2] if *f as usize == faces => *n as usize,
        [n, 2] if faces == 1 => *n as usize,
        _ => {
            return Err(OpError::request(format!(
                "array `uv` must have shape [{faces}, points, 2] (one row of points per face asked), got {shape:?}"
            )));
        }
    };
    let rows = data.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    Ok((rows, points))
}
