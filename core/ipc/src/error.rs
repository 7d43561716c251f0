//! Operation errors with the protocol's stable codes (docs/protocol.md, "Error codes").

use thiserror::Error;

/// The stable machine codes of error frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorCode {
    /// The bytes are not a valid frame.
    InvalidFrame,
    /// A valid frame with a wrong request.
    InvalidRequest,
    /// The mesh breaks an invariant.
    InvalidMesh,
    /// The B-Rep breaks an invariant.
    InvalidBrep,
    /// A declared size exceeds a limit.
    TooLarge,
    /// A format or option tessd does not support.
    Unsupported,
    /// A file could not be read or written.
    Io,
    /// The request was cancelled.
    Cancelled,
    /// A bug in tessd.
    Internal,
}

impl ErrorCode {
    /// The code as sent on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorCode::InvalidFrame => "invalid_frame",
            ErrorCode::InvalidRequest => "invalid_request",
            ErrorCode::InvalidMesh => "invalid_mesh",
            ErrorCode::InvalidBrep => "invalid_brep",
            ErrorCode::TooLarge => "too_large",
            ErrorCode::Unsupported => "unsupported",
            ErrorCode::Io => "io",
            ErrorCode::Cancelled => "cancelled",
            ErrorCode::Internal => "internal",
        }
    }

    /// Parses a wire code (unknown codes map to `Internal`).
    pub fn parse(s: &str) -> ErrorCode {
        use ErrorCode::*;
        [
            InvalidFrame,
            InvalidRequest,
            InvalidMesh,
            InvalidBrep,
            TooLarge,
            Unsupported,
            Io,
            Cancelled,
        ]
        .into_iter()
        .find(|c| c.as_str() == s)
        .unwrap_or(Internal)
    }
}

/// An operation's failure: a code and a message naming the offending element.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error("{}: {message}", code.as_str())]
pub struct OpError {
    /// Stable code.
    pub code: ErrorCode,
    /// Human-readable message.
    pub message: String,
}

impl OpError {
    /// An error with `code` and `message`.
    pub fn new(code: ErrorCode, message: impl Into<String>) -> OpError {
        OpError {
            code,
            message: message.into(),
        }
    }

    /// An `invalid_request` error.
    pub fn request(message: impl Into<String>) -> OpError {
        OpError::new(ErrorCode::InvalidRequest, message)
    }

    /// The `cancelled` error.
    pub fn cancelled() -> OpError {
        OpError::new(ErrorCode::Cancelled, "the request was cancelled")
    }
}
