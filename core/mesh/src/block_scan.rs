//! Block-wise reductions for validating large arrays at memory speed.
//!
//! Each check reduces a block of a few thousand values to one number (a maximum, an OR) in a
//! branch-free loop the compiler vectorises, and only when a block fails looks inside it for
//! the first offending element, so that errors still name it. Validation of a 4 M-triangle mesh
//! is then a few passes over its arrays instead of a branch per corner, and the blocks are
//! shared out between the cores (rayon's `position_first` still reports the *first* failing
//! block, so the error named does not depend on the thread count).

use rayon::prelude::*;

/// Values per block: big enough to amortise the per-block test, small enough to stay in L1.
const BLOCK: usize = 4096;

/// Bits of an `f32` with the sign cleared; at or above this value it is ±∞ or NaN.
const NON_FINITE: u32 = 0x7f80_0000;

/// Index of the first value that is NaN or infinite.
pub(crate) fn first_non_finite(values: &[f32]) -> Option<usize> {
    let b = values.par_chunks(BLOCK).position_first(|block| {
        let top = block
            .iter()
            .fold(0u32, |m, v| m.max(v.to_bits() & 0x7fff_ffff));
        top >= NON_FINITE
    })?;
    let i = values[b * BLOCK..].iter().position(|v| !v.is_finite());
    Some(b * BLOCK + i.expect("the block holds one"))
}

/// Index of the first value that is `>= bound`.
pub(crate) fn first_at_or_above(values: &[u32], bound: u32) -> Option<usize> {
    let b = values
        .par_chunks(BLOCK)
        .position_first(|block| block.iter().fold(0u32, |m, &v| m.max(v)) >= bound)?;
    let i = values[b * BLOCK..].iter().position(|&v| v >= bound);
    Some(b * BLOCK + i.expect("the block holds one"))
}

/// Whether every step of `offsets` is at least `min_step` (so the offsets never decrease and
/// every face has at least `min_step` corners).
pub(crate) fn steps_at_least(offsets: &[u32], min_step: u32) -> bool {
    let n = offsets.len().saturating_sub(1);
    let (lo, hi) = (&offsets[..n], &offsets[offsets.len().min(1)..]);
    lo.par_chunks(BLOCK)
        .zip(hi.par_chunks(BLOCK))
        .all(|(a, b)| {
            // u64 sums cannot wrap; the OR of the failures vectorises.
            let bad = a.iter().zip(b).fold(0u32, |acc, (&x, &y)| {
                acc | u32::from(u64::from(x) + u64::from(min_step) > u64::from(y))
            });
            bad == 0
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_first_non_finite_value_across_blocks() {
        let mut v = vec![1.5f32; 3 * BLOCK + 7];
        assert_eq!(first_non_finite(&v), None);
        v[2 * BLOCK + 5] = f32::NAN;
        v[3 * BLOCK + 1] = f32::INFINITY;
        assert_eq!(first_non_finite(&v), Some(2 * BLOCK + 5));
        v[2 * BLOCK + 5] = -f32::MAX;
        assert_eq!(first_non_finite(&v), Some(3 * BLOCK + 1));
        v[0] = f32::NEG_INFINITY;
        assert_eq!(first_non_finite(&v), Some(0));
        assert_eq!(first_non_finite(&[]), None);
    }

    #[test]
    fn finds_the_first_index_at_or_above_a_bound() {
        let mut v: Vec<u32> = (0..10_000).map(|i| i % 100).collect();
        assert_eq!(first_at_or_above(&v, 100), None);
        v[9_999] = 100;
        v[5_000] = u32::MAX;
        assert_eq!(first_at_or_above(&v, 100), Some(5_000));
        assert_eq!(first_at_or_above(&v, 0), Some(0));
        assert_eq!(first_at_or_above(&[], 0), None);
    }

    #[test]
    fn steps_cover_decreases_and_short_faces() {
        let mut o: Vec<u32> = (0..=3 * BLOCK as u32).map(|f| 3 * f).collect();
        assert!(steps_at_least(&o, 3));
        assert!(!steps_at_least(&o, 4));
        o[BLOCK + 1] -= 1;
        assert!(!steps_at_least(&o, 3));
        o[BLOCK + 1] = u32::MAX;
        assert!(!steps_at_least(&o, 3), "a decrease after a huge step");
        assert!(steps_at_least(&[0], 3) && steps_at_least(&[], 3));
    }
}
