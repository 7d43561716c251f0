//! The paths a request names, resolved against its base folder (the client's working folder
//! for the CLI, the job file's folder for `tessd job run`).

use std::path::PathBuf;
use tessd_ipc::error::OpError;
use tessd_ipc::registry::Request;

/// The request's output path (`params.output`), resolved, if any.
///
/// # Errors
/// `invalid_request` when `output` is not a string.
pub fn output_path(request: &Request) -> Result<Option<PathBuf>, OpError> {
    Ok(request.str_param("output")?.map(|p| request.resolve(p)))
}
