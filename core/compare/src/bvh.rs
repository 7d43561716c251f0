//! A bounding-volume hierarchy over triangles for exact nearest-point queries.
//!
//! Layout: a binary tree whose nodes hold the boxes of *both* children (one 64-byte cache
//! line per node), so one visit loads both boxes and measures them together (two `f64` lanes),
//! leaves cost no node visit of their own, and a pushed sibling carries its box distance for
//! a free re-check when popped. Nodes are stored depth-first with children at relative
//! offsets, so subtrees built in parallel are concatenated without any index fix-up.
//! Triangles are copied into leaf order (three `f32` corners each), one contiguous read per
//! leaf.
//!
//! Build: binned SAH (16 bins along the longest centroid axis; per-bin primitive and centroid
//! bounds give both children's bounds, so each level costs two passes: binning and
//! partition), subtrees in parallel with `rayon::join` and large nodes binned in parallel;
//! O(n log n), and the same tree whatever the thread count.
//!
//! Query: nearest-first depth-first traversal with an explicit stack, pruning every box whose
//! distance is not below the best distance so far; the caller may seed the search with a
//! triangle (the previous sample's answer), which makes coherent query streams much cheaper.

use crate::geom::{V3, closest_on_triangle, v64};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Most triangles in a leaf (the SAH may stop earlier).
const MAX_LEAF: usize = 8;
/// Number of SAH bins.
const BINS: usize = 16;
/// Nodes with at most this many primitives sort them instead of binning.
const SMALL: usize = 16;
/// Subtrees smaller than this are built sequentially into one vector.
const PAR_THRESHOLD: usize = 16 * 1024;
/// Nodes larger than this are binned in parallel.
const PAR_BIN: usize = 256 * 1024;
/// Relative cost of visiting a node against testing one triangle.
const TRAVERSAL_COST: f32 = 1.0;
/// Below this depth the SAH decides; deeper (only on pathological inputs) nodes are split at
/// the centroid median of their longest axis, which bounds the depth by `SAH_DEPTH + 32`.
const SAH_DEPTH: usize = 48;
/// Initial traversal stack capacity: above the deepest possible tree.
pub(crate) const STACK: usize = 128;

/// An interior node: the boxes of its two children, and for each child either a leaf
/// (`count > 0` triangles from `child`) or a node at offset `child` from this one (`count ==
/// 0`; offset 0 marks a missing child, whose box is empty).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    lo: [[f32; 2]; 3],
    hi: [[f32; 2]; 3],
    child: [u32; 2],
    count: [u32; 2],
}

#[derive(Clone, Copy)]
struct Prim {
    lo: [f32; 3],
    hi: [f32; 3],
    tri: u32,
}

impl Prim {
    /// Twice the centroid of the box along axis `k` (the factor 2 changes no decision).
    #[inline(always)]
    fn c(&self, k: usize) -> f32 {
        self.lo[k] + self.hi[k]
    }
}

#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };

    #[inline(always)]
    fn grow(&mut self, lo: [f32; 3], hi: [f32; 3]) {
        for k in 0..3 {
            self.lo[k] = fmin(self.lo[k], lo[k]);
            self.hi[k] = fmax(self.hi[k], hi[k]);
        }
    }

    #[inline(always)]
    fn union(mut self, o: &Aabb) -> Aabb {
        self.grow(o.lo, o.hi);
        self
    }

    #[inline(always)]
    fn half_area(&self) -> f32 {
        let d = [
            fmax(self.hi[0] - self.lo[0], 0.0),
            fmax(self.hi[1] - self.lo[1], 0.0),
            fmax(self.hi[2] - self.lo[2], 0.0),
        ];
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
}

