//! Job files: a request (or a list of them) read from JSON and run in-process through the same
//! registry as socket requests (docs/protocol.md, "Job files").

use crate::error::OpError;
use crate::job::JobContext;
use crate::json_kind::json_kind;
use crate::registry::{Registry, Request, Response};
use serde_json::{Map, Value};
use std::path::Path;

/// One entry of a job file.
#[derive(Debug)]
pub struct JobSpec {
    /// Operation name.
    pub op: String,
    /// Its parameters.
    pub params: Map<String, Value>,
}

/// Parses a job file's text: `{"op": ..., "params": {...}}` or `{"jobs": [ ... ]}`.
///
/// # Errors
/// `invalid_request` naming the job and the field at fault.
pub fn parse(text: &str) -> Result<Vec<JobSpec>, OpError> {
    let v: Value = serde_json::from_str(text)
        .map_err(|e| OpError::request(format!("job file is not valid JSON: {e}")))?;
    let Value::Object(mut top) = v else {
        return Err(OpError::request(format!(
            "job file must hold an object, got {}",
            json_kind(&v)
        )));
    };
    match top.remove("jobs") {
        Some(Value::Array(items)) => items
            .into_iter()
            .enumerate()
            .map(|(i, item)| match item {
                Value::Object(m) => {
                    spec(m).map_err(|e| OpError::request(format!("job {i}: {}", e.message)))
                }
                other => Err(OpError::request(format!(
                    "job {i} must be an object, got {}",
                    json_kind(&other)
                ))),
            })
            .collect(),
        Some(other) => Err(OpError::request(format!(
            "`jobs` must be a list, got {}",
            json_kind(&other)
        ))),
        None => Ok(vec![spec(top)?]),
    }
}

fn spec(mut m: Map<String, Value>) -> Result<JobSpec, OpError> {
    let op = match m.remove("op") {
        Some(Value::String(s)) => s,
        _ => return Err(OpError::request("needs a string `op`")),
    };
    let params = match m.remove("params") {
        None => Map::new(),
        Some(Value::Object(p)) => p,
        Some(other) => {
            return Err(OpError::request(format!(
                "`params` must be an object, got {}",
                json_kind(&other)
            )));
        }
    };
    Ok(JobSpec { op, params })
}

/// Runs one job with paths resolved against `base_dir`.
///
/// # Errors
/// The operation's error.
pub fn run(
    registry: &Registry,
    job: JobSpec,
    base_dir: &Path,
    ctx: &JobContext,
) -> Result<Response, OpError> {
    let request = Request {
        params: job.params,
        base_dir: Some(base_dir.to_path_buf()),
        ..Request::default()
    };
    registry.run(&job.op, request, ctx)
}
