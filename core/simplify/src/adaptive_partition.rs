//! Adaptive binary partitions (Belblidia & Perrin, sections 3–5).
//!
//! Both goals start from one cell, the bounding box of the object (section 3), and split a cell
//! in two across the largest side of the *points' inner bounding box* (section 5, figure 6), so
//! empty cells are never split and the cuts follow the points:
//!
//! - **quality goal** (section 3): a cell whose largest vertex displacement to its
//!   representative exceeds the tolerance is split, recursively, until none does. Every vertex
//!   then lies within the tolerance of its representative. Beyond the paper, named cells can be
//!   split further ([`Adaptive::split_clusters`]) until the surfaces, not only the vertices, are
//!   within the tolerance (`coverage.rs`).
//! - **complexity goal** (section 4): the cell with the largest displacement is split, one at a
//!   time (a priority queue), until the number of cells reaches the target.
//!
//! The vertices of a cell are a range of one index array that each split partitions in place
//! (like a k-d tree build), so the whole partition costs one `u32` per vertex.

use crate::options::Representative;
use crate::partition::{Cell, Partition, UNUSED};
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::atomic::{AtomicBool, Ordering as AtomicOrdering};

/// Cells with more vertices than this are refined in parallel (quality goal).
const PARALLEL_CELL: usize = 1 << 15;

/// A cell's vertices summarised: largest displacement to the representative, inner bounding
/// box.
#[derive(Clone, Copy, Debug)]
struct Eval {
    err: f64,
    lo: [f32; 3],
    hi: [f32; 3],
}

/// A quality partition that can still be refined: the vertices in leaf order and the leaves
/// (sorted by range; leaf `i` is cluster `i`).
pub(crate) struct Refinable {
    order: Vec<Point>,
    leaves: Vec<Node>,
    tolerance: f64,
}

/// A cell during refinement: its range of the index array, its box and its evaluation.
#[derive(Clone, Copy, Debug)]
struct Node {
    start: usize,
    end: usize,
    cell: Cell,
    eval: Eval,
}

/// The inputs shared by every step.
pub(crate) struct Adaptive<'a> {
    positions: &'a [[f32; 3]],
    weights: &'a [f32],
    heaviest: bool,
    cancel: Option<&'a AtomicBool>,
}

/// Why refinement stopped early.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Stop {
    /// Cancelled from outside.
    Cancelled,
}

impl<'a> Adaptive<'a> {
    /// Refinement over `positions` with `weights` (zero = unreferenced). Cells are judged with
    /// the heaviest vertex for [`Representative::Heaviest`] and with the weighted barycentre
    /// otherwise (the quadric representative is placed afterwards, see `representative.rs`).
    pub(crate) fn new(
        positions: &'a [[f32; 3]],
        weights: &'a [f32],
        rep: Representative,
        cancel: Option<&'a AtomicBool>,
    ) -> Self {
        Adaptive {
            positions,
            weights,
            heaviest: rep == Representative::Heaviest,
            cancel,
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(AtomicOrdering::Relaxed))
    }

    /// The referenced vertices, grouped by class (one root cell per class), and the root cells.
    /// Vertices are copied with their weights so that every later pass reads memory in order.
    fn roots(&self, classes: Option<&[u8]>, bounds: &Cell) -> (Vec<Point>, Vec<Node>) {
        let mut order: Vec<Point> = (0..self.positions.len())
            .filter(|&v| self.weights[v] > 0.0)
            .map(|v| Point {
                p: self.positions[v],
                w: self.weights[v],
                id: v as u32,
            })
            .collect();
        let mut ranges = vec![(0, order.len())];
        if let Some(classes) = classes {
            order.sort_by_key(|q| classes[q.id as usize]);
            let split = order.partition_point(|q| classes[q.id as usize] == 0);
            ranges = vec![(0, split), (split, order.len())];
        }
        let roots = ranges
            .into_iter()
            .filter(|(s, e)| e > s)
            .map(|(start, end)| Node {
                start,
                end,
                cell: *bounds,
                eval: self.evaluate(&order[start..end]),
            })
            .collect();
        (order, roots)
    }

    /// Representative, largest displacement and inner box of a non-empty set of vertices.
    fn evaluate(&self, verts: &[Point]) -> Eval {
        let mut acc = Acc::default();
        verts.iter().for_each(|q| acc.add(q));
        self.finish_eval(&acc, verts)
    }

