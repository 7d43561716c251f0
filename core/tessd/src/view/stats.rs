//! What a scripted run reports (`{"stats": PATH}`): frames, frame times, what was drawn and
//! how, and what the background work did. Frame times are wall times from one frame's start
//! to the next, so they include presenting.

use serde_json::{Value, json};

/// Frame times and counters, kept for the whole run.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    /// Each frame's time, milliseconds.
    pub frame_ms: Vec<f64>,
    /// Frames drawn while background work (decoding, LODs, subdivision) was running.
    pub frames_while_busy: u64,
}

impl FrameStats {
    /// The `q`-quantile of the frame times (nearest rank), 0 when there are none.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.frame_ms.is_empty() {
            return 0.0;
        }
        let mut t = self.frame_ms.clone();
        t.sort_by(f64::total_cmp);
        let rank = ((q * t.len() as f64).ceil() as usize).clamp(1, t.len());
        t[rank - 1]
    }

    /// The JSON of the frame counters, merged into `extra` (the viewer's state).
    pub fn to_json(&self, mut extra: Value) -> Value {
        extra["frames"] = json!(self.frame_ms.len());
        extra["frame_ms_median"] = json!(self.quantile(0.5));
        extra["frame_ms_p95"] = json!(self.quantile(0.95));
        extra["frames_while_busy"] = json!(self.frames_while_busy);
        extra
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_ranks_of_the_sorted_times() {
        let s = FrameStats {
            frame_ms: (1..=100).rev().map(f64::from).collect(),
            frames_while_busy: 0,
        };
        assert_eq!(s.quantile(0.5), 50.0);
        assert_eq!(s.quantile(0.95), 95.0);
        assert_eq!(FrameStats::default().quantile(0.5), 0.0);
    }
}
