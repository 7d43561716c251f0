//! A blocking Rust client, one request at a time (the CLI demo and benchmarks use it; host
//! tools use the Python package in `python/`).

use crate::arrays::{Arrays, OwnedArray};
use crate::error::{ErrorCode, OpError};
use crate::frame::{FrameError, Limits, read_frame, write_frame};
use crate::job::Progress;
use interprocess::local_socket::Stream;
use serde_json::{Map, Value, json};
use std::io::{BufReader, Read};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

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
    reader: BufReader<SharedStream>,
    shared: Arc<Shared>,
    limits: Limits,
    last_elapsed_ms: Option<f64>,
}

/// What a [`Client`] shares with its [`Canceller`]s: the stream (frames are written whole,
/// under `write`), the request ids and the request running now (0: none).
struct Shared {
    stream: Arc<Stream>,
    write: Mutex<()>,
    next_id: AtomicU64,
    running: AtomicU64,
}

impl Shared {
    fn send(&self, op: &str, params: Value, arrays: &[OwnedArray]) -> Result<u64, ClientError> {
        let id = self.next_id.fetch_add(1, Ordering::SeqCst);
        let Value::Object(msg) = json!({"id": id, "op": op, "params": params}) else {
            unreachable!()
        };
        let _turn = self.write.lock().unwrap_or_else(|e| e.into_inner());
        write_frame(&mut &*self.stream, msg, arrays).map_err(FrameError::Io)?;
        Ok(id)
    }
}

/// The read side of the shared stream.
struct SharedStream(Arc<Stream>);

impl Read for SharedStream {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        (&*self.0).read(buf)
    }
}

/// Cancels, from anywhere (another thread, or the progress callback of the call itself), the
/// request its [`Client`] is waiting on: it sends `cancel` for that request's id on the same
/// connection (docs/protocol.md, "Cancel"), and the call then ends with a `cancelled` error
/// at the request's next checkpoint.
#[derive(Clone)]
pub struct Canceller(Arc<Shared>);

impl Canceller {
    /// Asks the daemon to cancel the running request; `false` when none is running (nothing
    /// is sent). The `cancel` request's own reply is read, and dropped, by the call.
    ///
    /// # Errors
    /// When the frame cannot be written.
    pub fn cancel(&self) -> Result<bool, ClientError> {
        let running = self.0.running.load(Ordering::SeqCst);
        if running == 0 {
            return Ok(false);
        }
        self.0.send("cancel", json!({"id": running}), &[])?;
        Ok(true)
    }
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
        let stream = Arc::new(stream);
        Ok(Client {
            reader: BufReader::with_capacity(64 << 10, SharedStream(stream.clone())),
            shared: Arc::new(Shared {
                stream,
                write: Mutex::new(()),
                next_id: AtomicU64::new(1),
                running: AtomicU64::new(0),
            }),
            limits,
            last_elapsed_ms: None,
        })
    }

    /// A handle that cancels the request this client is waiting on (see [`Canceller`]).
    pub fn canceller(&self) -> Canceller {
        Canceller(self.shared.clone())
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
        self.last_elapsed_ms = None;
        let id = self.shared.send(op, params, arrays)?;
        self.shared.running.store(id, Ordering::SeqCst);
        let result = self.wait_for(id, &mut on_progress);
        self.shared.running.store(0, Ordering::SeqCst);
        result
    }

    /// Reads frames until request `id`'s final reply; frames of other requests (the replies
    /// to a [`Canceller`]'s `cancel`) are dropped.
    fn wait_for(
        &mut self,
        id: u64,
        on_progress: &mut impl FnMut(&Progress),
    ) -> Result<(Value, Arrays), ClientError> {
        loop {
            let frame = read_frame(&mut self.reader, &self.limits)?;
            if frame.json.get("id").and_then(Value::as_u64) != Some(id) {
                continue;
            }
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
