//! Adaptive binary probabilities (paper 003 §5.3 computes one table per context and level from
//! the whole file; here each context's decisions learn their probability as they are coded, so
//! a cell needs no table and codes in one pass).
//!
//! A model starts at 1/2 and moves towards each decision it sees by `1/(n + 2)` of the way, `n`
//! being the decisions seen so far (the Krichevsky–Trofimov estimate: after the first decision
//! 3/4, then 2/3 of the count…), until the rate reaches [`RATE_LIMIT`], after which it keeps
//! that rate and follows a drifting source. The fast start is what lets every cell start from
//! scratch (prefixes, view sessions and threads need each cell decodable alone) at little cost
//! against trained tables. Everything is integer: the same bits on every machine.

use crate::binary_coder::PROB_BITS;

/// The slowest rate is `1 / RATE_LIMIT`.
pub const RATE_LIMIT: u32 = 32;

/// Probabilities stay within `[MIN_P, 2^16 − MIN_P]`, so that a surprise costs at most
/// about 11 bits.
const MIN_P: u32 = 32;

/// One binary model: the probability of a 0 (16 bits) and the decisions seen (saturating).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Model(u32);

/// The rate `2^16 / min(n + 2, RATE_LIMIT)` for each count `n` (which saturates at
/// `RATE_LIMIT − 1`).
const RECIPROCALS: [u32; RATE_LIMIT as usize] = {
    let mut t = [0u32; RATE_LIMIT as usize];
    let mut n = 0;
    while n < t.len() {
        let d = if n as u32 + 2 < RATE_LIMIT {
            n as u32 + 2
        } else {
            RATE_LIMIT
        };
        t[n] = (1 << 16) / d;
        n += 1;
    }
    t
};

impl Default for Model {
    fn default() -> Self {
        Model::new()
    }
}

impl Model {
    /// Even odds, nothing seen.
    pub const fn new() -> Self {
        Model(1 << (PROB_BITS - 1))
    }

    /// The probability of a 0, in units of `2^-16`.
    #[inline]
    pub fn p0(self) -> u32 {
        self.0 & 0xFFFF
    }

    /// The same probability, as if learnt from at most `n` decisions (it then moves faster).
    pub fn with_count_at_most(self, n: u32) -> Self {
        Model(((self.0 >> 16).min(n) << 16) | (self.0 & 0xFFFF))
    }

    /// Learns from one decision.
    #[inline]
    pub fn update(&mut self, bit: bool) {
        let n = self.0 >> 16;
        let p = (self.0 & 0xFFFF) as i32;
        let rate = RECIPROCALS[n as usize] as i32;
        let target = if bit {
            MIN_P as i32
        } else {
            (1 << 16) - MIN_P as i32
        };
        let p = p + (((target - p) * rate) >> 16);
        let n = (n + 1).min(RATE_LIMIT - 1);
        self.0 = (n << 16) | p as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_fast_and_stays_in_bounds() {
        let mut m = Model::new();
        m.update(false);
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
}
