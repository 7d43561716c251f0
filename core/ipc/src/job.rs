//! The job model shared by socket requests and job files: progress reporting and cooperative
//! cancellation (docs/protocol.md, "Replies" and "Cancellation").

use crate::error::OpError;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A progress report: how far, in which stage, with an optional message.
#[derive(Clone, Debug, PartialEq)]
pub struct Progress {
    /// Fraction done, 0..=1.
    pub fraction: f64,
    /// Short stage name (`read`, `cluster`, ...).
    pub stage: String,
    /// Free text.
    pub message: String,
}

/// A flag that asks a job to stop; cheap to clone and to check.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// Asks the job to stop at its next checkpoint.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// The shared flag itself, for library code that polls an `Arc<AtomicBool>`
    /// (e.g. `tessd_mesh::io::ReadOptions::with_cancel`).
    pub fn flag(&self) -> Arc<AtomicBool> {
        self.0.clone()
    }

    /// Whether cancellation was asked for.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// What an operation gets besides its request: a progress sink and a cancel token.
pub struct JobContext<'a> {
    sink: &'a (dyn Fn(Progress) + Sync),
    cancel: CancelToken,
    last: std::sync::Mutex<Option<Instant>>,
}

/// Progress reports closer together than this are dropped (except the final one), so a tight
/// loop cannot flood the socket.
const PROGRESS_INTERVAL: Duration = Duration::from_millis(10);

impl<'a> JobContext<'a> {
    /// A context reporting to `sink` and stopping when `cancel` is set.
    pub fn new(sink: &'a (dyn Fn(Progress) + Sync), cancel: CancelToken) -> JobContext<'a> {
        JobContext {
            sink,
            cancel,
            last: std::sync::Mutex::new(None),
        }
    }

    /// Reports progress (rate-limited), then checks for cancellation.
    ///
    /// # Errors
    /// [`OpError::cancelled`] when the job was cancelled.
    pub fn progress(&self, fraction: f64, stage: &str, message: &str) -> Result<(), OpError> {
        let now = Instant::now();
        let send = {
            let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
            let due = last.is_none_or(|t| now - t >= PROGRESS_INTERVAL) || fraction >= 1.0;
            if due {
                *last = Some(now);
            }
            due
        };
        if send {
            (self.sink)(Progress {
                fraction: fraction.clamp(0.0, 1.0),
                stage: stage.into(),
                message: message.into(),
            });
        }
        self.checkpoint()
    }

    /// Returns `Err(cancelled)` when the job should stop.
    ///
    /// # Errors
    /// [`OpError::cancelled`] when the job was cancelled.
    pub fn checkpoint(&self) -> Result<(), OpError> {
        if self.cancel.is_cancelled() {
            Err(OpError::cancelled())
        } else {
            Ok(())
        }
    }

    /// The job's cancel token, for handing to library code that polls it.
    pub fn cancel_token(&self) -> &CancelToken {
        &self.cancel
    }
}
