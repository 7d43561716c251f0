//! The library crates' errors in the protocol's terms: each `MeshError`, `UsdError`,
//! `ValidationError` (B-Rep), `RenderError` and `SimplifyError` becomes an [`OpError`] with the code a client
//! acts on. Below the ops and their parameters, which all raise them.

use tessd_brep::ValidationError;
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_mesh::MeshError;
use tessd_render::RenderError;
use tessd_simplify::SimplifyError;

/// Maps a mesh-crate error onto the protocol's codes. An unknown extension's message lists
/// what tessd reads and writes, `.usda` stages included, and says that binary USD is not one
/// of them.
pub fn mesh_error(e: MeshError) -> OpError {
    let code = match e.code() {
        "too_large" => ErrorCode::TooLarge,
        "unsupported" => ErrorCode::Unsupported,
        "io" => ErrorCode::Io,
        "cancelled" => ErrorCode::Cancelled,
        _ => ErrorCode::InvalidMesh,
    };
    let mut message = e.to_string();
    if let MeshError::Unsupported(m) = &e
        && m.ends_with(tessd_mesh::io::EXPECTED_EXTENSIONS)
    {
        let binary_usd = ["'.usdc'", "'.usdz'", "'.usd'"]
            .iter()
            .any(|x| m.to_ascii_lowercase().contains(x));
        let head = &m[..m.len() - tessd_mesh::io::EXPECTED_EXTENSIONS.len()];
        message = format!("{head}{TESSD_EXTENSIONS}");
        if binary_usd {
            message += "; binary USD (.usdc, .usdz, .usd) is not supported: use .usda, USD's \
                        text format (usdcat converts one into the other)";
        }
    }
    OpError::new(code, message)
}

/// The mesh files tessd reads and writes, as an unknown extension's message lists them.
pub const TESSD_EXTENSIONS: &str = "expected .obj, .ply, .stl, .off or .usda (a USD stage)";

/// Maps a USD writer or reader error onto the protocol's codes (a stage that cannot be read
/// is `invalid_mesh`, a binary crate file `unsupported`).
pub fn usd_error(e: tessd_usd::UsdError) -> OpError {
    let code = match e.code() {
        "invalid_mesh" => ErrorCode::InvalidMesh,
        "too_large" => ErrorCode::TooLarge,
        "io" => ErrorCode::Io,
        "unsupported" => ErrorCode::Unsupported,
        _ => ErrorCode::InvalidRequest,
    };
    OpError::new(code, e.to_string())
}

/// Maps a refusal of the document to `invalid_brep`, its message naming the element.
pub fn brep_error(e: ValidationError) -> OpError {
    OpError::new(ErrorCode::InvalidBrep, e.to_string())
}

/// Maps a renderer error onto the protocol's codes.
pub fn render_error(e: RenderError) -> OpError {
    if matches!(e, RenderError::Cancelled) {
        return OpError::cancelled();
    }
    let code = match &e {
        RenderError::Size(_) | RenderError::Camera(_) => ErrorCode::InvalidRequest,
        RenderError::Io(_) => ErrorCode::Io,
        _ => ErrorCode::Internal,
    };
    OpError::new(code, e.to_string())
}

/// Maps a simplification error onto the protocol's codes; `what` names the parameter an
/// invalid option comes from.
pub fn simplify_error(e: SimplifyError, what: &str) -> OpError {
    match e {
        SimplifyError::InvalidMesh(m) => mesh_error(m),
        SimplifyError::Empty => OpError::new(ErrorCode::InvalidMesh, "the mesh has no faces"),
        SimplifyError::InvalidOption(msg) => OpError::request(format!("`{what}`: {msg}")),
        SimplifyError::Cancelled => OpError::cancelled(),
        other => OpError::new(ErrorCode::Internal, other.to_string()),
    }
}