/// Bounds of a set of primitives: their boxes and their (doubled) centroids.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    b: Aabb,
    c: Aabb,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        b: Aabb::EMPTY,
        c: Aabb::EMPTY,
    };

    #[inline(always)]
    fn add(&mut self, p: &Prim) {
        self.b.grow(p.lo, p.hi);
        let c = [p.c(0), p.c(1), p.c(2)];
        self.c.grow(c, c);
    }

    fn union(self, o: &Bounds) -> Bounds {
        Bounds {
            b: self.b.union(&o.b),
            c: self.c.union(&o.c),
        }
    }

    fn of(prims: &[Prim]) -> Bounds {
        let mut b = Bounds::EMPTY;
        for p in prims {
            b.add(p);
        }
        b
    }
}

/// What a subtree build returns to its parent: the subtree's box and, for a leaf, its range.
#[derive(Clone, Copy)]
struct Sub {
    b: Aabb,
    /// `(first, count)` for a leaf; `None` for an interior node.
    leaf: Option<(u32, u32)>,
}

impl Node {
    const EMPTY_CHILD: Sub = Sub {
        b: Aabb::EMPTY,
        leaf: None,
    };

    /// A node over children `l` and `r`; `lo`/`ro` are their node offsets when interior.
    fn new(l: &Sub, lo: usize, r: &Sub, ro: usize) -> Node {
        let mut n = Node {
            lo: [[0.0; 2]; 3],
            hi: [[0.0; 2]; 3],
            child: [0; 2],
            count: [0; 2],
        };
        for (c, (s, off)) in [(l, lo), (r, ro)].into_iter().enumerate() {
            for k in 0..3 {
                n.lo[k][c] = s.b.lo[k];
                n.hi[k][c] = s.b.hi[k];
            }
            match s.leaf {
                Some((first, count)) => {
                    n.child[c] = first;
                    n.count[c] = count;
                }
                None => n.child[c] = off as u32,
            }
        }
        n
    }
}

/// The result of a nearest-point query.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    /// Squared distance.
    pub d2: f64,
    /// Closest point.
    pub point: V3,
    /// Leaf-order index of the triangle holding it (a seed for the next query).
    pub tri: u32,
}

/// BVH over a triangle soup.
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    tris: Vec<[[f32; 3]; 3]>,
}

impl Bvh {
    /// Builds the hierarchy over `tris` (indices into `positions`); `tris` must be non-empty.
    #[cfg(test)]
    pub(crate) fn build(positions: &[[f32; 3]], tris: &[[u32; 3]]) -> Bvh {
        Self::build_cancellable(positions, tris, None).expect("no cancel flag")
    }

    /// As [`Bvh::build`], checking `cancel` before every node split of the parallel levels
    /// (each split bins at most its node's triangles, the root's included) and before every
    /// sequential subtree (under 16 K triangles): `None` when it was set.
    pub(crate) fn build_cancellable(
        positions: &[[f32; 3]],
        tris: &[[u32; 3]],
        cancel: Option<&AtomicBool>,
    ) -> Option<Bvh> {
        assert!(!tris.is_empty());
        let stop = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
        let mut prims: Vec<Prim> = tris
            .par_iter()
            .enumerate()
            .map(|(i, t)| {
                let (a, b, c) = (
                    positions[t[0] as usize],
                    positions[t[1] as usize],
                    positions[t[2] as usize],
                );
                let mut lo = a;
                let mut hi = a;
                for p in [b, c] {
                    for k in 0..3 {
                        lo[k] = fmin(lo[k], p[k]);
                        hi[k] = fmax(hi[k], p[k]);
                    }
                }
                Prim {
                    lo,
                    hi,
                    tri: i as u32,
                }
            })
            .collect();
        if stop() {
            return None;
        }
        let bounds = par_bounds(&prims);
        let (root, segments) = build_par(&mut prims, 0, bounds, 0, cancel);
        if stop() {
            return None;
        }
        let nodes = if root.leaf.is_some() {
            vec![Node::new(&root, 0, &Node::EMPTY_CHILD, 0)]
        } else {
            let total: usize = segments.iter().map(Vec::len).sum();
            let mut nodes = Vec::with_capacity(total);
            for s in segments {
                nodes.extend_from_slice(&s);
            }
            nodes
        };
        let tris = prims
            .par_iter()
            .map(|p| {
                let t = tris[p.tri as usize];
                [
                    positions[t[0] as usize],
                    positions[t[1] as usize],
                    positions[t[2] as usize],
                ]
            })
            .collect();
        Some(Bvh { nodes, tris })
    }

