//! Adaptive binary partitions (Belblidia & Perrin, sections 3–5): what both goals share.
//!
//! Both goals start from one cell, the bounding box of the object (section 3), and split a cell
//! in two across the largest side of the *points' inner bounding box* (section 5, figure 6), so
//! empty cells are never split and the cuts follow the points (`kd.rs`). The goals themselves
//! are their own files: the quality goal (section 3) in `adaptive_quality.rs`, the complexity
//! goal (section 4) in `adaptive_complexity.rs`. This file holds the inputs they share
//! ([`Adaptive`]), the root cells, a cell's representative and its exact key, and the
//! partition they read back ([`LeafView`]).
//!
//! The vertices of a cell are a range of one array of 16-byte points that each split
//! partitions in place (a k-d tree build). The split pass gathers the halves' boxes only; the
//! box often decides without looking at the points again (issue 33, design point 3): the
//! representative lies in the box, so a box whose diagonal is within the tolerance moves no
//! vertex farther, and one whose half largest side exceeds it moves some vertex farther. Only
//! the cells in between get the exact pass (weights read by vertex index, the representative,
//! the largest displacement).

use crate::blocks::{self, disjoint_slices};
use crate::feature_priority::{PackedNormal, plane_distance2, priority};
use crate::kd::{Bounds, Point};
use crate::options::Representative;
use crate::partition::{Cell, Partition, UNUSED};
use crate::tangent_key;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering as AtomicOrdering};

/// Cells with more vertices than this are refined in parallel (quality goal) and evaluated
/// by blocks on every core.
pub(crate) const PARALLEL_CELL: usize = 1 << 15;

/// The inputs shared by every step.
#[derive(Clone)]
pub(crate) struct Adaptive<'a> {
    pub(crate) positions: &'a [[f32; 3]],
    pub(crate) weights: &'a [f32],
    pub(crate) heaviest: bool,
    pub(crate) keep_cells: bool,
    pub(crate) cancel: Option<&'a AtomicBool>,
    /// Whether cells are keyed by the complexity goal's surface-error priority
    /// (`feature_priority.rs`; the points then carry their normals) instead of their
    /// displacement.
    pub(crate) surface: bool,
    /// Whether the output's representative is the quadric point: the surface key of a small
    /// cell is then measured from its tangent planes' quadric point (`tangent_key.rs`).
    pub(crate) tangent_key: bool,
}

/// What travels beside each point of a partition (`kd::split_points`): nothing for the quality
/// goal, whose exact passes are few and read the weights by vertex index; the weight and the
/// normal for the complexity goal, which measures every cell it splits: reading them by index
/// cost it 12 % (the gathers miss the cache; torus_1M at 10 %, one thread).
pub(crate) trait Aux: Copy + Send + Sync {
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

/// Nothing beside each of `n` points (no allocation: the unit type has no size).
pub(crate) fn nothing(n: usize) -> Vec<()> {
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

    pub(crate) fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(AtomicOrdering::Relaxed))
    }

    /// The referenced vertices, grouped by class (one root cell per class), and the root cells
    /// with their boxes.
    ///
    /// A stable two-way split by class, on every core: each block of vertices counts its
    /// referenced vertices of either class, which fixes where it writes them (class 0 first,
    /// blocks in order), so the order is that of the vertices within each class whatever the
    /// thread count.
    pub(crate) fn roots(
        &self,
        classes: Option<&[u8]>,
    ) -> (Vec<Point>, Vec<(usize, usize, Bounds)>) {
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
    pub(crate) fn representative<A: Aux>(&self, verts: &[Point], aux: &[A]) -> [f32; 3] {
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
    pub(crate) fn key2<A: Aux>(&self, verts: &[Point], aux: &[A]) -> f32 {
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
    pub(crate) fn extremes<A: Aux>(&self, rep: [f32; 3], verts: &[Point], aux: &[A]) -> (f32, f32) {
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

    /// Labels every vertex with its leaf (leaves given by their starts and the end, in order).
    pub(crate) fn finish(&self, order: &[Point], start: &[u32], cells: Vec<Cell>) -> Partition {
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

/// Points on a line, for the goals' tests: `n` points one apart along x, weight 1, and
/// their cell.
#[cfg(test)]
pub(crate) fn line(n: usize) -> (Vec<[f32; 3]>, Vec<f32>, Cell) {
    let p: Vec<[f32; 3]> = (0..n).map(|i| [i as f32, 0.0, 0.0]).collect();
    let b = Cell {
        min: [0.0; 3],
        max: [(n - 1) as f32, 0.0, 0.0],
    };
    (p, vec![1.0; n], b)
}