    /// Completes an evaluation from a cell's accumulated sums: one more pass over its vertices
    /// for the largest displacement (in f32: the rounding is far below any tolerance, see the
    /// margin in `Prepared::run`).
    fn finish_eval(&self, acc: &Acc, verts: &[Point]) -> Eval {
        let rep: [f32; 3] = if self.heaviest {
            self.positions[acc.best.1 as usize]
        } else {
            acc.sum.map(|s| (s / acc.wsum) as f32)
        };
        let mut err2 = 0f32;
        for q in verts {
            let d = [q.p[0] - rep[0], q.p[1] - rep[1], q.p[2] - rep[2]];
            err2 = err2.max(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
        Eval {
            err: f64::from(err2).sqrt(),
            lo: acc.lo,
            hi: acc.hi,
        }
    }

    /// Splits `node` across the largest side of its inner box: partitions its vertices in place
    /// and returns the two children (both non-empty), or `None` when its vertices coincide. The
    /// partition pass also accumulates both children's sums, so each child costs one more pass.
    fn split(&self, order: &mut [Point], node: &Node) -> Option<(Node, Node)> {
        let Eval { lo, hi, .. } = node.eval;
        let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))?;
        if hi[axis] <= lo[axis] {
            return None;
        }
        let verts = &mut order[node.start..node.end];
        let mut at = 0.5 * (lo[axis] + hi[axis]);
        let (mut left_acc, mut right_acc) = (Acc::default(), Acc::default());
        let mut mid = partition_in_place(verts, |q| q.p[axis] < at, &mut left_acc, &mut right_acc);
        if mid == 0 || mid == verts.len() {
            // The midpoint rounded onto an end of the box: split at the median instead.
            mid = verts.len() / 2;
            verts.select_nth_unstable_by(mid, |a, b| a.p[axis].total_cmp(&b.p[axis]));
            at = verts[mid].p[axis];
            (left_acc, right_acc) = (Acc::default(), Acc::default());
            verts[..mid].iter().for_each(|q| left_acc.add(q));
            verts[mid..].iter().for_each(|q| right_acc.add(q));
        }
        let (left, right) = verts.split_at(mid);
        let mut lcell = node.cell;
        let mut rcell = node.cell;
        lcell.max[axis] = at;
        rcell.min[axis] = at;
        let (le, re) = (
            self.finish_eval(&left_acc, left),
            self.finish_eval(&right_acc, right),
        );
        Some((
            Node {
                start: node.start,
                end: node.start + mid,
                cell: lcell,
                eval: le,
            },
            Node {
                start: node.start + mid,
                end: node.end,
                cell: rcell,
                eval: re,
            },
        ))
    }

    /// Quality goal: refines until every vertex is within `tolerance` of its cell's
    /// representative. The result can be refined further ([`Adaptive::split_clusters`]) and
    /// read as a partition ([`Adaptive::partition`]).
    pub(crate) fn quality(
        &self,
        classes: Option<&[u8]>,
        bounds: &Cell,
        tolerance: f64,
    ) -> Result<Refinable, Stop> {
        let (mut order, roots) = self.roots(classes, bounds);
        let leaves = self.refine_all(&mut order, &roots, tolerance)?;
        Ok(Refinable {
            order,
            leaves,
            tolerance,
        })
    }

    /// The partition of a quality refinement: cluster `i` is its `i`-th leaf.
    pub(crate) fn partition(&self, r: &Refinable, keep_cells: bool) -> Partition {
        self.finish(&r.order, r.leaves.iter(), keep_cells)
    }

