//! `brep.load`: reads a B-Rep exchange document (docs/brep-format.md) from a file or inline,
//! resolves arrays by reference from the request's payload, validates it (`tessd-brep`), and
//! reports the face ids and the paper's table-1 counts, so a host learns before any
//! tessellation whether its export is sound and what it holds.
//!
//! Parameters are described in docs/protocol.md ("brep.load").

// Re-exported where they lived: `view` reads B-Rep files through these paths.
pub use super::library_errors::brep_error;
pub use super::params::brep_input::{is_brep_path, request_brep};
use serde_json::json;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::JobContext;
use tessd_ipc::registry::{Request, Response};

/// The operation.
///
/// # Errors
/// `invalid_request` for missing or conflicting parameters and unknown array references,
/// `io` when the file cannot be read, `invalid_brep` for a document the validator refuses
/// (its first error, with the count of the others).
pub fn run(mut request: Request, ctx: &JobContext) -> Result<Response, OpError> {
    ctx.progress(0.0, "read", "")?;
    let doc = request_brep(&mut request)?;
    ctx.progress(0.5, "validate", "")?;
    let errors = doc.errors();
    if let Some(first) = errors.first() {
        let mut message = first.to_string();
        if errors.len() > 1 {
            message.push_str(&format!(
                " (and {} more error{})",
                errors.len() - 1,
                if errors.len() == 2 { "" } else { "s" }
            ));
        }
        return Err(OpError::new(ErrorCode::InvalidBrep, message));
    }
    let result = json!({
        "format": doc.format,
        "version": doc.version,
        "units": doc.units.name(),
        "source": doc.source,
        "faces": doc.faces.iter().map(|f| f.id).collect::<Vec<_>>(),
        "edges": doc.edges.as_ref().map(|e| e.iter().map(|e| e.id).collect::<Vec<_>>()),
        "stats": doc.stats(),
    });
    ctx.progress(1.0, "done", "")?;
    Ok(Response::json(result))
}
