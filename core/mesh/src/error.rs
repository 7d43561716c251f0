//! The one error type of this crate: every variant names the offending element.

use thiserror::Error;

/// Errors from validating, reading or writing a mesh.
///
/// Messages name the element at fault ("face 12 uses vertex 9000; the mesh has 8000"), so a
/// host tool can show them to a user as they are.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The mesh breaks an invariant (index out of range, NaN coordinate, face with < 3 corners...).
    #[error("{0}")]
    Invalid(String),
    /// A file could not be parsed; `line` is 1-based for text formats, 0 where it does not apply
    /// (binary data), in which case the message is shown as `path: message`.
    #[error("{path}:{}{message}", line_prefix(*line))]
    Parse {
        /// The file (or `<memory>`).
        path: String,
        /// 1-based line for text formats; 0 for binary formats.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// A declared size exceeds what the input can hold or what the caller allows.
    #[error("{0}")]
    TooLarge(String),
    /// The file format or a feature of it is not supported.
    #[error("{0}")]
    Unsupported(String),
    /// An I/O failure, with the file it concerns.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned.
        path: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Reading stopped because the caller's cancel flag was set (see `io::ReadOptions::cancel`).
    #[error("cancelled")]
    Cancelled,
}

/// `"12: "` for a text line, `" "` when the line does not apply.
fn line_prefix(line: u64) -> String {
    if line == 0 {
        " ".to_string()
    } else {
        format!("{line}: ")
    }
}

impl MeshError {
    /// A short stable machine code for this error, as used by the wire protocol.
    pub fn code(&self) -> &'static str {
        match self {
            MeshError::Invalid(_) | MeshError::Parse { .. } => "invalid_mesh",
            MeshError::TooLarge(_) => "too_large",
            MeshError::Unsupported(_) => "unsupported",
            MeshError::Io { .. } => "io",
            MeshError::Cancelled => "cancelled",
        }
    }
}
