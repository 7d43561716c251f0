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

use crate::blocks;
use crate::feature_priority::{PackedNormal, plane_distance2, priority};
use crate::options::Representative;
use crate::partition::{Cell, Partition, UNUSED};
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::atomic::{AtomicBool, Ordering as AtomicOrdering};

/// Cells with more vertices than this are refined in parallel (quality goal) and evaluated
/// by blocks on every core.
const PARALLEL_CELL: usize = 1 << 15;

/// The slices `ranges` (increasing, disjoint) of `order`, each mutable on its own: the cells
/// of a partition own disjoint ranges of the vertex order, so they can be refined or split in
/// parallel.
fn disjoint_slices<T>(
    order: &mut [T],
    ranges: impl Iterator<Item = std::ops::Range<usize>>,
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

/// Rounds with fewer points than this are split on one core (see `Adaptive::split_round`).
const PARALLEL_ROUND: usize = 1 << 14;

/// Cells of a round split together (see `Adaptive::approach`).
const ROUND_CHUNK: usize = 4096;

/// A split's two children and its cut, or `None` when the cell's vertices coincide.
type Halves = Option<(Node, Node, Cut)>;

/// The complexity goal's rounds (see `Adaptive::approach`): a round splits every cell whose
/// key is at least this share of the largest.
const ROUND_SHARE: f64 = 0.9;

/// A cell's vertices summarised: largest displacement to the representative (or, with vertex
/// normals, the complexity goal's split priority), and where the cell would be split (the
/// middle of the largest side of its inner box: the box itself is not kept, 12 bytes a cell
/// instead of 28).
#[derive(Clone, Copy, Debug)]
struct Eval {
    /// The largest squared displacement, as measured (in f32): the displacement is its root in
    /// f64 ([`Eval::err`]), which orders exactly as it does, and it takes half the room. For
    /// the complexity goal with vertex normals, the square of the cell's
    /// `feature_priority::priority` instead: zero exactly when the displacement is.
    err2: f32,
    /// The coordinate of the cut along `axis`.
    at: f32,
    /// The axis of the inner box's largest side, or [`NO_CUT`] when the vertices coincide.
    axis: u8,
}

/// [`Eval::axis`] of a cell whose vertices coincide.
const NO_CUT: u8 = u8::MAX;

impl Eval {
    /// The largest displacement.
    fn err(&self) -> f64 {
        f64::from(self.err2).sqrt()
    }
}

/// A quality partition that can still be refined: the vertices in leaf order and the leaves.
pub(crate) struct Refinable {
    order: Vec<Point>,
    leaves: Leaves,
    tolerance: f64,
}

/// The leaves of a partition in the order of their ranges, which follow one another and cover
/// the whole index array: leaf `i` (cluster `i`) holds `order[start[i]..start[i + 1]]`. Four
/// bytes a leaf, plus its cell when the cells are kept; a leaf's evaluation is not kept, since
/// only the few leaves that coverage splits again need it (it is recomputed for them).
#[derive(Default)]
pub(crate) struct Leaves {
    /// Where each leaf starts, and the end of the last one.
    pub start: Vec<u32>,
    /// The cell of each leaf (empty unless the cells are kept).
    cells: Vec<Cell>,
}

impl Leaves {
    /// Appends the leaf starting at `start` in `cell`.
    fn push(&mut self, start: usize, cell: &Cell, keep_cells: bool) {
        self.start.push(start as u32);
        if keep_cells {
            self.cells.push(*cell);
        }
    }

    /// Appends `other`'s leaves (without its end), their starts shifted by `by`.
    fn append(&mut self, other: Leaves, by: usize) {
        self.start
            .extend(other.start.iter().map(|&s| s + by as u32));
        self.cells.extend(other.cells);
    }

    /// Number of leaves (once the end is pushed).
    fn len(&self) -> usize {
        self.start.len() - 1
    }
}

/// A cell during refinement: its range of the index array and its evaluation (its box
/// travels beside it, and only when the cells are kept is it stored).
#[derive(Clone, Copy, Debug)]
struct Node {
    start: u32,
    end: u32,
    eval: Eval,
}

impl Node {
    fn range(&self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }
}

/// The inputs shared by every step.
#[derive(Clone)]
pub(crate) struct Adaptive<'a> {
    positions: &'a [[f32; 3]],
    weights: &'a [f32],
    heaviest: bool,
    keep_cells: bool,
    cancel: Option<&'a AtomicBool>,
    /// Whether cells are keyed by the complexity goal's surface-error priority (the points
    /// then carry their normals) instead of their displacement.
    surface_priority: bool,
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
    /// `keep_cells`: the partitions list their cells ("show partition").
    pub(crate) fn new(
        positions: &'a [[f32; 3]],
        weights: &'a [f32],
        rep: Representative,
        keep_cells: bool,
        cancel: Option<&'a AtomicBool>,
    ) -> Self {
        Adaptive {
            positions,
            weights,
            heaviest: rep == Representative::Heaviest,
            keep_cells,
            cancel,
            surface_priority: false,
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(AtomicOrdering::Relaxed))
    }

    /// The referenced vertices, grouped by class (one root cell per class), and the root cells.
    /// Vertices are copied with their weights so that every later pass reads memory in order.
    /// `normals` (one per vertex) go into the points and are freed.
    ///
    /// A stable two-way split by class, on every core: each block of vertices counts its
    /// referenced vertices of either class, which fixes where it writes them (class 0 first,
    /// blocks in order), so the order is that of the vertices within each class whatever the
    /// thread count.
    fn roots(
        &self,
        classes: Option<&[u8]>,
        normals: Option<Vec<PackedNormal>>,
    ) -> (Vec<Point>, Vec<Node>) {
        let n = self.positions.len();
        let class = |v: usize| classes.map_or(0, |c| usize::from(c[v] != 0));
        let counts: Vec<[usize; 2]> = blocks::map(n, |r| {
            let mut c = [0; 2];
            r.filter(|&v| self.weights[v] > 0.0)
                .for_each(|v| c[class(v)] += 1);
            c
        });
        let split = counts.iter().map(|c| c[0]).sum::<usize>();
        let total = split + counts.iter().map(|c| c[1]).sum::<usize>();
        let mut order: Vec<Point> = Vec::with_capacity(total);
        {
            // Each block's two destination slices, cut from the front of either class's part.
            let (mut zero, mut one) = order.spare_capacity_mut()[..total].split_at_mut(split);
            let mut jobs = Vec::with_capacity(counts.len());
            for c in &counts {
                let (a, rest) = std::mem::take(&mut zero).split_at_mut(c[0]);
                zero = rest;
                let (b, rest) = std::mem::take(&mut one).split_at_mut(c[1]);
                one = rest;
                jobs.push([a, b]);
            }
            let normal = |v: usize| normals.as_ref().map_or(PackedNormal::NONE, |n| n[v]);
            blocks::ranges(n).zip(jobs).for_each(|(r, out)| {
                let mut at = [0; 2];
                for v in r.filter(|&v| self.weights[v] > 0.0) {
                    let k = class(v);
                    out[k][at[k]].write(Point {
                        p: self.positions[v],
                        w: self.weights[v],
                        id: v as u32,
                        n: normal(v),
                    });
                    at[k] += 1;
                }
            });
        }
        // SAFETY: the blocks' slices tile `0..total` and each block wrote every place of its
        // slices (its counts are the number of points it wrote).
        unsafe { order.set_len(total) };
        drop(normals);
        let roots = [(0, split), (split, total)]
            .into_iter()
            .filter(|(s, e)| e > s)
            .map(|(start, end)| self.node(&order, start, end))
            .collect();
        (order, roots)
    }

    /// The node of the vertices `order[start..end]` (non-empty).
    fn node(&self, order: &[Point], start: usize, end: usize) -> Node {
        Node {
            start: start as u32,
            end: end as u32,
            eval: self.evaluate(&order[start..end]),
        }
    }

    /// Representative, largest displacement and inner box of a non-empty set of vertices.
    /// A large set (the first levels of a split) is summed by blocks on every core, the block
    /// sums added in block order, so the result does not depend on the thread count.
    fn evaluate(&self, verts: &[Point]) -> Eval {
        let acc = if verts.len() > PARALLEL_CELL {
            blocks::map(verts.len(), |r| Acc::of(&verts[r]))
                .iter()
                .fold(Acc::default(), |mut all, part| {
                    all.merge(part);
                    all
                })
        } else {
            Acc::of(verts)
        };
        self.finish_eval(&acc, verts)
    }

    /// Completes an evaluation from a cell's accumulated sums: one more pass over its vertices
    /// (by blocks on every core for a large cell: a maximum does not depend on the order) for
    /// the largest displacement (in f32: the rounding is far below any tolerance, see the
    /// margin in `Prepared::run`).
    fn finish_eval(&self, acc: &Acc, verts: &[Point]) -> Eval {
        let rep: [f32; 3] = if self.heaviest {
            self.positions[acc.best.1 as usize]
        } else {
            acc.sum.map(|s| (s / acc.wsum) as f32)
        };
        let (err2, surface2) = if verts.len() > PARALLEL_CELL {
            blocks::map(verts.len(), |r| self.extremes(rep, &verts[r]))
                .into_iter()
                .fold((0f32, 0f32), |a, b| (a.0.max(b.0), a.1.max(b.1)))
        } else {
            self.extremes(rep, verts)
        };
        let err2 = if self.surface_priority {
            priority(surface2.sqrt(), err2.sqrt()).powi(2)
        } else {
            err2
        };
        let (lo, hi) = (acc.lo, acc.hi);
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .expect("three axes");
        Eval {
            err2,
            at: 0.5 * (lo[axis] + hi[axis]),
            axis: if hi[axis] > lo[axis] {
                axis as u8
            } else {
                NO_CUT
            },
        }
    }

    /// The largest squared displacement of `verts` from `rep`, and (with the surface priority)
    /// the largest squared distance from `rep` to their tangent planes.
    fn extremes(&self, rep: [f32; 3], verts: &[Point]) -> (f32, f32) {
        let delta = |p: [f32; 3]| {
            let d = [rep[0] - p[0], rep[1] - p[1], rep[2] - p[2]];
            (d, d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        };
        let (mut err2, mut surface2) = (0f32, 0f32);
        if self.surface_priority {
            for q in verts {
                let (d, dd) = delta(q.p);
                err2 = err2.max(dd);
                surface2 = surface2.max(plane_distance2(d, dd, q.n.direction()));
            }
        } else {
            for q in verts {
                err2 = err2.max(delta(q.p).1);
            }
        }
        (err2, surface2)
    }

    /// Splits `node` across the largest side of its inner box: partitions its vertices in place
    /// and returns the two children (both non-empty) and the cut (axis, coordinate), or `None`
    /// when its vertices coincide. The partition pass also accumulates both children's sums, so
    /// each child costs one more pass.
    fn split(&self, order: &mut [Point], node: &Node) -> Halves {
        let Eval { at, axis, .. } = node.eval;
        if axis == NO_CUT {
            return None;
        }
        let (axis, mut at) = (usize::from(axis), at);
        let verts = &mut order[node.range()];
        let (mut left_acc, mut right_acc) = (Acc::default(), Acc::default());
        let mut mid = partition_in_place(verts, |q| q.p[axis] < at, &mut left_acc, &mut right_acc);
        if mid == 0 || mid == verts.len() {
            // The midpoint rounded onto an end of the box: split at the median instead.
            mid = verts.len() / 2;
            verts.select_nth_unstable_by(mid, |a, b| a.p[axis].total_cmp(&b.p[axis]));
            at = verts[mid].p[axis];
            (left_acc, right_acc) = (Acc::of(&verts[..mid]), Acc::of(&verts[mid..]));
        }
        let (left, right) = verts.split_at(mid);
        let (le, re) = (
            self.finish_eval(&left_acc, left),
            self.finish_eval(&right_acc, right),
        );
        let mid = node.start + mid as u32;
        Some((
            Node {
                start: node.start,
                end: mid,
                eval: le,
            },
            Node {
                start: mid,
                end: node.end,
                eval: re,
            },
            Cut { axis, at },
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
        let (mut order, roots) = self.roots(classes, None);
        let roots: Vec<(Node, Cell)> = roots.into_iter().map(|n| (n, *bounds)).collect();
        let mut leaves = self.refine_all(&mut order, &roots, tolerance)?;
        leaves.start.push(order.len() as u32);
        Ok(Refinable {
            order,
            leaves,
            tolerance,
        })
    }

    /// The partition of a quality refinement: cluster `i` is its `i`-th leaf.
    pub(crate) fn partition(&self, r: &Refinable) -> Partition {
        self.finish(&r.order, &r.leaves.start, r.leaves.cells.clone())
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
            let c = c as usize;
            let (start, end) = (r.leaves.start[c] as usize, r.leaves.start[c + 1] as usize);
            // A leaf keeps no evaluation: its box (a minimum and maximum, the same whatever the
            // order of its vertices) is measured again.
            let leaf = self.node(&r.order, start, end);
            let cell = r.leaves.cells.get(c).copied().unwrap_or(ANY_CELL);
            if let Some((left, right, cut)) = self.split(&mut r.order, &leaf) {
                split[c] = true;
                let (lcell, rcell) = cut.cells(&cell);
                halves.extend([(left, lcell), (right, rcell)]);
            }
        }
        let count = halves.len() / 2;
        if count > 0 {
            // Both the kept leaves and the refined halves are in range order: merge them.
            let refined = self.refine_all(&mut r.order, &halves, r.tolerance)?;
            let old = std::mem::take(&mut r.leaves);
            let keep = self.keep_cells;
            let mut kept = (0..old.len()).filter(|&c| !split[c]).peekable();
            let mut leaves = Leaves::default();
            leaves
                .start
                .reserve(old.len() + refined.start.len() - count + 1);
            for (i, &start) in refined.start.iter().enumerate() {
                while let Some(k) = kept.next_if(|&k| old.start[k] < start) {
                    leaves.push(
                        old.start[k] as usize,
                        old.cells.get(k).unwrap_or(&ANY_CELL),
                        keep,
                    );
                }
                leaves.push(
                    start as usize,
                    refined.cells.get(i).unwrap_or(&ANY_CELL),
                    keep,
                );
            }
            for k in kept {
                leaves.push(
                    old.start[k] as usize,
                    old.cells.get(k).unwrap_or(&ANY_CELL),
                    keep,
                );
            }
            leaves.start.push(r.order.len() as u32);
            r.leaves = leaves;
        }
        Ok(count)
    }

    /// Refines each of `cells` (disjoint ranges of `order`, sorted by start, with their boxes)
    /// until every resulting cell's displacement is at most `tolerance`; returns the leaves
    /// sorted by start (without the end).
    ///
    /// Refining is *tentative-safe*: splitting a cell only permutes its own range and always
    /// yields the same children, so the input cells stay valid whatever is done with the result.
    fn refine_all(
        &self,
        order: &mut [Point],
        cells: &[(Node, Cell)],
        tolerance: f64,
    ) -> Result<Leaves, Stop> {
        let slices = disjoint_slices(order, cells.iter().map(|(c, _)| c.range()));
        let jobs: Vec<(Node, Cell, &mut [Point])> = cells
            .iter()
            .zip(slices)
            .map(|((c, cell), slice)| (*c, *cell, slice))
            .collect();
        let parts: Vec<Result<Leaves, Stop>> = if jobs.len() > 1 {
            jobs.into_par_iter()
                .with_min_len(64)
                .map(|(c, cell, slice)| self.refine_one(slice, c, cell, tolerance))
                .collect()
        } else {
            jobs.into_iter()
                .map(|(c, cell, slice)| self.refine_one(slice, c, cell, tolerance))
                .collect()
        };
        let mut out = Leaves::default();
        for (p, (c, _)) in parts.into_iter().zip(cells) {
            out.append(p?, c.start as usize);
        }
        Ok(out)
    }

    /// Refines one cell whose vertices are exactly `slice`; its leaves are numbered from the
    /// cell's start.
    fn refine_one(
        &self,
        slice: &mut [Point],
        node: Node,
        cell: Cell,
        tolerance: f64,
    ) -> Result<Leaves, Stop> {
        let mut out = Leaves::default();
        let local = Node {
            start: 0,
            end: node.end - node.start,
            ..node
        };
        self.refine(slice, local, cell, tolerance, &mut out)?;
        Ok(out)
    }

    /// Depth-first refinement of one cell. `order` holds exactly the cell's vertices and
    /// `node` is numbered locally (`node.start == 0`); leaves are appended to `out` in order,
    /// numbered locally too.
    fn refine(
        &self,
        order: &mut [Point],
        node: Node,
        cell: Cell,
        tolerance: f64,
        out: &mut Leaves,
    ) -> Result<(), Stop> {
        if node.eval.err() <= tolerance {
            out.push(0, &cell, self.keep_cells);
            return Ok(());
        }
        if self.cancelled() {
            return Err(Stop::Cancelled);
        }
        let Some((l, r, cut)) = self.split(order, &node) else {
            out.push(0, &cell, self.keep_cells);
            return Ok(());
        };
        let (lcell, rcell) = cut.cells(&cell);
        let mid = l.end;
        let (lo, hi) = order.split_at_mut(mid as usize);
        let r_local = Node {
            start: 0,
            end: r.end - mid,
            ..r
        };
        if (node.end - node.start) as usize > PARALLEL_CELL {
            let (mut left, mut right) = (Leaves::default(), Leaves::default());
            let (a, b) = rayon::join(
                || self.refine(lo, l, lcell, tolerance, &mut left),
                || self.refine(hi, r_local, rcell, tolerance, &mut right),
            );
            a?;
            b?;
            out.append(left, 0);
            out.append(right, mid as usize);
        } else {
            let from = out.start.len();
            self.refine(lo, l, lcell, tolerance, out)?;
            let middle = out.start.len();
            self.refine(hi, r_local, rcell, tolerance, out)?;
            out.start[middle..].iter_mut().for_each(|s| *s += mid);
            debug_assert!(out.start[from..].is_sorted());
        }
        Ok(())
    }

    /// Complexity goal (section 4): splits, one at a time, the cell with the largest
    /// displacement until there are `target` cells. `more` then counts the output vertices
    /// after elimination (cells whose faces all collapse are lost) and asks for that many
    /// further splits; it is given the partition and its leaves (over [`Adaptive::order`]).
    /// Stops early when no cell can be split (all remaining cells hold coincident vertices).
    ///
    /// With `normals` (one per vertex, `feature_priority::vertex_normals`), cells are split by
    /// their surface-error estimate (`feature_priority.rs`) instead of their displacement.
    pub(crate) fn complexity(
        &self,
        classes: Option<&[u8]>,
        bounds: &Cell,
        target: u64,
        normals: Option<Vec<PackedNormal>>,
        mut more: impl FnMut(&Partition, LeafView) -> u64,
    ) -> Result<Partition, Stop> {
        let keyed = Adaptive {
            surface_priority: normals.is_some(),
            ..self.clone()
        };
        let this = &keyed;
        // The leaves live in an arena (`live`, a split cell hands its slot to its left child;
        // `cells` beside it when they are kept); `by_start` lists them in the order of their
        // ranges.
        let (mut order, mut live) = this.roots(classes, normals);
        let mut cells = if this.keep_cells {
            vec![*bounds; live.len()]
        } else {
            Vec::new()
        };
        let mut goal = target as usize;
        loop {
            let mut by_start = this.approach(&mut order, &mut live, &mut cells, goal)?;
            let leaf_cells = if this.keep_cells {
                by_start.iter().map(|&i| cells[i as usize]).collect()
            } else {
                Vec::new()
            };
            // The leaves' starts, in place of their arena indices.
            by_start
                .iter_mut()
                .for_each(|i| *i = live[*i as usize].start);
            by_start.push(order.len() as u32);
            let partition = this.finish(&order, &by_start, leaf_cells);
            let view = LeafView {
                order: &order,
                start: &by_start,
            };
            let extra = more(&partition, view) as usize;
            if extra == 0 || live.iter().all(|n| n.eval.err() <= 0.0) {
                return Ok(partition);
            }
            // Ask for half the shortfall at a time: a split can revive clusters whose faces had
            // all collapsed, so the output may grow by more than the splits added.
            goal = live.len() + extra.div_ceil(2);
        }
    }

    /// Greedy splitting up to `goal` cells. A [`SplitQueue`] holds the cells that can still be
    /// split (displacement above zero) by arena index; returns every leaf's arena index in the
    /// order of its range.
    ///
    /// The cells are split in rounds, so that every core has work: a round takes the cell
    /// with the largest key and every queued cell whose key is at least [`ROUND_SHARE`] of it
    /// (in key order, as many as the goal still allows), and splits them all at once. That is
    /// the one-at-a-time order of section 4 except where a child's key reaches into the round
    /// (children mostly move less than their parent); the rounds depend on the keys alone, not
    /// on the thread count.
    fn approach(
        &self,
        order: &mut [Point],
        live: &mut Vec<Node>,
        cells: &mut Vec<Cell>,
        goal: usize,
    ) -> Result<Vec<u32>, Stop> {
        let top = live.iter().map(|n| n.eval.err()).fold(0.0, f64::max);
        let mut queue = SplitQueue::new(top);
        let mut kept: Vec<u32> = Vec::with_capacity(goal + 1);
        live.reserve_exact(goal.saturating_sub(live.len()));
        for (i, n) in live.iter().enumerate() {
            if n.eval.err() > 0.0 {
                queue.push(ByError(n.eval.err(), i as u32));
            } else {
                kept.push(i as u32);
            }
        }
        let mut round: Vec<u32> = Vec::new();
        while kept.len() + queue.len() < goal {
            if self.cancelled() {
                return Err(Stop::Cancelled);
            }
            // Each split adds one cell: the round is at most the shortfall.
            let room = goal - kept.len() - queue.len();
            round.clear();
            let Some(ByError(largest, first)) = queue.pop() else {
                break;
            };
            round.push(first);
            while round.len() < room
                && let Some(ByError(_, i)) = queue.pop_at_least(largest * ROUND_SHARE)
            {
                round.push(i);
            }
            // A few thousand cells at a time: enough for every core, and the round's
            // bookkeeping stays small next to the points.
            for chunk in round.chunks(ROUND_CHUNK) {
                let split = self.split_round(order, live, chunk);
                for (&i, halves) in chunk.iter().zip(split) {
                    match halves {
                        Some((l, r, cut)) => {
                            live[i as usize] = l;
                            live.push(r);
                            if self.keep_cells {
                                let (lcell, rcell) = cut.cells(&cells[i as usize]);
                                cells[i as usize] = lcell;
                                cells.push(rcell);
                            }
                            for (child, slot) in [(l, i), (r, live.len() as u32 - 1)] {
                                if child.eval.err() > 0.0 {
                                    queue.push(ByError(child.eval.err(), slot));
                                } else {
                                    kept.push(slot);
                                }
                            }
                        }
                        None => kept.push(i),
                    }
                }
            }
        }
        kept.extend(queue.drain().map(|k| k.1));
        kept.sort_unstable_by_key(|&i| live[i as usize].start);
        Ok(kept)
    }

    /// Splits the cells `round` (arena indices) of `live`, in parallel when there are several:
    /// their vertex ranges are disjoint, so each split gets its own slice of `order`. The
    /// halves come back in the order of `round`, with their ranges in `order`'s terms.
    fn split_round(&self, order: &mut [Point], live: &[Node], round: &[u32]) -> Vec<Halves> {
        let points: usize = round.iter().map(|&i| live[i as usize].range().len()).sum();
        if round.len() == 1 || points < PARALLEL_ROUND || blocks::single_thread() {
            // Too little to share out: one after the other (the same splits, so the same
            // result), without the bookkeeping.
            return round
                .iter()
                .map(|&i| self.split(order, &live[i as usize]))
                .collect();
        }
        let mut by_start: Vec<usize> = (0..round.len()).collect();
        by_start.sort_unstable_by_key(|&k| live[round[k] as usize].start);
        let ranges = by_start.iter().map(|&k| live[round[k] as usize].range());
        let slices = disjoint_slices(order, ranges);
        let jobs: Vec<(usize, Node, &mut [Point])> = by_start
            .iter()
            .zip(slices)
            .map(|(&k, slice)| {
                let node = live[round[k] as usize];
                let local = Node {
                    start: 0,
                    end: node.end - node.start,
                    ..node
                };
                (k, local, slice)
            })
            .collect();
        let mut halves: Vec<(usize, Halves)> = jobs
            .into_par_iter()
            .map(|(k, local, slice)| {
                let base = live[round[k] as usize].start;
                let shift = |n: Node| Node {
                    start: n.start + base,
                    end: n.end + base,
                    ..n
                };
                let split = self.split(slice, &local);
                (k, split.map(|(l, r, cut)| (shift(l), shift(r), cut)))
            })
            .collect();
        halves.sort_unstable_by_key(|h| h.0);
        halves.into_iter().map(|h| h.1).collect()
    }

    /// Labels every vertex with its leaf (leaves given by their starts and the end, in order).
    fn finish(&self, order: &[Point], start: &[u32], cells: Vec<Cell>) -> Partition {
        let mut cluster_of = vec![UNUSED; self.positions.len()];
        for (id, w) in start.windows(2).enumerate() {
            for q in &order[w[0] as usize..w[1] as usize] {
                cluster_of[q.id as usize] = id as u32;
            }
        }
        Partition {
            cluster_of,
            clusters: start.len() - 1,
            cells,
        }
    }
}

impl Refinable {
    /// The leaves over the vertex order.
    pub(crate) fn view(&self) -> LeafView<'_> {
        LeafView {
            order: &self.order,
            start: &self.leaves.start,
        }
    }
}

/// The clusters of an adaptive partition as ranges of its vertex order: cluster `i` holds
/// `order[start[i]..start[i + 1]]`. The representatives are placed from it
/// (`cluster_stats::of_points`), with no per-cluster statistics held.
#[derive(Clone, Copy)]
pub(crate) struct LeafView<'a> {
    /// The referenced vertices, in leaf order.
    pub order: &'a [Point],
    /// Where each leaf starts, and the end.
    pub start: &'a [u32],
}

