//! Adaptive binary probabilities (paper 003 §5.3 computes one table per context and level from
//! the whole file; here each context's decisions learn their probability as they are coded, so
//! a cell needs no table and codes in one pass).
//!
//! A model holds two estimates of the probability of a 0. Each starts at 1/2 and moves towards
//! each decision it sees by `1/(n + 2)` of the way, `n` being the decisions seen so far (the
//! Krichevsky–Trofimov estimate: after the first decision 3/4, then 2/3 of the count…), until its
//! rate reaches its limit: 1/[`FAST`] for one, which then follows a drifting source, 1/[`SLOW`]
//! for the other, which then averages a steady one. The model predicts their mean. The fast
//! start is what lets every cell start from scratch (prefixes, view sessions and threads need
//! each cell decodable alone) at little cost against trained tables. Everything is integer: the
//! same bits on every machine.
//!
//! Measured on the bunny (one cell and 43), fandisk, spot and the bunny at 16 bits (issue 34's
//! contexts): one estimate at rate 1/32 gave 17.949 / 20.350 / 19.253 / 24.655 / 29.838 b/v;
//! two at 1/10 and 1/256, 17.783 / 20.177 / 18.973 / 24.552 / 29.657 (1/16 and 1/128:
//! 17.817 / 20.228 / 19.094 / 24.554 / 29.674), for about a quarter more time per decision.

use crate::binary_coder::PROB_BITS;

/// Estimates stay within `[MIN_P, 2^16 − MIN_P]`, so that a surprise costs at most about 11
/// bits.
const MIN_P: u32 = 32;

/// One binary model: two probabilities of a 0 (16 bits), one adapting fast and one slowly,
/// and the decisions seen (saturating).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model {
    fast: u16,
    slow: u16,
    n: u16,
}

/// Rate limit of the fast estimate.
pub const FAST: u32 = 10;
/// Rate limit of the slow estimate (a power of two: the count indexes a table of that size).
pub const SLOW: u32 = 256;

/// The rates `2^16 / min(n + 2, limit)` for each count `n`.
const fn reciprocals<const N: usize>(limit: u32) -> [u32; N] {
    let mut t = [0u32; N];
    let mut n = 0;
    while n < N {
        let d = if n as u32 + 2 < limit {
            n as u32 + 2
        } else {
            limit
        };
        t[n] = (1 << 16) / d;
        n += 1;
    }
    t
}

const R_FAST: [u32; SLOW as usize] = reciprocals::<{ SLOW as usize }>(FAST);
const R_SLOW: [u32; SLOW as usize] = reciprocals::<{ SLOW as usize }>(SLOW);

impl Default for Model {
    fn default() -> Self {
        Model::new()
    }
}

impl Model {
    /// Even odds, nothing seen.
    pub const fn new() -> Self {
        let half = 1 << (PROB_BITS - 1);
        Model {
            fast: half,
            slow: half,
            n: 0,
        }
    }

    /// A model that starts at probability `p0` (units of `2^-16`, clamped to the estimates'
    /// bounds) as if learnt from `n` decisions.
    pub fn starting_at(p0: u32, n: u16) -> Self {
        let p = p0.clamp(MIN_P, (1 << PROB_BITS) - MIN_P) as u16;
        Model {
            fast: p,
            slow: p,
            n: n.min(SLOW as u16 - 1),
        }
    }

    /// The probability of a 0, in units of `2^-16`.
    #[inline]
    pub fn p0(self) -> u32 {
        (self.fast as u32 + self.slow as u32) >> 1
    }

    /// The same probability, as if learnt from at most `n` decisions (it then moves faster).
    pub fn with_count_at_most(self, n: u32) -> Self {
        Model {
            n: self.n.min(n as u16),
            ..self
        }
    }

    /// Learns from one decision.
    #[inline]
    pub fn update(&mut self, bit: bool) {
        let n = self.n as usize & (SLOW as usize - 1);
        let target = if bit {
            MIN_P as i32
        } else {
            (1 << 16) - MIN_P as i32
        };
        let f = self.fast as i32;
        self.fast = (f + (((target - f) * R_FAST[n] as i32) >> 16)) as u16;
        let s = self.slow as i32;
        self.slow = (s + (((target - s) * R_SLOW[n] as i32) >> 16)) as u16;
        self.n = (self.n + 1).min(SLOW as u16 - 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_fast_and_stays_in_bounds() {
        let mut m = Model::new();
        m.update(false);
        // both estimates go half way to the top at once
        assert_eq!(m.p0(), 32768 + (65536 - 32 - 32768) / 2);
        for _ in 0..10_000 {
            m.update(false);
        }
        assert!(m.p0() <= 65536 - MIN_P && m.p0() > 65000, "{}", m.p0());
        for _ in 0..10_000 {
            m.update(true);
        }
        assert!(m.p0() >= MIN_P && m.p0() < 600, "{}", m.p0());
    }

    #[test]
    fn the_estimate_follows_the_frequency() {
        // 1 in 5 decisions is a 1: the model settles near p0 = 0.8
        let mut m = Model::new();
        let mut sum = 0u64;
        for i in 0..5_000 {
            m.update(i % 5 == 0);
            if i >= 1_000 {
                sum += m.p0() as u64;
            }
        }
        let mean = sum as f64 / 4_000.0 / 65536.0;
        assert!((mean - 0.8).abs() < 0.02, "{mean}");
    }

    #[test]
    fn the_fast_estimate_follows_a_change_the_slow_one_averages() {
        let mut m = Model::new();
        for _ in 0..1_000 {
            m.update(false);
        }
        for _ in 0..20 {
            m.update(true);
        }
        // twenty 1s after a thousand 0s: the fast half is near 0, the slow one still high
        assert!(m.fast < 10_000 && m.slow > 40_000, "{m:?}");
        assert!(m.p0() > 20_000 && m.p0() < 40_000, "{}", m.p0());
    }

    #[test]
    fn a_start_is_kept_until_decisions_move_it() {
        let mut m = Model::starting_at(60_000, 1);
        assert_eq!(m.p0(), 60_000);
        m.update(true);
        // the second decision moves it a third of the way (rate 1/(n + 2), n = 1)
        assert_eq!(m.p0(), 60_000 - (60_000 - MIN_P) / 3 - 1);
        assert_eq!(Model::starting_at(0, 0).p0(), MIN_P);
    }
}
