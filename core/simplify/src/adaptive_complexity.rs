//! The complexity goal of the adaptive partitions (Belblidia & Perrin, section 4): the cell
//! with the largest key is split, in rounds (a priority queue, `split_queue.rs`), until the
//! number of cells reaches the target. What both goals share is in `adaptive_partition.rs`.
//!
//! With the displacement as its key, the children enter the queue with the box's bound; the
//! exact key is computed only when a cell could be among the next to split, so leaves that
//! are never split are never measured (issue 33, design point 5). With the surface key
//! (`feature_priority.rs`, what `lib.rs` uses) the bound is the cell's size and the key its
//! sag, so nearly every child would be measured anyway (99.8 % on a 1 M-triangle torus at
//! 10 %): they are measured as they are split, while their points are in cache, and the
//! points carry their weights and normals beside them ([`Carry`]).

use crate::adaptive_partition::{Adaptive, Aux, LeafView, Stop};
use crate::blocks::{self, disjoint_slices};
use crate::feature_priority::PackedNormal;
use crate::kd::{Bounds, Cut, Point, split_points};
use crate::partition::{Cell, Partition};
use crate::split_queue::{ByError, SplitQueue};
use rayon::prelude::*;

/// Rounds with fewer points than this are split on one core (see `Adaptive::split_round`).
const PARALLEL_ROUND: usize = 1 << 14;

/// Cells of a round split together (see `Adaptive::approach`).
const ROUND_CHUNK: usize = 4096;

/// The complexity goal's rounds (see `Adaptive::approach`): a round splits every cell whose
/// key is at least this share of the largest.
const ROUND_SHARE: f64 = 0.9;

/// The margin of the complexity goal's bound key over the box's diagonal: the key
/// (`feature_priority::priority`) is the plane distance (at most the displacement, up to the
/// rounding of f32) plus a share of the displacement.
const BOUND_MARGIN: f64 = (1.0 + feature_priority_share()) * (1.0 + 1e-4);

const fn feature_priority_share() -> f64 {
    crate::feature_priority::DISPLACEMENT_SHARE as f64
}

/// A cell of the complexity goal: its range of the point array, its key and its cut (20
/// bytes; its box is not kept).
#[derive(Clone, Copy, Debug)]
struct Node {
    start: u32,
    end: u32,
    /// The square of the cell's key, as measured (in f32: the key is its root in f64, which
    /// orders exactly as it does) when it is ≥ 0; minus the square of an upper bound of the
    /// key when the cell has not been measured (see [`Node::bounded`]).
    key2: f32,
    /// The coordinate of the cut along `axis`.
    at: f32,
    /// The axis of the box's largest side, or [`NO_CUT`] when the vertices coincide.
    axis: u8,
}

/// [`Node::axis`] of a cell whose vertices coincide.
const NO_CUT: u8 = u8::MAX;

impl Node {
    fn range(&self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }

    /// A cell of `b` not measured yet: its key bounded by the box's diagonal. A cell whose
    /// vertices coincide has the key 0 (it cannot be split), measured.
    fn bounded(start: usize, end: usize, b: &Bounds) -> Node {
        let (key2, cut) = match b.cut() {
            Some(cut) => {
                let bound = f64::from(b.diagonal2()).sqrt() * BOUND_MARGIN;
                // Kept above zero, so an unmeasured cell is always told apart.
                let b2 = ((bound * bound) as f32 * (1.0 + 1e-6)).max(f32::MIN_POSITIVE);
                (-b2, Some(cut))
            }
            None => (0.0, None),
        };
        Node {
            start: start as u32,
            end: end as u32,
            key2,
            at: cut.map_or(0.0, |c| c.at),
            axis: cut.map_or(NO_CUT, |c| c.axis as u8),
        }
    }

    /// Whether the key is measured.
    fn exact(&self) -> bool {
        self.key2 >= 0.0
    }

    /// The key, or its bound.
    fn key(&self) -> f64 {
        f64::from(self.key2.abs()).sqrt()
    }

    fn cut(&self) -> Option<Cut> {
        (self.axis != NO_CUT).then_some(Cut {
            axis: usize::from(self.axis),
            at: self.at,
        })
    }
}

/// A split's two children (both non-empty) and its cut, or `None` when the cell's vertices
/// coincide.
type Halves = Option<(Node, Node, Cut)>;

/// A point's weight and normal, carried beside it by the complexity goal.
#[derive(Clone, Copy, Debug)]
struct Carry {
    w: f32,
    n: PackedNormal,
}

