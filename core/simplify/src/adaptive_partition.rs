//! Adaptive binary partitions (Belblidia & Perrin, sections 3–5).
//!
//! Both goals start from one cell, the bounding box of the object (section 3), and split a cell
//! in two across the largest side of the *points' inner bounding box* (section 5, figure 6), so
//! empty cells are never split and the cuts follow the points (`kd.rs`):
//!
//! - **quality goal** (section 3): a cell whose largest vertex displacement to its
//!   representative exceeds the tolerance is split, recursively, until none does. Every vertex
//!   then lies within the tolerance of its representative. Beyond the paper, named cells can be
//!   split further ([`Adaptive::split_clusters`]) until the surfaces, not only the vertices, are
//!   within the tolerance (`coverage.rs`).
//! - **complexity goal** (section 4): the cell with the largest key is split, in rounds (a
//!   priority queue, `split_queue.rs`), until the number of cells reaches the target.
//!
//! The vertices of a cell are a range of one array of 16-byte points that each split
//! partitions in place (a k-d tree build). The split pass gathers the halves' boxes only; the
//! box often decides without looking at the points again (issue 33, design point 3): the
//! representative lies in the box, so a box whose diagonal is within the tolerance moves no
//! vertex farther, and one whose half largest side exceeds it moves some vertex farther. Only
//! the cells in between get the exact pass (weights read by vertex index, the representative,
//! the largest displacement). With the displacement as its key, the complexity goal's children
//! enter its queue with the box's bound; the exact key is computed only when a cell could be
//! among the next to split, so leaves that are never split are never measured (design point
//! 5). With the surface key (`feature_priority.rs`, what `lib.rs` uses) the bound is the
//! cell's size and the key its sag, so nearly every child would be measured anyway (99.8 % on
//! a 1 M-triangle torus at 10 %): they are measured as they are split, while their points
//! are in cache, and the points carry their weights and normals beside them (`Carry`).

use crate::blocks::{self, disjoint_slices};
use crate::feature_priority::{PackedNormal, plane_distance2, priority};
use crate::kd::{Bounds, Cut, Point, split_points};
use crate::options::Representative;
use crate::partition::{Cell, Partition, UNUSED};
use crate::split_queue::{ByError, SplitQueue};
use crate::tangent_key;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering as AtomicOrdering};

/// Cells with more vertices than this are refined in parallel (quality goal) and evaluated
/// by blocks on every core.
const PARALLEL_CELL: usize = 1 << 15;

/// Rounds with fewer points than this are split on one core (see `Adaptive::split_round`).
const PARALLEL_ROUND: usize = 1 << 14;

/// Cells of a round split together (see `Adaptive::approach`).
const ROUND_CHUNK: usize = 4096;

/// The complexity goal's rounds (see `Adaptive::approach`): a round splits every cell whose
/// key is at least this share of the largest.
const ROUND_SHARE: f64 = 0.9;

/// The margin by which half a box's largest side must exceed the tolerance for the cell to
/// split without its exact pass: the displacement is measured in f32, a few ulps below the
/// exact distance at worst.
const SURE_SPLIT: f64 = 1.0 - 1.0 / (1u64 << 20) as f64;

/// The margin of the complexity goal's bound key over the box's diagonal: the key
/// (`feature_priority::priority`) is the plane distance (at most the displacement, up to the
/// rounding of f32) plus a share of the displacement.
const BOUND_MARGIN: f64 = (1.0 + feature_priority_share()) * (1.0 + 1e-4);

const fn feature_priority_share() -> f64 {
    crate::feature_priority::DISPLACEMENT_SHARE as f64
}

/// A quality partition that can still be refined: the vertices in leaf order and the leaves.
pub(crate) struct Refinable {
    order: Vec<Point>,
    leaves: Leaves,
    tolerance: f64,
}

/// The leaves of a partition in the order of their ranges, which follow one another and cover
/// the whole index array: leaf `i` (cluster `i`) holds `order[start[i]..start[i + 1]]`. Four
/// bytes a leaf, plus its cell when the cells are kept.
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

/// The inputs shared by every step.
#[derive(Clone)]
pub(crate) struct Adaptive<'a> {
    positions: &'a [[f32; 3]],
    weights: &'a [f32],
    heaviest: bool,
    keep_cells: bool,
    cancel: Option<&'a AtomicBool>,
    /// Whether cells are keyed by the complexity goal's surface-error priority
    /// (`feature_priority.rs`; the points then carry their normals) instead of their
    /// displacement.
    surface: bool,
    /// Whether the output's representative is the quadric point: the surface key of a small
    /// cell is then measured from its tangent planes' quadric point (`tangent_key.rs`).
    tangent_key: bool,
}