    /// Splits each of `clusters` (sorted leaf indices of `r`) once and refines both halves to
    /// the tolerance again (a half's new representative can be farther from some of its
    /// vertices than the parent's was). Returns how many were split: cells whose vertices all
    /// coincide cannot be, so a result of 0 means no further progress is possible.
    pub(crate) fn split_clusters(
        &self,
        r: &mut Refinable,
        clusters: &[u32],
    ) -> Result<usize, Stop> {
        let mut split = vec![false; r.leaves.len()];
        let mut halves = Vec::with_capacity(2 * clusters.len());
        for &c in clusters {
            if let Some((left, right)) = self.split(&mut r.order, &r.leaves[c as usize]) {
                split[c as usize] = true;
                halves.extend([left, right]);
            }
        }
        let count = halves.len() / 2;
        if count > 0 {
            // Both the kept leaves and the refined halves are in range order: merge them.
            let refined = self.refine_all(&mut r.order, &halves, r.tolerance)?;
            let mut kept = (r.leaves.iter().zip(&split))
                .filter(|(_, s)| !**s)
                .map(|(n, _)| *n)
                .peekable();
            let mut leaves = Vec::with_capacity(r.leaves.len() + refined.len() - count);
            for n in refined {
                while let Some(k) = kept.next_if(|k| k.start < n.start) {
                    leaves.push(k);
                }
                leaves.push(n);
            }
            leaves.extend(kept);
            r.leaves = leaves;
        }
        Ok(count)
    }

    /// Refines each of `cells` (disjoint ranges of `order`, sorted by start) until every
    /// resulting cell's displacement is at most `tolerance`; returns the leaves sorted by start.
    ///
    /// Refining is *tentative-safe*: splitting a cell only permutes its own range and always
    /// yields the same children, so the input cells stay valid whatever is done with the result.
    fn refine_all(
        &self,
        order: &mut [Point],
        cells: &[Node],
        tolerance: f64,
    ) -> Result<Vec<Node>, Stop> {
        let mut jobs: Vec<(Node, &mut [Point])> = Vec::with_capacity(cells.len());
        let mut rest = order;
        let mut consumed = 0;
        for c in cells {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(c.start - consumed);
            let (mine, tail) = tail.split_at_mut(c.end - c.start);
            rest = tail;
            consumed = c.end;
            jobs.push((*c, mine));
        }
        let parts: Vec<Result<Vec<Node>, Stop>> = if jobs.len() > 1 {
            use rayon::prelude::*;
            jobs.into_par_iter()
                .with_min_len(64)
                .map(|(c, slice)| self.refine_one(slice, c, tolerance))
                .collect()
        } else {
            jobs.into_iter()
                .map(|(c, slice)| self.refine_one(slice, c, tolerance))
                .collect()
        };
        let mut out = Vec::with_capacity(cells.len());
        for p in parts {
            out.extend(p?);
        }
        Ok(out)
    }

    /// Refines one cell whose vertices are exactly `slice`; leaves are numbered globally.
    fn refine_one(
        &self,
        slice: &mut [Point],
        cell: Node,
        tolerance: f64,
    ) -> Result<Vec<Node>, Stop> {
        if cell.eval.err <= tolerance {
            return Ok(vec![cell]);
        }
        let mut out = Vec::new();
        let local = Node {
            start: 0,
            end: cell.end - cell.start,
            ..cell
        };
        self.refine(slice, local, tolerance, &mut out)?;
        for n in &mut out {
            n.start += cell.start;
            n.end += cell.start;
        }
        Ok(out)
    }

    /// Depth-first refinement of one cell. `order` holds exactly the cell's vertices and
    /// `node` is numbered locally (`node.start == 0`); leaves are appended to `out` in order,
    /// numbered locally too.
    fn refine(
        &self,
        order: &mut [Point],
        node: Node,
        tolerance: f64,
        out: &mut Vec<Node>,
    ) -> Result<(), Stop> {
        if node.eval.err <= tolerance {
            out.push(node);
            return Ok(());
        }
        if self.cancelled() {
            return Err(Stop::Cancelled);
        }
        let Some((l, r)) = self.split(order, &node) else {
            out.push(node);
            return Ok(());
        };
        let mid = l.end;
        let (lo, hi) = order.split_at_mut(mid);
        let r_local = Node {
            start: 0,
            end: r.end - mid,
            ..r
        };
        if node.end - node.start > PARALLEL_CELL {
            let mut right = Vec::new();
            let (a, b) = rayon::join(
                || self.refine(lo, l, tolerance, out),
                || self.refine(hi, r_local, tolerance, &mut right),
            );
            a?;
            b?;
            out.extend(right.into_iter().map(|n| Node {
                start: n.start + mid,
                end: n.end + mid,
                ..n
            }));
        } else {
            self.refine(lo, l, tolerance, out)?;
            let from = out.len();
            self.refine(hi, r_local, tolerance, out)?;
            for n in &mut out[from..] {
                n.start += mid;
                n.end += mid;
            }
        }
        Ok(())
    }

