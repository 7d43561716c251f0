//! A blocking Rust client, one request at a time (the CLI demo and benchmarks use it; host
//! tools use the Python package in `python/`).

use crate::arrays::{Arrays, OwnedArray};
use crate::error::{ErrorCode, OpError};
use crate::frame::{FrameError, Limits, read_frame, write_frame};
use crate::job::Progress;
use interprocess::local_socket::Stream;
use serde_json::{Map, Value, json};
use std::io::BufReader;
use std::path::Path;

/// Why a call failed.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The daemon answered with an error frame (shown as the frame's `code: message`, once).
    #[error(transparent)]
    Op(#[from] OpError),
    /// The connection or its bytes failed.
    #[error("protocol: {0}")]
    Frame(#[from] FrameError),
    /// Could not connect.
    #[error("cannot connect to {path}: {source}")]
    Connect {
        /// Socket path.
        path: String,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}

/// A connection to a daemon.
pub struct Client {
    reader: BufReader<Stream>,
    next_id: u64,
    limits: Limits,
    last_elapsed_ms: Option<f64>,
}

impl Client {
    /// Connects to the daemon at `socket`.
    ///
    /// # Errors
    /// [`ClientError::Connect`] when nothing listens there.
    pub fn connect(socket: &Path) -> Result<Client, ClientError> {
        let stream = crate::socket::connect(socket).map_err(|source| ClientError::Connect {
            path: socket.display().to_string(),
            source,
        })?;
        let limits = Limits::default().with_max_payload(u64::MAX);
        Ok(Client {
            reader: BufReader::with_capacity(64 << 10, stream),
            next_id: 1,
            limits,
            last_elapsed_ms: None,
        })
    }

    /// Sends `op` and waits for its final reply, passing progress frames to `on_progress`.
    ///
    /// # Errors
    /// The daemon's error, or a transport failure.
    pub fn call(
        &mut self,
        op: &str,
        params: Value,
        arrays: &[OwnedArray],
        mut on_progress: impl FnMut(&Progress),
    ) -> Result<(Value, Arrays), ClientError> {
        let id = self.next_id;
        self.next_id += 1;
        self.last_elapsed_ms = None;
        let Value::Object(msg) = json!({"id": id, "op": op, "params": params}) else {
            unreachable!()
        };
        write_frame(&mut self.reader.get_ref(), msg, arrays).map_err(FrameError::Io)?;
        loop {
            let frame = read_frame(&mut self.reader, &self.limits)?;
            let kind = frame.json.get("type").and_then(Value::as_str).unwrap_or("");
            match kind {
                "progress" => on_progress(&parse_progress(&frame.json)),
                "ok" => {
                    self.last_elapsed_ms = frame.json.get("elapsed_ms").and_then(Value::as_f64);
                    let result = frame.json.get("result").cloned().unwrap_or(Value::Null);
                    return Ok((result, frame.arrays));
                }
                _ => {
                    let err = frame.json.get("error");
                    let field = |k: &str| {
                        err.and_then(|e| e.get(k))
                            .and_then(Value::as_str)
                            .unwrap_or("")
                            .to_string()
                    };
                    let code = ErrorCode::parse(&field("code"));
                    return Err(OpError::new(code, field("message")).into());
                }
            }
        }
    }

    /// The `elapsed_ms` of the last `ok` reply: the milliseconds the daemon spent on that
    /// request (docs/protocol.md, "Replies"); `None` before any, after an error, and for
    /// `hello` / `ping` / `cancel`, whose replies carry none.
    pub fn last_elapsed_ms(&self) -> Option<f64> {
        self.last_elapsed_ms
    }
}

fn parse_progress(json: &Map<String, Value>) -> Progress {
    let p = json.get("progress");
    let s = |k: &str| {
        p.and_then(|p| p.get(k))
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string()
    };
    Progress {
        fraction: p
            .and_then(|p| p.get("fraction"))
            .and_then(Value::as_f64)
            .unwrap_or(0.0),
        stage: s("stage"),
        message: s("message"),
    }
}
