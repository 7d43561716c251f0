//! `compare`: Metro-style surface distance between two meshes (`tessd-compare`): both
//! one-sided distances, the symmetric Hausdorff distance and RMS, and the same relative to
//! the diagonal of the meshes' common bounding box.
//!
//! The parameters are described in docs/protocol.md ("compare").

use super::common::read_mesh_param;
use super::params::scalars::{bool_param, u64_param};
use serde_json::{Value, json};
use tessd_compare::{CompareError, CompareOptions, Comparison, Distance};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

fn compare_error(e: CompareError) -> OpError {
    let code = match e {
        CompareError::InvalidOptions(_) => ErrorCode::InvalidRequest,
        CompareError::EmptyMesh { .. }
        | CompareError::DegenerateMesh { .. }
        | CompareError::InvalidMesh { .. } => ErrorCode::InvalidMesh,
        CompareError::Cancelled => return OpError::cancelled(),
        _ => ErrorCode::Internal,
    };
    OpError::new(code, e.to_string())
}

fn distance_json(d: &Distance, diagonal: f64) -> Value {
    json!({
        "max": d.max,
        "mean": d.mean,
        "rms": d.rms,
        "max_relative": relative(d.max, diagonal),
        "rms_relative": relative(d.rms, diagonal),
        "samples": d.samples,
        "area": d.area,
        "argmax_point": d.argmax_point,
        "argmax_closest": d.argmax_closest,
    })
}

/// `x / diagonal`, or `null` for a degenerate box.
fn relative(x: f64, diagonal: f64) -> Value {
    if diagonal > 0.0 {
        json!(x / diagonal)
    } else {
        Value::Null
    }
}

/// The operation: reads `a` and `b` (paths), measures `a → b` and, unless
/// `direction` is `"a_to_b"`, `b → a`.
///
/// # Errors
/// `invalid_request` for missing paths or bad options, `invalid_mesh` for a mesh without
/// (non-degenerate) faces, `io`, `cancelled` (within a few milliseconds of work: the
/// comparison checks the flag in every long loop).
pub fn run(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    // The comparison looks at the job's cancel flag every ~1 ms of work.
    let mut options = CompareOptions::default().with_cancel(ctx.cancel_token().flag());
    if let Some(n) = u64_param(&request, "samples")? {
        options = options.with_samples(n);
    }
    if let Some(seed) = u64_param(&request, "seed")? {
        options = options.with_seed(seed);
    }
    if let Some(v) = bool_param(&request, "vertices")? {
        options = options.with_vertices(v);
    }
    if let Some(e) = bool_param(&request, "edges")? {
        options = options.with_edges(e);
    }
    let both = match request.str_param("direction")? {
        None | Some("both") => true,
        Some("a_to_b") => false,
        Some(other) => {
            return Err(OpError::request(format!(
                "`direction` must be \"both\" or \"a_to_b\", got {other:?}"
            )));
        }
    };
    let (a, a_path) = read_mesh_param(&request, "a", ctx)?;
    ctx.progress(0.1, "read", "")?;
    let (b, b_path) = read_mesh_param(&request, "b", ctx)?;
    ctx.progress(0.2, "a_to_b", "")?;
    let ab = tessd_compare::one_sided(&a, &b, &options).map_err(compare_error)?;
    let diagonal = tessd_compare::bbox_diagonal(&a, &b);
    let mut result = json!({
        "a": a_path.display().to_string(),
        "b": b_path.display().to_string(),
        "a_to_b": distance_json(&ab, diagonal),
        "bbox_diagonal": diagonal,
    });
    if both {
        ctx.progress(0.6, "b_to_a", "")?;
        let ba = tessd_compare::one_sided(&b, &a, &options).map_err(compare_error)?;
        let c = Comparison::from_directions(ab, ba, diagonal);
        result["b_to_a"] = distance_json(&c.b_to_a, diagonal);
        result["hausdorff"] = json!(c.hausdorff);
        result["mean"] = json!(c.mean);
        result["rms"] = json!(c.rms);
        result["hausdorff_relative"] = relative(c.hausdorff, diagonal);
        result["rms_relative"] = relative(c.rms, diagonal);
    } else {
        result["b_to_a"] = Value::Null;
        result["hausdorff"] = Value::Null;
        result["mean"] = Value::Null;
        result["rms"] = Value::Null;
        result["hausdorff_relative"] = Value::Null;
        result["rms_relative"] = Value::Null;
    }
    ctx.progress(1.0, "done", "")?;
    Ok(Response::json(result))
}