impl LeafView<'_> {
    /// The vertices of cluster `c`.
    pub(crate) fn points(&self, c: usize) -> &[Point] {
        &self.order[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// Where a split cut its cell.
#[derive(Clone, Copy, Debug)]
struct Cut {
    axis: usize,
    at: f32,
}

impl Cut {
    /// The two halves of `cell`.
    fn cells(&self, cell: &Cell) -> (Cell, Cell) {
        let (mut l, mut r) = (*cell, *cell);
        l.max[self.axis] = self.at;
        r.min[self.axis] = self.at;
        (l, r)
    }
}

/// A stand-in for the cell of a leaf when the cells are not kept.
const ANY_CELL: Cell = Cell {
    min: [0.0; 3],
    max: [0.0; 3],
};

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
        self.refill()?;
        let k = self.heap.pop()?;
        self.len -= 1;
        Some(k)
    }

    /// Removes and returns the cell with the largest key if that key is at least `floor`.
    fn pop_at_least(&mut self, floor: f64) -> Option<ByError> {
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
pub(crate) struct Point {
    /// Position.
    pub p: [f32; 3],
    /// Weight.
    pub w: f32,
    /// Vertex index.
    pub id: u32,
    /// Its normal, for the complexity goal's surface priority (none otherwise).
    pub n: PackedNormal,
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

    /// The sums of `points`, added in order.
    fn of(points: &[Point]) -> Acc {
        let mut acc = Acc::default();
        points.iter().for_each(|q| acc.add(q));
        acc
    }

    /// Adds the sums of `other` (taken over other vertices).
    fn merge(&mut self, other: &Acc) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(other.lo[k]);
            self.hi[k] = self.hi[k].max(other.hi[k]);
            self.sum[k] += other.sum[k];
        }
        self.wsum += other.wsum;
        let (w, id) = other.best;
        if w > self.best.0 || (w == self.best.0 && id < self.best.1) {
            self.best = other.best;
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
        let a = Adaptive::new(&p, &w, Representative::Barycenter, true, None);
        let part = a.partition(&a.quality(None, &b, 2.0).unwrap());
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
        let a = Adaptive::new(&p, &w, Representative::Barycenter, false, None);
        let part = a.partition(&a.quality(None, &b, 3.0).unwrap());
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
        let a = Adaptive::new(&p, &w, Representative::Barycenter, true, None);
        let mut r = a.quality(None, &b, 2.0).unwrap();
        let before = a.partition(&r);
        assert_eq!(a.split_clusters(&mut r, &[0, 3]).unwrap(), 2);
        let after = a.partition(&r);
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
        let a = Adaptive::new(&p, &w, Representative::Barycenter, false, None);
        let part = a.complexity(None, &b, 137, None, |_, _| 0).unwrap();
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
        let a = Adaptive::new(&p, &w, Representative::Barycenter, false, None);
        let mut r = a.quality(None, &b, 1e-9).unwrap();
        assert_eq!(a.partition(&r).clusters, 1);
        assert_eq!(a.split_clusters(&mut r, &[0]).unwrap(), 0);
        assert_eq!(
            a.complexity(None, &b, 5, None, |_, _| 1).unwrap().clusters,
            1
        );
    }

    #[test]
    fn hoare_partition_accumulates_each_point_once() {
        let mut v: Vec<Point> = (0..10)
            .map(|i| Point {
                p: [(9 - i) as f32, 0.0, 0.0],
                w: 1.0,
                id: i,
                n: PackedNormal::NONE,
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