/// What travels beside each point of a partition (`kd::split_points`): nothing for the quality
/// goal, whose exact passes are few and read the weights by vertex index; the weight and the
/// normal for the complexity goal, which measures every cell it splits: reading them by index
/// cost it 12 % (the gathers miss the cache; torus_1M at 10 %, one thread).
trait Aux: Copy + Send + Sync {
    /// The weight of `q`.
    fn weight(&self, q: &Point, weights: &[f32]) -> f32;
    /// The normal of `q` (none when not carried).
    fn normal(&self) -> PackedNormal;
}

impl Aux for () {
    #[inline]
    fn weight(&self, q: &Point, weights: &[f32]) -> f32 {
        weights[q.id as usize]
    }
    #[inline]
    fn normal(&self) -> PackedNormal {
        PackedNormal::NONE
    }
}

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

/// Nothing beside each of `n` points (no allocation: the unit type has no size).
fn nothing(n: usize) -> Vec<()> {
    vec![(); n]
}

/// Why refinement stopped early.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Stop {
    /// Cancelled from outside.
    Cancelled,
}

/// Running sums of the exact pass: weighted position sum, heaviest vertex.
#[derive(Clone, Copy, Debug)]
struct Sums {
    sum: [f64; 3],
    wsum: f64,
    best: (f32, u32),
}

impl Sums {
    const EMPTY: Sums = Sums {
        sum: [0.0; 3],
        wsum: 0.0,
        best: (f32::NEG_INFINITY, u32::MAX),
    };

    /// The sums of `points`, in order.
    fn of<A: Aux>(points: &[Point], aux: &[A], weights: &[f32]) -> Sums {
        let mut s = Sums::EMPTY;
        for (q, a) in points.iter().zip(aux) {
            let w = a.weight(q, weights);
            for k in 0..3 {
                s.sum[k] += f64::from(w) * f64::from(q.p[k]);
            }
            s.wsum += f64::from(w);
            s.take_best(w, q.id);
        }
        s
    }

    /// Ties go to the lowest vertex index, so results do not depend on order.
    #[inline]
    fn take_best(&mut self, w: f32, id: u32) {
        if w > self.best.0 || (w == self.best.0 && id < self.best.1) {
            self.best = (w, id);
        }
    }