    /// Complexity goal (section 4): splits, one at a time, the cell with the largest
    /// displacement until there are `target` cells. `more` then counts the output vertices
    /// after elimination (cells whose faces all collapse are lost) and asks for that many
    /// further splits. Stops early when no cell can be split (all remaining cells hold
    /// coincident vertices).
    pub(crate) fn complexity(
        &self,
        classes: Option<&[u8]>,
        bounds: &Cell,
        target: u64,
        keep_cells: bool,
        mut more: impl FnMut(&Partition) -> u64,
    ) -> Result<Partition, Stop> {
        // The leaves live in an arena (`live`, a split cell hands its slot to its left child);
        // `by_start` lists them in the order of their ranges.
        let (mut order, mut live) = self.roots(classes, bounds);
        let mut by_start: Vec<u32> = (0..live.len() as u32).collect();
        let mut goal = target as usize;
        loop {
            self.approach(&mut order, &mut live, &mut by_start, goal)?;
            let leaves = by_start.iter().map(|&i| &live[i as usize]);
            let partition = self.finish(&order, leaves, keep_cells);
            let extra = more(&partition) as usize;
            if extra == 0 || live.iter().all(|n| n.eval.err <= 0.0) {
                return Ok(partition);
            }
            // Ask for half the shortfall at a time: a split can revive clusters whose faces had
            // all collapsed, so the output may grow by more than the splits added.
            goal = live.len() + extra.div_ceil(2);
        }
    }

    /// Greedy splitting up to `goal` cells. A [`SplitQueue`] holds the cells that can still be
    /// split (displacement above zero) by arena index; afterwards `by_start` lists every leaf
    /// in the order of its range.
    fn approach(
        &self,
        order: &mut [Point],
        live: &mut Vec<Node>,
        by_start: &mut Vec<u32>,
        goal: usize,
    ) -> Result<(), Stop> {
        let top = live.iter().map(|n| n.eval.err).fold(0.0, f64::max);
        let mut queue = SplitQueue::new(top);
        let mut kept: Vec<u32> = Vec::with_capacity(goal);
        for (i, n) in live.iter().enumerate() {
            if n.eval.err > 0.0 {
                queue.push(ByError(n.eval.err, i as u32));
            } else {
                kept.push(i as u32);
            }
        }
        while kept.len() + queue.len() < goal {
            if self.cancelled() {
                return Err(Stop::Cancelled);
            }
            let Some(ByError(_, i)) = queue.pop() else {
                break;
            };
            let node = live[i as usize];
            match self.split(order, &node) {
                Some((l, r)) => {
                    live[i as usize] = l;
                    live.push(r);
                    for (child, slot) in [(l, i), (r, live.len() as u32 - 1)] {
                        if child.eval.err > 0.0 {
                            queue.push(ByError(child.eval.err, slot));
                        } else {
                            kept.push(slot);
                        }
                    }
                }
                None => kept.push(i),
            }
        }
        kept.extend(queue.drain().map(|k| k.1));
        kept.sort_unstable_by_key(|&i| live[i as usize].start);
        *by_start = kept;
        Ok(())
    }

    /// Numbers the leaves in order of their ranges and labels every vertex with its cluster.
    fn finish<'n>(
        &self,
        order: &[Point],
        leaves: impl Iterator<Item = &'n Node> + Clone,
        keep_cells: bool,
    ) -> Partition {
        let mut cluster_of = vec![UNUSED; self.positions.len()];
        let mut clusters = 0;
        for (id, leaf) in leaves.clone().enumerate() {
            clusters += 1;
            for q in &order[leaf.start..leaf.end] {
                cluster_of[q.id as usize] = id as u32;
            }
        }
        let cells = if keep_cells {
            leaves.map(|l| l.cell).collect()
        } else {
            Vec::new()
        };
        Partition {
            cluster_of,
            clusters,
            cells,
        }
    }
}

/// A max-priority queue of split candidates that pops in exactly the order of a binary heap
/// but keeps that heap small: keys are binned by their float bits (8 mantissa bits, so a bin
/// spans 0.4 % of a binade) and only the highest non-empty bin is heapified when it is needed.
/// With millions of cells, a plain heap's sifting misses the cache at every level; here most
/// pushes are appends to a bin.
struct SplitQueue {
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

