//! Adaptive binary partitions (Belblidia & Perrin, sections 3–5).
//!
//! Both goals start from one cell, the bounding box of the object (section 3), and split a cell
//! in two across the largest side of the *points' inner bounding box* (section 5, figure 6), so
//! empty cells are never split and the cuts follow the points:
//!
//! - **quality goal** (section 3): a cell whose largest vertex displacement to its
//!   representative exceeds the tolerance is split, recursively, until none does. Every vertex
//!   then lies within the tolerance of its representative.
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
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut sum = [0f64; 3];
        let mut wsum = 0f64;
        let mut best = (f32::NEG_INFINITY, u32::MAX);
        for &Point { p, w, id: v } in verts {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
                sum[k] += f64::from(w) * f64::from(p[k]);
            }
            wsum += f64::from(w);
            // Ties go to the lowest vertex index, so results do not depend on order.
            if w > best.0 || (w == best.0 && v < best.1) {
                best = (w, v);
            }
        }
        let rep = if self.heaviest {
            self.positions[best.1 as usize].map(f64::from)
        } else {
            sum.map(|s| s / wsum)
        };
        let mut err2 = 0f64;
        for &Point { p, .. } in verts {
            let d2: f64 = (0..3).map(|k| (f64::from(p[k]) - rep[k]).powi(2)).sum();
            err2 = err2.max(d2);
        }
        Eval {
            err: err2.sqrt(),
            lo,
            hi,
        }
    }

    /// Splits `node` across the largest side of its inner box: partitions its vertices in place
    /// and returns the two children (both non-empty), or `None` when its vertices coincide.
    fn split(&self, order: &mut [Point], node: &Node) -> Option<(Node, Node)> {
        let Eval { lo, hi, .. } = node.eval;
        let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))?;
        if hi[axis] <= lo[axis] {
            return None;
        }
        let verts = &mut order[node.start..node.end];
        let mut at = 0.5 * (lo[axis] + hi[axis]);
        let mut mid = partition_in_place(verts, |q| q.p[axis] < at);
        if mid == 0 || mid == verts.len() {
            // The midpoint rounded onto an end of the box: split at the median instead.
            mid = verts.len() / 2;
            verts.select_nth_unstable_by(mid, |a, b| a.p[axis].total_cmp(&b.p[axis]));
            at = verts[mid].p[axis];
        }
        let (left, right) = verts.split_at(mid);
        let mut lcell = node.cell;
        let mut rcell = node.cell;
        lcell.max[axis] = at;
        rcell.min[axis] = at;
        let (le, re) = (self.evaluate(left), self.evaluate(right));
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
    /// representative.
    pub(crate) fn quality(
        &self,
        classes: Option<&[u8]>,
        bounds: &Cell,
        tolerance: f64,
        keep_cells: bool,
    ) -> Result<Partition, Stop> {
        let (mut order, roots) = self.roots(classes, bounds);
        let mut leaves = Vec::new();
        let mut rest = &mut order[..];
        let mut consumed = 0;
        for root in roots {
            let (mine, tail) = rest.split_at_mut(root.end - consumed);
            consumed = root.end;
            rest = tail;
            let local = Node {
                start: 0,
                end: root.end - root.start,
                ..root
            };
            let mut found = self.refine(mine, local, tolerance)?;
            for leaf in &mut found {
                leaf.start += root.start;
                leaf.end += root.start;
            }
            leaves.extend(found);
        }
        Ok(self.finish(&order, &leaves, keep_cells))
    }

    /// Depth-first refinement of one cell. `order` holds exactly the cell's vertices and
    /// `node` is numbered locally (`node.start == 0`); so are the leaves returned.
    fn refine(&self, order: &mut [Point], node: Node, tolerance: f64) -> Result<Vec<Node>, Stop> {
        if self.cancelled() {
            return Err(Stop::Cancelled);
        }
        if node.eval.err <= tolerance {
            return Ok(vec![node]);
        }
        let Some((l, r)) = self.split(order, &node) else {
            return Ok(vec![node]);
        };
        let mid = l.end;
        let (lo, hi) = order.split_at_mut(mid);
        let r_local = Node {
            start: 0,
            end: r.end - mid,
            ..r
        };
        let (left, right) = if order_len(&node) > PARALLEL_CELL {
            rayon::join(
                || self.refine(lo, l, tolerance),
                || self.refine(hi, r_local, tolerance),
            )
        } else {
            (
                self.refine(lo, l, tolerance),
                self.refine(hi, r_local, tolerance),
            )
        };
        let mut out = left?;
        out.extend(right?.into_iter().map(|n| Node {
            start: n.start + mid,
            end: n.end + mid,
            ..n
        }));
        Ok(out)
    }

    /// Complexity goal: splits the cell with the largest displacement until there are
    /// `target` cells, then lets `more` ask for further splits (the caller counts the output
    /// vertices after elimination, which can be fewer than the cells). Stops early when no cell
    /// can be split (all remaining cells hold coincident vertices).
    pub(crate) fn complexity(
        &self,
        classes: Option<&[u8]>,
        bounds: &Cell,
        target: u64,
        keep_cells: bool,
        mut more: impl FnMut(&Partition) -> u64,
    ) -> Result<Partition, Stop> {
        let (mut order, roots) = self.roots(classes, bounds);
        // Nodes live in an arena; the heap orders small (error, index) keys, so its sifting
        // moves 16 bytes, not whole nodes.
        let mut nodes: Vec<Node> = roots;
        let mut heap: BinaryHeap<ByError> = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| ByError(n.eval.err, i as u32))
            .collect();
        let mut done: Vec<u32> = Vec::new();
        let mut goal = target;
        loop {
            while (heap.len() + done.len()) < goal as usize {
                if self.cancelled() {
                    return Err(Stop::Cancelled);
                }
                let Some(ByError(err, i)) = heap.pop() else {
                    break;
                };
                let node = nodes[i as usize];
                let children = if err > 0.0 {
                    self.split(&mut order, &node)
                } else {
                    None
                };
                match children {
                    Some((l, r)) => {
                        for child in [l, r] {
                            heap.push(ByError(child.eval.err, nodes.len() as u32));
                            nodes.push(child);
                        }
                    }
                    None => done.push(i),
                }
            }
            let mut leaves: Vec<Node> = done
                .iter()
                .chain(heap.iter().map(|k| &k.1))
                .map(|&i| nodes[i as usize])
                .collect();
            leaves.sort_unstable_by_key(|n| n.start);
            let partition = self.finish(&order, &leaves, keep_cells);
            let extra = more(&partition);
            if extra == 0 || heap.iter().all(|k| k.0 <= 0.0) {
                return Ok(partition);
            }
            goal = (heap.len() + done.len()) as u64 + extra;
        }
    }

    /// Numbers the leaves in order of their ranges and labels every vertex with its cluster.
    fn finish(&self, order: &[Point], leaves: &[Node], keep_cells: bool) -> Partition {
        let mut cluster_of = vec![UNUSED; self.positions.len()];
        for (id, leaf) in leaves.iter().enumerate() {
            for q in &order[leaf.start..leaf.end] {
                cluster_of[q.id as usize] = id as u32;
            }
        }
        let cells = if keep_cells {
            leaves.iter().map(|l| l.cell).collect()
        } else {
            Vec::new()
        };
        Partition {
            cluster_of,
            clusters: leaves.len(),
            cells,
        }
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

fn order_len(n: &Node) -> usize {
    n.end - n.start
}

/// A referenced vertex as the partition handles it: position, weight and vertex index.
#[derive(Clone, Copy, Debug)]
struct Point {
    p: [f32; 3],
    w: f32,
    id: u32,
}

/// Moves the elements satisfying `pred` to the front (Hoare's two-pointer scheme: each element
/// moves at most once); returns how many there are.
fn partition_in_place(v: &mut [Point], pred: impl Fn(&Point) -> bool) -> usize {
    let (mut i, mut j) = (0, v.len());
    loop {
        while i < j && pred(&v[i]) {
            i += 1;
        }
        while i < j && !pred(&v[j - 1]) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        v.swap(i, j - 1);
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
        let part = a.quality(None, &b, 2.0, true).unwrap();
        let mut sum = vec![[0f64; 2]; part.clusters];
        for (v, &c) in part.cluster_of.iter().enumerate() {
            sum[c as usize][0] += p[v][0] as f64;
            sum[c as usize][1] += 1.0;
        }
        for (v, &c) in part.cluster_of.iter().enumerate() {
            let rep = sum[c as usize][0] / sum[c as usize][1];
            assert!((p[v][0] as f64 - rep).abs() <= 2.0);
        }
        // 100 points 1 apart, clusters at most 5 wide: at least 20 clusters, and the split
        // never makes clusters smaller than needed by more than a factor of 2.
        assert!((20..=50).contains(&part.clusters), "{}", part.clusters);
        assert_eq!(part.cells.len(), part.clusters);
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
        assert_eq!(a.quality(None, &b, 1e-9, false).unwrap().clusters, 1);
        assert_eq!(a.complexity(None, &b, 5, false, |_| 1).unwrap().clusters, 1);
    }
}