    /// Number of triangles.
    pub(crate) fn len(&self) -> usize {
        self.tris.len()
    }

    /// Bytes held by the hierarchy.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node>()
            + self.tris.capacity() * std::mem::size_of::<[[f32; 3]; 3]>()
    }

    #[inline(always)]
    fn tri_closest(&self, p: V3, i: u32) -> (f64, V3) {
        let t = &self.tris[i as usize];
        let q = closest_on_triangle(p, v64(t[0]), v64(t[1]), v64(t[2]));
        (p.distance_squared(q), q)
    }

    /// Tests the triangles of leaf child `c` of `node` (but `skip`), updating `best`.
    #[inline(always)]
    fn scan_leaf(&self, p: V3, node: &Node, c: usize, skip: Option<u32>, best: &mut Hit) {
        let first = node.child[c];
        for i in first..first + node.count[c] {
            if Some(i) == skip {
                continue;
            }
            let (d2, q) = self.tri_closest(p, i);
            if d2 < best.d2 {
                *best = Hit {
                    d2,
                    point: q,
                    tri: i,
                };
            }
        }
    }

    /// The closest point of the triangles to `p`. `seed`, a leaf-order triangle index (such as
    /// the `tri` of a previous nearby query), only speeds the search up: the answer is the
    /// exact minimum either way.
    ///
    /// `stack` is scratch space, reused across calls to avoid initialising a stack per query.
    pub(crate) fn nearest(&self, p: V3, seed: Option<u32>, stack: &mut Vec<(u32, f64)>) -> Hit {
        let mut best = match seed {
            Some(i) if (i as usize) < self.tris.len() => {
                let (d2, point) = self.tri_closest(p, i);
                Hit { d2, point, tri: i }
            }
            _ => Hit {
                d2: f64::INFINITY,
                point: p,
                tri: u32::MAX,
            },
        };
        let nodes = &self.nodes[..];
        stack.clear();
        let mut n = 0usize;
        loop {
            let node = &nodes[n];
            let d = box_d2(p, node);
            let (near, far) = if d[0] <= d[1] { (0, 1) } else { (1, 0) };
            let mut next = None;
            // The far child is only worth a look when the near one is.
            if d[near] < best.d2 {
                if node.count[near] > 0 {
                    self.scan_leaf(p, node, near, seed, &mut best);
                } else {
                    next = Some(n + node.child[near] as usize);
                }
                if d[far] < best.d2 {
                    if node.count[far] > 0 {
                        self.scan_leaf(p, node, far, seed, &mut best);
                    } else if next.is_none() {
                        next = Some(n + node.child[far] as usize);
                    } else {
                        stack.push(((n + node.child[far] as usize) as u32, d[far]));
                    }
                }
            }
            if let Some(m) = next {
                n = m;
                continue;
            }
            // Pop the next subtree that can still hold something closer.
            loop {
                let Some((m, dm)) = stack.pop() else {
                    return best;
                };
                if dm < best.d2 {
                    n = m as usize;
                    break;
                }
            }
        }
    }
}

/// Squared distances from `p` to the two child boxes of `n` (0 inside; infinite for a
/// missing child).
#[inline(always)]
fn box_d2(p: V3, n: &Node) -> [f64; 2] {
    #[inline(always)]
    fn max(a: f64, b: f64) -> f64 {
        if a > b { a } else { b }
    }
    let gap = |k: usize, c: usize| {
        let e = max(max(n.lo[k][c] as f64 - p[k], p[k] - n.hi[k][c] as f64), 0.0);
        e * e
    };
    [
        gap(0, 0) + gap(1, 0) + gap(2, 0),
        gap(0, 1) + gap(1, 1) + gap(2, 1),
    ]
}