impl Aux for Carry {
    #[inline]
    fn weight(&self, _: &Point, _: &[f32]) -> f32 {
        self.w
    }
    #[inline]
    fn normal(&self) -> PackedNormal {
        self.n
    }
}

impl<'a> Adaptive<'a> {
    /// Complexity goal (section 4): splits the cell with the largest key until there are
    /// `target` cells. `more` then counts the output vertices after elimination (cells whose
    /// faces all collapse are lost) and asks for that many further splits; it is given the
    /// partition and its leaves. Stops early when no cell can be split (all remaining cells
    /// hold coincident vertices).
    ///
    /// The key is the largest displacement, or with `normals` (one per vertex,
    /// `feature_priority::vertex_normals`) the surface-error estimate (`feature_priority.rs`).
    pub(crate) fn complexity(
        &self,
        classes: Option<&[u8]>,
        bounds: &Cell,
        target: u64,
        normals: Option<Vec<PackedNormal>>,
        mut more: impl FnMut(&Partition, LeafView) -> u64,
    ) -> Result<Partition, Stop> {
        let keyed = Adaptive {
            positions: self.positions,
            weights: self.weights,
            heaviest: self.heaviest,
            keep_cells: self.keep_cells,
            cancel: self.cancel,
            surface: normals.is_some(),
            tangent_key: self.tangent_key,
        };
        let this = &keyed;
        // The leaves live in an arena (`live`, a split cell hands its slot to its left child;
        // `cells` beside it when they are kept); `by_start` lists them in the order of their
        // ranges. The roots are measured.
        let (mut order, roots) = this.roots(classes);
        let mut carry: Vec<Carry> = order
            .par_iter()
            .with_min_len(4096)
            .map(|q| Carry {
                w: self.weights[q.id as usize],
                n: normals
                    .as_ref()
                    .map_or(PackedNormal::NONE, |n| n[q.id as usize]),
            })
            .collect();
        drop(normals);
        let mut live: Vec<Node> = roots
            .iter()
            .map(|&(s, e, b)| {
                let mut n = Node::bounded(s, e, &b);
                n.key2 = this.key2(&order[s..e], &carry[s..e]);
                n
            })
            .collect();
        let mut cells = if this.keep_cells {
            vec![*bounds; live.len()]
        } else {
            Vec::new()
        };
        let mut goal = target as usize;
        loop {
            let mut by_start =
                this.approach(&mut order, &mut carry, &mut live, &mut cells, goal)?;
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
                weights: this.weights,
            };
            let extra = more(&partition, view) as usize;
            // An unmeasured cell can be split (its vertices do not coincide); a measured
            // one with the key 0 cannot.
            if extra == 0 || live.iter().all(|n| n.key2 == 0.0) {
                return Ok(partition);
            }
            // Ask for half the shortfall at a time: a split can revive clusters whose faces had
            // all collapsed, so the output may grow by more than the splits added.
            goal = live.len() + extra.div_ceil(2);
        }
    }

    /// Measures the cells `batch` (arena indices) of `live`, on every core when they are
    /// many, and queues them again with their keys (or keeps those that cannot be split).
    fn measure(
        &self,
        order: &[Point],
        carry: &[Carry],
        live: &mut [Node],
        batch: &[u32],
        queue: &mut SplitQueue,
        kept: &mut Vec<u32>,
    ) {
        let points: usize = batch.iter().map(|&i| live[i as usize].range().len()).sum();
        let key = |&i: &u32| {
            let n = live[i as usize];
            if n.exact() {
                n.key2
            } else {
                self.key2(&order[n.range()], &carry[n.range()])
            }
        };
        let keys: Vec<f32> = if batch.len() > 1 && points >= PARALLEL_ROUND {
            batch.par_iter().with_min_len(64).map(key).collect()
        } else {
            batch.iter().map(key).collect()
        };
        for (&i, k2) in batch.iter().zip(keys) {
            let n = &mut live[i as usize];
            n.key2 = k2;
            if n.key() > 0.0 {
                queue.push(ByError(n.key(), i));
            } else {
                kept.push(i);
            }
        }
    }

    /// Greedy splitting up to `goal` cells. A [`SplitQueue`] holds the cells that can still be
    /// split (key above zero, or not measured yet) by arena index; returns every leaf's arena
    /// index in the order of its range.
    ///
    /// The cells are split in rounds, so that every core has work: a round takes the cell
    /// with the largest key and every queued cell whose key is at least [`ROUND_SHARE`] of it
    /// (in key order, as many as the goal still allows), and splits them all at once. That is
    /// the one-at-a-time order of section 4 except where a child's key reaches into the round
    /// (children mostly move less than their parent); the rounds depend on the keys alone, not
    /// on the thread count.
    ///
    /// Children are queued with their boxes' bound (at least their key); a cell is measured
    /// when its bound reaches the top or the round's floor, so every round is made of
    /// measured keys: the same rounds as measuring every child.
    fn approach(
        &self,
        order: &mut [Point],
        carry: &mut [Carry],
        live: &mut Vec<Node>,
        cells: &mut Vec<Cell>,
        goal: usize,
    ) -> Result<Vec<u32>, Stop> {
        let top = live.iter().map(Node::key).fold(0.0, f64::max);
        let mut queue = SplitQueue::new(top);
        let mut kept: Vec<u32> = Vec::with_capacity(goal + 1);
        live.reserve_exact(goal.saturating_sub(live.len()));
        for (i, n) in live.iter().enumerate() {
            if n.key() > 0.0 {
                queue.push(ByError(n.key(), i as u32));
            } else {
                kept.push(i as u32);
            }
        }
        let mut round: Vec<ByError> = Vec::new();
        let mut batch: Vec<u32> = Vec::new();
        let mut measured: Vec<ByError> = Vec::new();
        while kept.len() + queue.len() < goal {
            if self.cancelled() {
                return Err(Stop::Cancelled);
            }
            // The largest measured key: bounds above it are measured first, with every bound
            // near them (they will mostly be needed for this round).
            let largest = loop {
                let Some(first) = queue.pop() else {
                    break None;
                };
                if live[first.1 as usize].exact() {
                    break Some(first);
                }
                batch.clear();
                measured.clear();
                batch.push(first.1);
                while let Some(k) = queue.pop_at_least(first.0 * ROUND_SHARE) {
                    if live[k.1 as usize].exact() {
                        measured.push(k);
                    } else {
                        batch.push(k.1);
                    }
                }
                measured.iter().for_each(|&k| queue.push(k));
                self.measure(order, carry, live, &batch, &mut queue, &mut kept);
            };
            let Some(first) = largest else {
                break;
            };
            // Each split adds one cell: the round is at most the shortfall (`first` is out of
            // the queue).
            let room = goal - kept.len() - queue.len() - 1;
            let floor = first.0 * ROUND_SHARE;
            round.clear();
            round.push(first);
            loop {
                batch.clear();
                while let Some(k) = queue.pop_at_least(floor) {
                    if live[k.1 as usize].exact() {
                        round.push(k);
                    } else {
                        batch.push(k.1);
                    }
                }
                if batch.is_empty() {
                    break;
                }
                self.measure(order, carry, live, &batch, &mut queue, &mut kept);
            }
            // The round in key order, as a queue of measured keys pops it; what the goal
            // leaves out goes back.
            round[1..].sort_unstable_by(|a, b| b.cmp(a));
            let room = room.min(round.len());
            round.drain(room..).for_each(|k| queue.push(k));
            let ids: Vec<u32> = round.iter().map(|k| k.1).collect();
            // A few thousand cells at a time: enough for every core, and the round's
            // bookkeeping stays small next to the points.
            for chunk in ids.chunks(ROUND_CHUNK) {
                let split = self.split_round(order, carry, live, chunk);
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
                                if child.key() > 0.0 {
                                    queue.push(ByError(child.key(), slot));
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

    /// Splits the cell `node` of `order` (its range in `order`'s terms) and returns its
    /// children: with the surface key measured at once, while their points are in cache,
    /// since its box bound is loose (a cell's key is mostly its sag, its box's diagonal its
    /// size): on a 1 M-triangle torus at 10 %, 99.8 % of the children were measured anyway;
    /// with the displacement key unmeasured, queued with their boxes' bounds.
    fn split(&self, order: &mut [Point], carry: &mut [Carry], node: &Node) -> Halves {
        let cut = node.cut()?;
        let (verts, carry) = (&mut order[node.range()], &mut carry[node.range()]);
        let (mid, lb, rb, cut) = split_points(verts, carry, cut);
        let (s, m, e) = (
            node.start as usize,
            node.start as usize + mid,
            node.end as usize,
        );
        let (mut l, mut r) = (Node::bounded(s, m, &lb), Node::bounded(m, e, &rb));
        if self.surface {
            let ((lv, rv), (la, ra)) = (verts.split_at(mid), carry.split_at(mid));
            for (n, v, a) in [(&mut l, lv, la), (&mut r, rv, ra)] {
                if !n.exact() {
                    n.key2 = self.key2(v, a);
                }
            }
        }
        Some((l, r, cut))
    }

    /// Splits the cells `round` (arena indices) of `live`, in parallel when there are several:
    /// their vertex ranges are disjoint, so each split gets its own slice of `order`. The
    /// halves come back in the order of `round`, with their ranges in `order`'s terms.
    fn split_round(
        &self,
        order: &mut [Point],
        carry: &mut [Carry],
        live: &[Node],
        round: &[u32],
    ) -> Vec<Halves> {
        let points: usize = round.iter().map(|&i| live[i as usize].range().len()).sum();
        if round.len() == 1 || points < PARALLEL_ROUND || blocks::single_thread() {
            // Too little to share out: one after the other (the same splits, so the same
            // result), without the bookkeeping.
            return round
                .iter()
                .map(|&i| self.split(order, carry, &live[i as usize]))
                .collect();
        }
        let mut by_start: Vec<usize> = (0..round.len()).collect();
        by_start.sort_unstable_by_key(|&k| live[round[k] as usize].start);
        let ranges = by_start.iter().map(|&k| live[round[k] as usize].range());
        let slices = disjoint_slices(order, ranges.clone());
        let carried = disjoint_slices(carry, ranges);
        let jobs: Vec<(usize, Node, &mut [Point], &mut [Carry])> = by_start
            .iter()
            .zip(slices)
            .zip(carried)
            .map(|((&k, slice), carried)| {
                let node = live[round[k] as usize];
                let local = Node {
                    start: 0,
                    end: node.end - node.start,
                    ..node
                };
                (k, local, slice, carried)
            })
            .collect();
        let mut halves: Vec<(usize, Halves)> = jobs
            .into_par_iter()
            .map(|(k, local, slice, carried)| {
                let base = live[round[k] as usize].start;
                let shift = |n: Node| Node {
                    start: n.start + base,
                    end: n.end + base,
                    ..n
                };
                let split = self.split(slice, carried, &local);
                (k, split.map(|(l, r, cut)| (shift(l), shift(r), cut)))
            })
            .collect();
        halves.sort_unstable_by_key(|h| h.0);
        halves.into_iter().map(|h| h.1).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adaptive_partition::{line, nothing};
    use crate::options::Representative;

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
    fn lazy_keys_bound_the_measured_ones() {
        // Random points in a box: every child's bound is at least its measured key.
        let n = 4000;
        let mut x = 12345u64;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let p: Vec<[f32; 3]> = (0..n).map(|_| [rnd(), rnd() * 0.5, rnd() * 0.1]).collect();
        let w: Vec<f32> = (0..n).map(|_| 0.5 + rnd()).collect();
        let normals: Vec<PackedNormal> = (0..n)
            .map(|i| {
                if i % 7 == 0 {
                    PackedNormal::NONE
                } else {
                    PackedNormal::pack([rnd() - 0.5, rnd() - 0.5, 1.0])
                }
            })
            .collect();
        for surface in [false, true] {
            let a = Adaptive {
                surface,
                ..Adaptive::new(&p, &w, Representative::Barycenter, false, None)
            };
            let (mut order, roots) = a.roots(None);
            let mut carry: Vec<Carry> = order
                .iter()
                .map(|q| Carry {
                    w: w[q.id as usize],
                    n: normals[q.id as usize],
                })
                .collect();
            let (s, e, b) = roots[0];
            let mut stack = vec![Node::bounded(s, e, &b)];
            let mut checked = 0;
            while let Some(node) = stack.pop() {
                let r = node.range();
                let key = f64::from(a.key2(&order[r.clone()], &carry[r])).sqrt();
                assert!(key <= node.key(), "{key} > {}", node.key());
                checked += 1;
                // Measured as the goal measures them: by the weights carried, and by index.
                let by_index = a.key2(&order[node.range()], &nothing(node.range().len()));
                if !surface {
                    assert_eq!(
                        by_index.to_bits(),
                        a.key2(&order[node.range()], &carry[node.range()]).to_bits()
                    );
                }
                if let Some((mut l, mut r, _)) = a.split(&mut order, &mut carry, &node) {
                    // Unmeasured children, for the bound to be checked.
                    for c in [&mut l, &mut r] {
                        if c.key2 > 0.0 {
                            let (s, e) = (c.start as usize, c.end as usize);
                            *c = Node::bounded(s, e, &Bounds::of(&order[s..e]));
                        }
                    }
                    stack.extend([l, r]);
                }
            }
            assert!(checked > n);
        }
    }
}
