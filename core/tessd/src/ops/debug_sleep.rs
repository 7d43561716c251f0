//! `debug.sleep`: a job that only waits, in steps, reporting progress and checking for
//! cancellation at each; it lets tests and host plugins exercise progress and cancel without
//! depending on how fast a real algorithm is.

use serde_json::json;
use std::time::Duration;
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

/// Longest sleep accepted, seconds.
const MAX_SECONDS: f64 = 60.0;

/// The operation: `params.seconds` (≤ 60) split into `params.steps` (1..=1000) steps.
///
/// # Errors
/// `invalid_request` for out-of-range parameters; `cancelled`.
pub fn run(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    let seconds = request.f64_param("seconds")?.unwrap_or(1.0);
    if !(0.0..=MAX_SECONDS).contains(&seconds) {
        return Err(OpError::request(format!(
            "`seconds` must be in 0..={MAX_SECONDS}, got {seconds}"
        )));
    }
    let steps = request.f64_param("steps")?.unwrap_or(10.0);
    if !(1.0..=1000.0).contains(&steps) || steps.fract() != 0.0 {
        return Err(OpError::request(format!(
            "`steps` must be an integer in 1..=1000, got {steps}"
        )));
    }
    let steps = steps as u32;
    for i in 0..steps {
        ctx.progress(
            f64::from(i) / f64::from(steps),
            "sleep",
            &format!("step {} of {steps}", i + 1),
        )?;
        std::thread::sleep(Duration::from_secs_f64(seconds / f64::from(steps)));
    }
    ctx.progress(1.0, "sleep", "done")?;
    Ok(Response::json(json!({"slept": seconds, "steps": steps})))
}