fn par_bounds(prims: &[Prim]) -> Bounds {
    if prims.len() < PAR_BIN {
        return Bounds::of(prims);
    }
    prims
        .par_chunks(PAR_BIN / 8)
        .map(Bounds::of)
        .reduce(|| Bounds::EMPTY, |a, b| a.union(&b))
}

/// SAH bins along one axis.
#[derive(Clone, Copy)]
struct Bins {
    count: [usize; BINS],
    bounds: [Bounds; BINS],
}

impl Bins {
    fn new() -> Bins {
        Bins {
            count: [0; BINS],
            bounds: [Bounds::EMPTY; BINS],
        }
    }

    fn fill(prims: &[Prim], k: usize, lo: f32, inv: f32) -> Bins {
        let mut b = Bins::new();
        for p in prims {
            let i = bin_of(p.c(k), lo, inv);
            b.count[i] += 1;
            b.bounds[i].add(p);
        }
        b
    }

    fn merge(mut self, o: &Bins) -> Bins {
        for i in 0..BINS {
            self.count[i] += o.count[i];
            self.bounds[i] = self.bounds[i].union(&o.bounds[i]);
        }
        self
    }
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, inv: f32) -> usize {
    // The clamp also maps NaN to 0 (`f32::clamp` would propagate it; `max` does not).
    let x = ((c - lo) * inv).max(0.0).min((BINS - 1) as f32);
    x as i32 as usize
}

