//! The codec's errors: every one names what it refers to (a parameter, an element of the input,
//! or the byte offset of a corrupt file).

use thiserror::Error;

/// What can go wrong while compressing or decoding.
#[derive(Debug, Error)]
pub enum CodecError {
    /// A parameter is out of its range.
    #[error("invalid parameter {name}: {why}")]
    Parameter {
        /// The parameter's name as the CLI spells it.
        name: &'static str,
        /// What is wrong with its value.
        why: String,
    },
    /// The input mesh holds something the codec cannot take.
    #[error("invalid input: {0}")]
    Input(String),
    /// The compressed file is not a valid `.tsc` file.
    #[error("corrupt .tsc file at byte offset {offset}: {why}")]
    Corrupt {
        /// Byte offset in the file where the problem was found.
        offset: u64,
        /// What was wrong there.
        why: String,
    },
    /// The caller asked to stop.
    #[error("cancelled")]
    Cancelled,
    /// Reading or writing a file failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being read or written.
        context: String,
        /// The operating system's error.
        source: std::io::Error,
    },
}

impl CodecError {
    /// A corrupt-file error at `offset`.
    pub(crate) fn corrupt(offset: u64, why: impl Into<String>) -> Self {
        CodecError::Corrupt {
            offset,
            why: why.into(),
        }
    }

    /// An I/O error with what was being done.
    pub(crate) fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        CodecError::Io {
            context: context.into(),
            source,
        }
    }
}
