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

/// What one job may use, set by the daemon's operator (`tessd serve --max-mesh-elements`,
/// `--max-job-memory`) so that no single request can take the machine down.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JobLimits {
    /// Most vertices, faces or face corners an input mesh may have.
    pub max_mesh_elements: u64,
    /// Most bytes a job's estimated working set may reach; a job whose estimate, computed
    /// before it allocates, is larger is refused with `too_large`.
    pub max_job_memory: u64,
}

impl Default for JobLimits {
    /// The readers' own element cap (2^31) and the machine's physical memory.
    fn default() -> Self {
        JobLimits {
            max_mesh_elements: 1 << 31,
            max_job_memory: physical_memory().unwrap_or(u64::MAX),
        }
    }
}

/// The machine's physical memory in bytes (`MemTotal` of /proc/meminfo), where known.
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// What an operation gets besides its request: a progress sink, a cancel token and the limits
/// it is held to.
pub struct JobContext<'a> {
    sink: &'a (dyn Fn(Progress) + Sync),
    cancel: CancelToken,
    limits: JobLimits,
    /// When the last report was sent, and every stage reported so far.
    last: std::sync::Mutex<(Option<Instant>, Vec<String>)>,
}

/// Progress reports closer together than this are dropped (except the final one and the first
/// of each stage, which a client may be waiting for), so a tight loop cannot flood the socket.
/// A stage that comes back (the simplification's place / count / kd rounds alternate) is
/// rate-limited like any other report: only its first appearance always goes out.
const PROGRESS_INTERVAL: Duration = Duration::from_millis(10);

impl<'a> JobContext<'a> {
    /// A context reporting to `sink` and stopping when `cancel` is set.
    pub fn new(sink: &'a (dyn Fn(Progress) + Sync), cancel: CancelToken) -> JobContext<'a> {
        JobContext {
            sink,
            cancel,
            limits: JobLimits::default(),
            last: std::sync::Mutex::new((None, Vec::new())),
        }
    }

    /// Holds the job to `limits` instead of the defaults.
    pub fn with_limits(mut self, limits: JobLimits) -> Self {
        self.limits = limits;
        self
    }

    /// The limits the job is held to.
    pub fn limits(&self) -> &JobLimits {
        &self.limits
    }

    /// Refuses a job whose working set, estimated at `bytes` for `what` before anything is
    /// allocated, exceeds [`JobLimits::max_job_memory`].
    ///
    /// # Errors
    /// `too_large`, naming `what`, the estimate and the limit.
    pub fn admit_memory(&self, what: &str, bytes: u64) -> Result<(), OpError> {
        if bytes > self.limits.max_job_memory {
            return Err(OpError::new(
                crate::error::ErrorCode::TooLarge,
                format!(
                    "{what} needs about {bytes} bytes, above the daemon's per-job limit of {} \
                     bytes (tessd serve --max-job-memory)",
                    self.limits.max_job_memory
                ),
            ));
        }
        Ok(())
    }

    /// Reports progress (rate-limited: a new stage and the final report always go out), then
    /// checks for cancellation.
    ///
    /// # Errors
    /// [`OpError::cancelled`] when the job was cancelled.
    pub fn progress(&self, fraction: f64, stage: &str, message: &str) -> Result<(), OpError> {
        let now = Instant::now();
        let send = {
            let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
            let (at, seen) = &mut *last;
            let new_stage = !seen.iter().any(|s| s == stage);
            let due =
                fraction >= 1.0 || new_stage || at.is_none_or(|t| now - t >= PROGRESS_INTERVAL);
            if new_stage {
                seen.push(stage.to_string());
            }
            if due {
                *at = Some(now);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Reports inside the interval are dropped, except a new stage's first and the final one; a
    /// stage that comes back is not new.
    #[test]
    fn a_new_stage_and_the_end_always_go_out() {
        let sent = std::sync::Mutex::new(Vec::new());
        let sink = |p: Progress| sent.lock().unwrap().push((p.stage, p.fraction));
        let ctx = JobContext::new(&sink, CancelToken::default());
        // All within microseconds, far inside the 10 ms interval.
        ctx.progress(0.0, "read", "").unwrap();
        ctx.progress(0.05, "read", "").unwrap();
        ctx.progress(0.1, "read", "").unwrap();
        ctx.progress(0.2, "a_to_b", "").unwrap();
        ctx.progress(0.3, "a_to_b", "").unwrap();
        // Stages that come back in rounds are not new: dropped inside the interval.
        ctx.progress(0.4, "read", "").unwrap();
        ctx.progress(0.5, "a_to_b", "").unwrap();
        ctx.progress(1.0, "done", "").unwrap();
        let sent = sent.lock().unwrap().clone();
        assert_eq!(
            sent,
            vec![
                ("read".to_string(), 0.0),
                ("a_to_b".to_string(), 0.2),
                ("done".to_string(), 1.0)
            ]
        );
    }
}