/// Where to split a node: `None` for a leaf, else the number of primitives moved to the left
/// (the slice is partitioned in place) and the bounds of both sides.
fn split(prims: &mut [Prim], nb: &Bounds, depth: usize) -> Option<(usize, Bounds, Bounds)> {
    let n = prims.len();
    if n <= 2 {
        return None;
    }
    let cb = &nb.c;
    let ext = [0, 1, 2].map(|k| cb.hi[k] - cb.lo[k]);
    let k = if ext[0] >= ext[1] && ext[0] >= ext[2] {
        0
    } else if ext[1] >= ext[2] {
        1
    } else {
        2
    };
    // Coincident centroids (or a pathologically deep tree): split by count.
    let median = |prims: &mut [Prim]| {
        if n <= MAX_LEAF {
            return None;
        }
        let mid = n / 2;
        prims.select_nth_unstable_by(mid, |x, y| x.c(k).total_cmp(&y.c(k)));
        let (l, r) = prims.split_at(mid);
        Some((mid, Bounds::of(l), Bounds::of(r)))
    };
    // `ext[k]` may be NaN only for non-finite input, which `Mesh::validate` rules out.
    if ext[k].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || depth >= SAH_DEPTH {
        return median(prims);
    }
    let parent_area = nb.b.half_area();
    let leaf_is_cheaper = |cost: f32| {
        let split_cost = if parent_area > 0.0 {
            TRAVERSAL_COST + cost / parent_area
        } else {
            TRAVERSAL_COST + n as f32 * 0.5
        };
        n <= MAX_LEAF && n as f32 <= split_cost
    };
    if n <= SMALL {
        // Few primitives: exact SAH over the centroid order (cheaper than binning here).
        prims.sort_unstable_by(|x, y| x.c(k).total_cmp(&y.c(k)));
        let mut right = [0.0f32; SMALL];
        let mut acc = Aabb::EMPTY;
        for i in (1..n).rev() {
            acc.grow(prims[i].lo, prims[i].hi);
            right[i] = acc.half_area();
        }
        let mut acc = Aabb::EMPTY;
        let (mut best, mut mid) = (f32::INFINITY, n / 2);
        for i in 0..n - 1 {
            acc.grow(prims[i].lo, prims[i].hi);
            let cost = acc.half_area() * (i + 1) as f32 + right[i + 1] * (n - i - 1) as f32;
            if cost < best {
                (best, mid) = (cost, i + 1);
            }
        }
        if leaf_is_cheaper(best) {
            return None;
        }
        let (l, r) = prims.split_at(mid);
        return Some((mid, Bounds::of(l), Bounds::of(r)));
    }
    let (lo, inv) = (cb.lo[k], BINS as f32 / ext[k]);
    let bins = if n >= PAR_BIN {
        prims
            .par_chunks(PAR_BIN / 8)
            .map(|c| Bins::fill(c, k, lo, inv))
            .reduce(Bins::new, |a, b| a.merge(&b))
    } else {
        Bins::fill(prims, k, lo, inv)
    };
    // Sweep from the right, then from the left.
    let mut right = [Bounds::EMPTY; BINS];
    let mut right_count = [0usize; BINS];
    let mut acc = Bounds::EMPTY;
    let mut cnt = 0;
    for i in (1..BINS).rev() {
        acc = acc.union(&bins.bounds[i]);
        cnt += bins.count[i];
        right[i] = acc;
        right_count[i] = cnt;
    }
    let mut best: Option<(f32, usize)> = None;
    let mut acc = Bounds::EMPTY;
    let mut cnt = 0;
    let mut left = [Bounds::EMPTY; BINS];
    for i in 0..BINS - 1 {
        acc = acc.union(&bins.bounds[i]);
        cnt += bins.count[i];
        left[i + 1] = acc;
        let rc = right_count[i + 1];
        if cnt == 0 || rc == 0 {
            continue;
        }
        let cost = acc.b.half_area() * cnt as f32 + right[i + 1].b.half_area() * rc as f32;
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, i + 1));
        }
    }
    // Centroids spread along k fill the first and last bins, so a split exists.
    let Some((cost, boundary)) = best else {
        return median(prims);
    };
    if leaf_is_cheaper(cost) {
        return None;
    }
    let mid = partition(prims, |p| bin_of(p.c(k), lo, inv) < boundary);
    debug_assert_eq!(mid, (0..boundary).map(|i| bins.count[i]).sum::<usize>());
    Some((mid, left[boundary], right[boundary]))
}

/// In-place partition; returns the number of elements for which `pred` holds (moved first).
fn partition(v: &mut [Prim], pred: impl Fn(&Prim) -> bool) -> usize {
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

/// Builds the subtree over `prims` (the first of which becomes triangle `first` in leaf
/// order) and returns it with its nodes, depth-first, as segments to concatenate (none for a
/// leaf).
/// When `cancel` is set, what is left is built as leaves at once (the caller discards the tree).
fn build_par(
    prims: &mut [Prim],
    first: usize,
    nb: Bounds,
    depth: usize,
    cancel: Option<&AtomicBool>,
) -> (Sub, Vec<Vec<Node>>) {
    if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
        return (leaf(&nb, first, prims.len()), Vec::new());
    }
    if prims.len() < PAR_THRESHOLD {
        let mut out = Vec::new();
        let s = build_seq(prims, first, nb, depth, &mut out);
        return (s, vec![out]);
    }
    let Some((mid, lb, rb)) = split(prims, &nb, depth) else {
        return (leaf(&nb, first, prims.len()), Vec::new());
    };
    let (l, r) = prims.split_at_mut(mid);
    let ((ls, lsegs), (rs, rsegs)) = rayon::join(
        || build_par(l, first, lb, depth + 1, cancel),
        || build_par(r, first + mid, rb, depth + 1, cancel),
    );
    let left_nodes: usize = lsegs.iter().map(Vec::len).sum();
    let mut segs = Vec::with_capacity(1 + lsegs.len() + rsegs.len());
    segs.push(vec![Node::new(&ls, 1, &rs, 1 + left_nodes)]);
    segs.extend(lsegs);
    segs.extend(rsegs);
    (
        Sub {
            b: nb.b,
            leaf: None,
        },
        segs,
    )
}

