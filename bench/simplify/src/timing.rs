//! Medians and the stage clock: the time between the library's progress callbacks.

use std::time::Instant;

/// The median of `v` (NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// The name of the span from the call until the library's first progress callback
/// (validation and preparation, in the library before issue 33).
pub const START: &str = "start";

/// Times one call stage by stage. The library calls `progress(fraction, stage)` between
/// stages, naming the stage that begins; the clock charges the time since the previous
/// callback to the stage that callback named ([`START`] before the first one), so a stage
/// named several times (the quality goal's `cover` rounds) sums its spans.
pub struct StageClock {
    start: Instant,
    last: Instant,
    current: String,
    /// (stage, seconds, spans) in first-seen order.
    stages: Vec<(String, f64, u32)>,
}

impl StageClock {
    /// A clock started now.
    pub fn start() -> StageClock {
        let now = Instant::now();
        StageClock {
            start: now,
            last: now,
            current: START.to_string(),
            stages: Vec::new(),
        }
    }

    fn close_span(&mut self, now: Instant) {
        let dt = now.duration_since(self.last).as_secs_f64();
        match self.stages.iter_mut().find(|s| s.0 == self.current) {
            Some(s) => {
                s.1 += dt;
                s.2 += 1;
            }
            None => self.stages.push((self.current.clone(), dt, 1)),
        }
        self.last = now;
    }

    /// A progress callback naming `stage`.
    pub fn mark(&mut self, stage: &str) {
        self.close_span(Instant::now());
        stage.clone_into(&mut self.current);
    }

    /// Stops the clock (the call returned): the stages as (name, seconds, spans) in the
    /// order first met, and the whole call's seconds.
    pub fn finish(mut self) -> (Vec<(String, f64, u32)>, f64) {
        let now = Instant::now();
        self.close_span(now);
        (self.stages, now.duration_since(self.start).as_secs_f64())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_go_to_the_named_stage_and_repeat_sums() {
        let mut c = StageClock::start();
        std::thread::sleep(std::time::Duration::from_millis(4));
        c.mark("a");
        std::thread::sleep(std::time::Duration::from_millis(8));
        c.mark("b");
        c.mark("a");
        std::thread::sleep(std::time::Duration::from_millis(8));
        let (stages, total) = c.finish();
        let names: Vec<&str> = stages.iter().map(|s| s.0.as_str()).collect();
        assert_eq!(names, [START, "a", "b"]);
        assert!(stages[0].1 >= 0.004 && stages[1].1 >= 0.016, "{stages:?}");
        assert_eq!(stages[1].2, 2);
        let sum: f64 = stages.iter().map(|s| s.1).sum();
        assert!((sum - total).abs() < 1e-3, "{sum} vs {total}");
    }
}
