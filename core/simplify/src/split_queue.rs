//! The complexity goal's queue of split candidates (Belblidia & Perrin, section 4: the cell
//! with the largest key is split next).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// A max-priority queue of split candidates that pops in exactly the order of a binary heap
/// but keeps that heap small: keys are binned by their float bits (8 mantissa bits, so a bin
/// spans 0.4 % of a binade) and only the highest non-empty bin is heapified when it is needed.
/// With millions of cells, a plain heap's sifting misses the cache at every level; here most
/// pushes are appends to a bin.
pub(crate) struct SplitQueue {
    bins: Vec<Vec<ByError>>,
    /// Index of the lowest bin whose keys live in `heap`; every key in `bins` is below it.
    current: usize,
    heap: BinaryHeap<ByError>,
    /// Bin of the largest error seen at creation; bins are counted down from it.
    base: i64,
    len: usize,
}

impl SplitQueue {
    const BINS: usize = 1 << 16;

    pub(crate) fn new(largest: f64) -> SplitQueue {
        let base = (largest.to_bits() >> 44) as i64 + 1;
        SplitQueue {
            bins: vec![Vec::new(); Self::BINS],
            current: Self::BINS,
            heap: BinaryHeap::new(),
            base,
            len: 0,
        }
    }

    /// The bin of a key: monotone in the key (non-negative floats order like their bits).
    fn bin(&self, err: f64) -> usize {
        let b = (err.to_bits() >> 44) as i64 - (self.base - Self::BINS as i64);
        b.clamp(0, Self::BINS as i64 - 1) as usize
    }

    pub(crate) fn push(&mut self, k: ByError) {
        let b = self.bin(k.0);
        if b >= self.current {
            self.heap.push(k);
        } else {
            self.bins[b].push(k);
        }
        self.len += 1;
    }

    pub(crate) fn pop(&mut self) -> Option<ByError> {
        self.refill()?;
        let k = self.heap.pop()?;
        self.len -= 1;
        Some(k)
    }

    /// Removes and returns the cell with the largest key if that key is at least `floor`.
    pub(crate) fn pop_at_least(&mut self, floor: f64) -> Option<ByError> {
        self.refill()?;
        if self.heap.peek()?.0 < floor {
            return None;
        }
        self.pop()
    }

    /// Moves the highest non-empty bin into the heap when the heap is empty; `None` when the
    /// queue is empty.
    fn refill(&mut self) -> Option<()> {
        if self.heap.is_empty() {
            let b = (0..self.current)
                .rev()
                .find(|&b| !self.bins[b].is_empty())?;
            self.current = b;
            self.heap = BinaryHeap::from(std::mem::take(&mut self.bins[b]));
        }
        Some(())
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    pub(crate) fn drain(self) -> impl Iterator<Item = ByError> {
        self.heap.into_iter().chain(self.bins.into_iter().flatten())
    }
}

/// Heap key: a node's largest displacement and its arena index. Largest error first; ties go
/// to the older node, so the order is deterministic.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ByError(pub f64, pub u32);

impl PartialEq for ByError {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for ByError {}
impl PartialOrd for ByError {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for ByError {
    fn cmp(&self, o: &Self) -> Ordering {
        self.0.total_cmp(&o.0).then(o.1.cmp(&self.1))
    }
}