    fn new(largest: f64) -> SplitQueue {
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

    fn push(&mut self, k: ByError) {
        let b = self.bin(k.0);
        if b >= self.current {
            self.heap.push(k);
        } else {
            self.bins[b].push(k);
        }
        self.len += 1;
    }

    fn pop(&mut self) -> Option<ByError> {
        if self.heap.is_empty() {
            let b = (0..self.current)
                .rev()
                .find(|&b| !self.bins[b].is_empty())?;
            self.current = b;
            self.heap = BinaryHeap::from(std::mem::take(&mut self.bins[b]));
        }
        let k = self.heap.pop()?;
        self.len -= 1;
        Some(k)
    }

    fn len(&self) -> usize {
        self.len
    }

    fn drain(self) -> impl Iterator<Item = ByError> {
        self.heap.into_iter().chain(self.bins.into_iter().flatten())
    }
}

/// Heap key: a node's largest displacement and its arena index. Largest error first; ties go
/// to the older node, so the order is deterministic.
#[derive(Clone, Copy, Debug)]
struct ByError(f64, u32);

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

/// A referenced vertex as the partition handles it: position, weight and vertex index.
#[derive(Clone, Copy, Debug)]
struct Point {
    p: [f32; 3],
    w: f32,
    id: u32,
}

/// Running sums of a cell: inner box, weighted position sum, heaviest vertex.
#[derive(Clone, Copy, Debug)]
struct Acc {
    lo: [f32; 3],
    hi: [f32; 3],
    sum: [f64; 3],
    wsum: f64,
    best: (f32, u32),
}

impl Default for Acc {
    fn default() -> Self {
        Acc {
            lo: [f32::INFINITY; 3],
            hi: [f32::NEG_INFINITY; 3],
            sum: [0.0; 3],
            wsum: 0.0,
            best: (f32::NEG_INFINITY, u32::MAX),
        }
    }
}

impl Acc {
    #[inline]
    fn add(&mut self, q: &Point) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(q.p[k]);
            self.hi[k] = self.hi[k].max(q.p[k]);
            self.sum[k] += f64::from(q.w) * f64::from(q.p[k]);
        }
        self.wsum += f64::from(q.w);
        // Ties go to the lowest vertex index, so results do not depend on order.
        if q.w > self.best.0 || (q.w == self.best.0 && q.id < self.best.1) {
            self.best = (q.w, q.id);
        }
    }
}

