//! The quality goal of the adaptive partitions (Belblidia & Perrin, section 3): a cell whose
//! largest vertex displacement to its representative exceeds the tolerance is split,
//! recursively, until none does. Every vertex then lies within the tolerance of its
//! representative. Beyond the paper, named cells can be split further
//! ([`Adaptive::split_clusters`]) until the surfaces, not only the vertices, are within the
//! tolerance (`coverage.rs`). What both goals share is in `adaptive_partition.rs`.

use crate::adaptive_partition::{Adaptive, LeafView, PARALLEL_CELL, Stop, nothing};
use crate::blocks::disjoint_slices;
use crate::kd::{Bounds, Point, split_points};
use crate::partition::{Cell, Partition};
use rayon::prelude::*;

/// The margin by which half a box's largest side must exceed the tolerance for the cell to
/// split without its exact pass: the displacement is measured in f32, a few ulps below the
/// exact distance at worst.
const SURE_SPLIT: f64 = 1.0 - 1.0 / (1u64 << 20) as f64;

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

/// A stand-in for the cell of a leaf when the cells are not kept.
const ANY_CELL: Cell = Cell {
    min: [0.0; 3],
    max: [0.0; 3],
};

impl<'a> Adaptive<'a> {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adaptive_partition::line;
    use crate::options::Representative;

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
}