    fn merge(mut self, o: &Sums) -> Sums {
        for k in 0..3 {
            self.sum[k] += o.sum[k];
        }
        self.wsum += o.wsum;
        self.take_best(o.best.0, o.best.1);
        self
    }
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
            surface: false,
            tangent_key: rep == Representative::Quadric,
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(AtomicOrdering::Relaxed))
    }

    /// The referenced vertices, grouped by class (one root cell per class), and the root cells
    /// with their boxes.
    ///
    /// A stable two-way split by class, on every core: each block of vertices counts its
    /// referenced vertices of either class, which fixes where it writes them (class 0 first,
    /// blocks in order), so the order is that of the vertices within each class whatever the
    /// thread count.
    fn roots(&self, classes: Option<&[u8]>) -> (Vec<Point>, Vec<(usize, usize, Bounds)>) {
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
        let boxes: Vec<[Bounds; 2]> = {
            // Each block's two destination slices, cut from the front of either class's part.
            let (zero, one) = order.spare_capacity_mut()[..total].split_at_mut(split);
            let zero = disjoint_slices(zero, blocks::consecutive(counts.iter().map(|c| c[0])));
            let one = disjoint_slices(one, blocks::consecutive(counts.iter().map(|c| c[1])));
            let jobs: Vec<_> = zero.into_iter().zip(one).map(|(a, b)| [a, b]).collect();
            blocks::ranges(n)
                .zip(jobs)
                .map(|(r, out)| {
                    let mut at = [0; 2];
                    let mut b = [Bounds::EMPTY; 2];
                    for v in r.filter(|&v| self.weights[v] > 0.0) {
                        let k = class(v);
                        let p = self.positions[v];
                        out[k][at[k]].write(Point { p, id: v as u32 });
                        b[k].add(&p);
                        at[k] += 1;
                    }
                    b
                })
                .collect()
        };
        // SAFETY: the blocks' slices tile `0..total` and each block wrote every place of its
        // slices (its counts are the number of points it wrote).
        unsafe { order.set_len(total) };
        let mut b = [Bounds::EMPTY; 2];
        for part in &boxes {
            b[0].merge(&part[0]);
            b[1].merge(&part[1]);
        }
        let roots = [(0, split, b[0]), (split, total, b[1])]
            .into_iter()
            .filter(|(s, e, _)| e > s)
            .collect();
        (order, roots)
    }

    /// The representative of a non-empty set of vertices. A large set (the first levels of a
    /// split) is summed by blocks on every core, the block sums added in block order, so the
    /// result does not depend on the thread count.
    fn representative<A: Aux>(&self, verts: &[Point], aux: &[A]) -> [f32; 3] {
        let s = if verts.len() > PARALLEL_CELL {
            blocks::map(verts.len(), |r| {
                Sums::of(&verts[r.clone()], &aux[r], self.weights)
            })
            .iter()
            .fold(Sums::EMPTY, Sums::merge)
        } else {
            Sums::of(verts, aux, self.weights)
        };
        if self.heaviest {
            self.positions[s.best.1 as usize]
        } else {
            s.sum.map(|x| (x / s.wsum) as f32)
        }
    }

    /// The exact pass: the square of the cell's key — its largest displacement (in f32: the
    /// rounding is far below any tolerance, see the margin in `Prepared::run`), or with the
    /// normals the square of `feature_priority::priority` (zero exactly when the displacement
    /// is). A large cell is measured by blocks on every core (a maximum does not depend on
    /// the order).
    fn key2<A: Aux>(&self, verts: &[Point], aux: &[A]) -> f32 {
        if self.surface && self.tangent_key && verts.len() <= tangent_key::SMALL_CELL {
            return tangent_key::key2(verts, |i| {
                (aux[i].weight(&verts[i], self.weights), aux[i].normal())
            });
        }
        let rep = self.representative(verts, aux);
        let (err2, surface2) = if verts.len() > PARALLEL_CELL {
            blocks::map(verts.len(), |r| {
                self.extremes(rep, &verts[r.clone()], &aux[r])
            })
            .into_iter()
            .fold((0f32, 0f32), |a, b| (a.0.max(b.0), a.1.max(b.1)))
        } else {
            self.extremes(rep, verts, aux)
        };
        if self.surface {
            priority(surface2.sqrt(), err2.sqrt()).powi(2)
        } else {
            err2
        }
    }

    /// The largest squared displacement of `verts` from `rep`, and (with the normals) the
    /// largest squared distance from `rep` to their tangent planes.
    fn extremes<A: Aux>(&self, rep: [f32; 3], verts: &[Point], aux: &[A]) -> (f32, f32) {
        let delta = |p: [f32; 3]| {
            let d = [rep[0] - p[0], rep[1] - p[1], rep[2] - p[2]];
            (d, d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        };
        let (mut err2, mut surface2) = (0f32, 0f32);
        if self.surface {
            for (q, a) in verts.iter().zip(aux) {
                let (d, dd) = delta(q.p);
                err2 = err2.max(dd);
                surface2 = surface2.max(plane_distance2(d, dd, a.normal().direction()));
            }
        } else {
            for q in verts {
                err2 = err2.max(delta(q.p).1);
            }
        }
        (err2, surface2)
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
        let (mut order, roots) = self.roots(classes);
        let roots: Vec<Half> = roots
            .into_iter()
            .map(|(s, e, b)| Half {
                range: s..e,
                b,
                cell: *bounds,
            })
            .collect();
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
            // A leaf keeps no box: it is measured again (a minimum and maximum, the same
            // whatever the order of its vertices).
            let verts = &mut r.order[start..end];
            let cell = r.leaves.cells.get(c).copied().unwrap_or(ANY_CELL);
            if let Some(cut) = Bounds::of(verts).cut() {
                let (mid, lb, rb, cut) = split_points(verts, &mut nothing(end - start), cut);
                split[c] = true;
                let (lcell, rcell) = cut.cells(&cell);
                halves.extend([
                    Half {
                        range: start..start + mid,
                        b: lb,
                        cell: lcell,
                    },
                    Half {
                        range: start + mid..end,
                        b: rb,
                        cell: rcell,
                    },
                ]);
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

    /// Refines each of `cells` (disjoint ranges of `order`, sorted by start) until every
    /// resulting cell's displacement is at most `tolerance`; returns the leaves sorted by
    /// start (without the end).
    ///
    /// Refining is *tentative-safe*: splitting a cell only permutes its own range and always
    /// yields the same children, so the input cells stay valid whatever is done with the result.
    fn refine_all(
        &self,
        order: &mut [Point],
        cells: &[Half],
        tolerance: f64,
    ) -> Result<Leaves, Stop> {
        let slices = disjoint_slices(order, cells.iter().map(|h| h.range.clone()));
        let jobs: Vec<(&Half, &mut [Point])> = cells.iter().zip(slices).collect();
        let refine_one = |(h, slice): (&Half, &mut [Point])| {
            let mut out = Leaves::default();
            self.refine(slice, &h.b, h.cell, tolerance, &mut out)
                .map(|()| out)
        };
        let parts: Vec<Result<Leaves, Stop>> = if jobs.len() > 1 {
            jobs.into_par_iter()
                .with_min_len(64)
                .map(refine_one)
                .collect()
        } else {
            jobs.into_iter().map(refine_one).collect()
        };
        let mut out = Leaves::default();
        for (p, h) in parts.into_iter().zip(cells) {
            out.append(p?, h.range.start);
        }
        Ok(out)
    }

    /// Depth-first refinement of one cell whose vertices are exactly `order`, with their box
    /// `b`; leaves are appended to `out` in order, numbered from the cell's start.
    ///
    /// The box decides most cells without a pass over their vertices: the representative (a
    /// weighted mean or a vertex) lies in the box, so no vertex moves farther than its
    /// diagonal (computed as the displacements are, each rounding monotone, so this holds to
    /// the bit), and some vertex moves at least half its largest side. Only between the two
    /// is the displacement measured: the same decisions, so the same cuts, as measuring
    /// every cell.
    fn refine(
        &self,
        order: &mut [Point],
        b: &Bounds,
        cell: Cell,
        tolerance: f64,
        out: &mut Leaves,
    ) -> Result<(), Stop> {
        let Some(cut) = b.cut() else {
            // The vertices coincide: nothing moves.
            out.push(0, &cell, self.keep_cells);
            return Ok(());
        };
        let within = f64::from(b.diagonal2()).sqrt() <= tolerance
            || (b.half_largest_side() * SURE_SPLIT <= tolerance
                && f64::from(self.key2(order, &nothing(order.len()))).sqrt() <= tolerance);
        if within {
            out.push(0, &cell, self.keep_cells);
            return Ok(());
        }
        if self.cancelled() {
            return Err(Stop::Cancelled);
        }
        let parallel = order.len() > PARALLEL_CELL;
        let (mid, lb, rb, cut) = split_points(order, &mut nothing(order.len()), cut);
        let (lcell, rcell) = cut.cells(&cell);
        let (lo, hi) = order.split_at_mut(mid);
        if parallel {
            let (mut left, mut right) = (Leaves::default(), Leaves::default());
            let (a, b) = rayon::join(
                || self.refine(lo, &lb, lcell, tolerance, &mut left),
                || self.refine(hi, &rb, rcell, tolerance, &mut right),
            );
            a?;
            b?;
            out.append(left, 0);
            out.append(right, mid);
        } else {
            let from = out.start.len();
            self.refine(lo, &lb, lcell, tolerance, out)?;
            let middle = out.start.len();
            self.refine(hi, &rb, rcell, tolerance, out)?;
            out.start[middle..]
                .iter_mut()
                .for_each(|s| *s += mid as u32);
            debug_assert!(out.start[from..].is_sorted());
        }
        Ok(())
    }

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

/// A cell to refine (quality goal): its range of the point array, its points' box and its
/// cell.
struct Half {
    range: std::ops::Range<usize>,
    b: Bounds,
    cell: Cell,
}

impl Refinable {
    /// The leaves over the vertex order.
    pub(crate) fn view<'a>(&'a self, weights: &'a [f32]) -> LeafView<'a> {
        LeafView {
            order: &self.order,
            start: &self.leaves.start,
            weights,
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
    /// Every vertex's weight, by index.
    pub weights: &'a [f32],
}

impl<'a> LeafView<'a> {
    /// The vertices of cluster `c`.
    pub(crate) fn points(&self, c: usize) -> LeafPoints<'a> {
        LeafPoints {
            points: &self.order[self.start[c] as usize..self.start[c + 1] as usize],
            weights: self.weights,
        }
    }
}

/// The vertices of one cluster, with the weights their indices read (the points carry none).
#[derive(Clone, Copy)]
pub(crate) struct LeafPoints<'a> {
    /// The vertices.
    pub points: &'a [Point],
    /// Every vertex's weight, by index.
    pub weights: &'a [f32],
}

impl std::ops::Deref for LeafPoints<'_> {
    type Target = [Point];

    fn deref(&self) -> &[Point] {
        self.points
    }
}

/// A stand-in for the cell of a leaf when the cells are not kept.
const ANY_CELL: Cell = Cell {
    min: [0.0; 3],
    max: [0.0; 3],
};

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