/// Moves the elements satisfying `pred` to the front (Hoare's two-pointer scheme: each element
/// is visited once) and adds each to the accumulator of the side it ends on; returns how many
/// satisfy `pred`.
fn partition_in_place(
    v: &mut [Point],
    pred: impl Fn(&Point) -> bool,
    left: &mut Acc,
    right: &mut Acc,
) -> usize {
    let (mut i, mut j) = (0, v.len());
    loop {
        while i < j && pred(&v[i]) {
            left.add(&v[i]);
            i += 1;
        }
        while i < j && !pred(&v[j - 1]) {
            right.add(&v[j - 1]);
            j -= 1;
        }
        if i >= j {
            return i;
        }
        v.swap(i, j - 1);
        left.add(&v[i]);
        right.add(&v[j - 1]);
        i += 1;
        j -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> (Vec<[f32; 3]>, Vec<f32>, Cell) {
        let p: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 0.0, 0.0]).collect();
        let b = Cell {
            min: [0.0; 3],
            max: [(n - 1) as f32, 0.0, 0.0],
        };
        (p, vec![1.0; n], b)
    }

    #[test]
    fn quality_bounds_every_displacement() {
        let (p, w, b) = line(100);
        let a = Adaptive::new(&p, &w, Representative::Barycenter, None);
        let part = a.partition(&a.quality(None, &b, 2.0).unwrap(), true);
        let mut sum = vec![[0f64; 2]; part.clusters];
        for (v, &c) in part.cluster_of.iter().enumerate() {
            sum[c as usize][0] += p[v][0] as f64;
            sum[c as usize][1] += 1.0;
        }
        for (v, &c) in part.cluster_of.iter().enumerate() {
            let rep = sum[c as usize][0] / sum[c as usize][1];
            assert!((p[v][0] as f64 - rep).abs() <= 2.0);
        }
        // 100 points 1 apart in clusters at most 5 wide: at least 20 clusters, and halving
        // never makes them more than twice as many as needed.
        assert!((20..=50).contains(&part.clusters), "{}", part.clusters);
        assert_eq!(part.cells.len(), part.clusters);
    }

    #[test]
    fn quality_in_parallel_matches_the_definition() {
        // Enough points to take the parallel path; every cluster must still meet the bound.
        let n = 3 * PARALLEL_CELL;
        let p: Vec<[f32; 3]> = (0..n)
            .map(|i| [(i % 1000) as f32, (i / 1000) as f32, 0.0])
            .collect();
        let w = vec![1.0; n];
        let b = Cell {
            min: [0.0; 3],
            max: [999.0, (n / 1000) as f32, 0.0],
        };
        let a = Adaptive::new(&p, &w, Representative::Barycenter, None);
        let part = a.partition(&a.quality(None, &b, 3.0).unwrap(), false);
        let mut sum = vec![[0f64; 3]; part.clusters];
        for (v, &c) in part.cluster_of.iter().enumerate() {
            sum[c as usize][0] += p[v][0] as f64;
            sum[c as usize][1] += p[v][1] as f64;
            sum[c as usize][2] += 1.0;
        }
        for (v, &c) in part.cluster_of.iter().enumerate() {
            let s = sum[c as usize];
            let d = ((p[v][0] as f64 - s[0] / s[2]).powi(2)
                + (p[v][1] as f64 - s[1] / s[2]).powi(2))
            .sqrt();
            assert!(d <= 3.0 + 1e-4, "vertex {v} moves {d}");
        }
    }

    #[test]
    fn split_clusters_splits_the_named_leaves_and_keeps_the_bound() {
        let (p, w, b) = line(100);
        let a = Adaptive::new(&p, &w, Representative::Barycenter, None);
        let mut r = a.quality(None, &b, 2.0).unwrap();
        let before = a.partition(&r, true);
        assert_eq!(a.split_clusters(&mut r, &[0, 3]).unwrap(), 2);
        let after = a.partition(&r, true);
        assert!(after.clusters >= before.clusters + 2);
        // Leaves still partition the line in order, each cell's vertices inside its box.
        for (v, &c) in after.cluster_of.iter().enumerate() {
            let cell = after.cells[c as usize];
            assert!(cell.min[0] <= p[v][0] && p[v][0] <= cell.max[0]);
        }
        // Cells other than 0 and 3 are unchanged.
        for cell in before
            .cells
            .iter()
            .enumerate()
            .filter(|(i, _)| ![0, 3].contains(i))
        {
            assert!(after.cells.contains(cell.1));
        }
    }

    #[test]
    fn complexity_hits_the_target_exactly() {
        let (p, w, b) = line(1000);
        let a = Adaptive::new(&p, &w, Representative::Barycenter, None);
        let part = a.complexity(None, &b, 137, false, |_| 0).unwrap();
        assert_eq!(part.clusters, 137);
    }

    #[test]
    fn coincident_points_stop_refinement() {
        let p = vec![[1.0f32; 3]; 10];
        let w = vec![1.0; 10];
        let b = Cell {
            min: [1.0; 3],
            max: [1.0; 3],
        };
        let a = Adaptive::new(&p, &w, Representative::Barycenter, None);
        let mut r = a.quality(None, &b, 1e-9).unwrap();
        assert_eq!(a.partition(&r, false).clusters, 1);
        assert_eq!(a.split_clusters(&mut r, &[0]).unwrap(), 0);
        assert_eq!(a.complexity(None, &b, 5, false, |_| 1).unwrap().clusters, 1);
    }

    #[test]
    fn hoare_partition_accumulates_each_point_once() {
        let mut v: Vec<Point> = (0..10)
            .map(|i| Point {
                p: [(9 - i) as f32, 0.0, 0.0],
                w: 1.0,
                id: i,
            })
            .collect();
        let (mut l, mut r) = (Acc::default(), Acc::default());
        let mid = partition_in_place(&mut v, |q| q.p[0] < 4.0, &mut l, &mut r);
        assert_eq!(mid, 4);
        assert!(v[..4].iter().all(|q| q.p[0] < 4.0) && v[4..].iter().all(|q| q.p[0] >= 4.0));
        assert_eq!((l.wsum, r.wsum), (4.0, 6.0));
        assert_eq!((l.sum[0], r.sum[0]), (6.0, 39.0));
    }
}
