//! `debug.echo`: returns its params and arrays unchanged. It measures the protocol's own cost
//! (framing, array tables, socket) apart from any geometry work, and lets clients test their
//! array encoding against the daemon.

use serde_json::Value;
use tessd_ipc::error::OpError;
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

/// The operation: `result` is the params object; the arrays come back as sent (the payload
/// buffer is shared, not copied).
///
/// # Errors
/// Never, except `cancelled`.
pub fn run(request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.checkpoint()?;
    Ok(Response {
        result: Value::Object(request.params),
        arrays: request.arrays.into_owned(),
        files: Vec::new(),
    })
}
