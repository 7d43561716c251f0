//! Deterministic data parallelism: every parallel pass of the pipeline cuts its items
//! (vertices, faces, clusters) into blocks of a fixed size that does not depend on the thread
//! count, computes one partial result per block (in parallel, on rayon's pool) and combines
//! the partials in block order. Floating-point sums are then always added in the same order,
//! cluster ids are given in the same (first-met) order and faces keep their order, so the
//! output is the same bytes on 1, 2 or N threads.

use rayon::prelude::*;
use std::ops::Range;

/// Items per block: large enough that a block's work dwarfs rayon's scheduling, small enough
/// that a block's scratch (a local cell table, partial sums) stays in cache.
pub(crate) const BLOCK: usize = 1 << 14;

/// The ranges of the blocks of `0..n`.
pub(crate) fn ranges(n: usize) -> impl IndexedParallelIterator<Item = Range<usize>> {
    (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(move |b| b * BLOCK..((b + 1) * BLOCK).min(n))
}

/// `f` of every block of `0..n`, in block order.
pub(crate) fn map<T: Send>(n: usize, f: impl Fn(Range<usize>) -> T + Sync + Send) -> Vec<T> {
    ranges(n).map(f).collect()
}

/// Whether the pool running the caller has a single thread (passes may then skip the
/// synchronisation a shared result needs; their results must not differ).
pub(crate) fn single_thread() -> bool {
    rayon::current_num_threads() == 1
}

/// The slices `ranges` (increasing, disjoint) of `order`, each mutable on its own, for a
/// parallel pass whose parts each write their own range: the cells of an adaptive partition
/// own disjoint ranges of the vertex order; the blocks of a counting pass own [`consecutive`]
/// ranges of its output.
pub(crate) fn disjoint_slices<T>(
    order: &mut [T],
    ranges: impl Iterator<Item = Range<usize>>,
) -> Vec<&mut [T]> {
    let (mut rest, mut consumed) = (order, 0usize);
    ranges
        .map(|r| {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(r.start - consumed);
            let (mine, tail) = tail.split_at_mut(r.end - r.start);
            rest = tail;
            consumed = r.end;
            mine
        })
        .collect()
}

/// The consecutive ranges of the given lengths from 0: the places a counting pass gives the
/// blocks of the next one, for [`disjoint_slices`].
pub(crate) fn consecutive(
    lengths: impl IntoIterator<Item = usize>,
) -> impl Iterator<Item = Range<usize>> {
    lengths.into_iter().scan(0usize, |at, n| {
        let r = *at..*at + n;
        *at += n;
        Some(r)
    })
}

/// A slice that the blocks of a parallel pass write at once, each at places no other block
/// writes (the caller's counting fixes them beforehand, as in a counting sort): the one
/// shape of shared writing that safe Rust cannot split up front, since a block's places are
/// scattered over the whole slice.
pub(crate) struct DisjointWrites<'a> {
    ptr: *mut u32,
    len: usize,
    _slice: std::marker::PhantomData<&'a mut [u32]>,
}

// SAFETY: the slice is borrowed mutably for the writer's lifetime, and only written through
// `write`, whose callers guarantee that no two threads write the same index.
unsafe impl Sync for DisjointWrites<'_> {}

impl<'a> DisjointWrites<'a> {
    /// A writer over `slice`.
    pub(crate) fn new(slice: &'a mut [u32]) -> Self {
        DisjointWrites {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _slice: std::marker::PhantomData,
        }
    }

    /// Writes `value` at `at`; no other thread may write `at` during the pass.
    pub(crate) fn write(&self, at: usize, value: u32) {
        assert!(at < self.len, "index {at} out of {}", self.len);
        // SAFETY: in bounds (checked above); the caller owns index `at` exclusively.
        unsafe { self.ptr.add(at).write(value) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_cover_in_order() {
        let r = map(2 * BLOCK + 5, |r| (r.start, r.end));
        assert_eq!(
            r,
            vec![(0, BLOCK), (BLOCK, 2 * BLOCK), (2 * BLOCK, 2 * BLOCK + 5)]
        );
        assert!(map(0, |r| r.len()).is_empty());
    }
}