fn build_seq(
    prims: &mut [Prim],
    first: usize,
    nb: Bounds,
    depth: usize,
    out: &mut Vec<Node>,
) -> Sub {
    match split(prims, &nb, depth) {
        None => leaf(&nb, first, prims.len()),
        Some((mid, lb, rb)) => {
            let me = out.len();
            out.push(Node::new(&Node::EMPTY_CHILD, 0, &Node::EMPTY_CHILD, 0));
            let (l, r) = prims.split_at_mut(mid);
            let ls = build_seq(l, first, lb, depth + 1, out);
            let r_at = out.len();
            let rs = build_seq(r, first + mid, rb, depth + 1, out);
            out[me] = Node::new(&ls, 1, &rs, r_at - me);
            Sub {
                b: nb.b,
                leaf: None,
            }
        }
    }
}

fn leaf(nb: &Bounds, first: usize, count: usize) -> Sub {
    Sub {
        b: nb.b,
        leaf: Some((first as u32, count as u32)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::Rng;

    fn random_soup(n: usize, seed: u64) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let mut r = Rng::new(seed, 0);
        let mut pos = Vec::new();
        let mut tris = Vec::new();
        for i in 0..n {
            let c = [r.f64() as f32, r.f64() as f32, r.f64() as f32];
            for _ in 0..3 {
                pos.push([
                    c[0] + 0.05 * (r.f64() as f32 - 0.5),
                    c[1] + 0.05 * (r.f64() as f32 - 0.5),
                    c[2] + 0.05 * (r.f64() as f32 - 0.5),
                ]);
            }
            let b = 3 * i as u32;
            tris.push([b, b + 1, b + 2]);
        }
        (pos, tris)
    }

    fn brute(pos: &[[f32; 3]], tris: &[[u32; 3]], p: V3) -> f64 {
        tris.iter()
            .map(|t| {
                let q = closest_on_triangle(
                    p,
                    v64(pos[t[0] as usize]),
                    v64(pos[t[1] as usize]),
                    v64(pos[t[2] as usize]),
                );
                p.distance_squared(q)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn nearest_matches_brute_force() {
        // Large enough to exercise the parallel build path.
        let (pos, tris) = random_soup(40_000, 7);
        let bvh = Bvh::build(&pos, &tris);
        assert_eq!(bvh.len(), tris.len());
        let mut r = Rng::new(99, 1);
        let mut seed = None;
        let mut stack = Vec::new();
        for _ in 0..200 {
            let p = V3::new(
                r.f64() * 1.6 - 0.3,
                r.f64() * 1.6 - 0.3,
                r.f64() * 1.6 - 0.3,
            );
            let h = bvh.nearest(p, seed, &mut stack);
            let b = brute(&pos, &tris, p);
            assert_eq!(h.d2, b, "bvh {} vs brute {}", h.d2, b);
            assert_eq!(p.distance_squared(h.point), h.d2);
            // A seed never changes the answer.
            assert_eq!(bvh.nearest(p, None, &mut stack).d2, h.d2);
            seed = Some(h.tri);
        }
    }

    #[test]
    fn coincident_centroids_and_tiny_inputs() {
        // Many identical triangles: the SAH finds no split axis.
        let pos = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let tris = vec![[0u32, 1, 2]; 100];
        let bvh = Bvh::build(&pos, &tris);
        let mut stack = Vec::new();
        let h = bvh.nearest(V3::new(0.25, 0.25, 2.0), None, &mut stack);
        assert_eq!(h.d2, 4.0);
        let bvh = Bvh::build(&pos, &tris[..1]);
        assert_eq!(
            bvh.nearest(V3::new(2.0, 0.0, 0.0), None, &mut stack).d2,
            1.0
        );
    }
}
