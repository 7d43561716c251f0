//! Per-cluster statistics, what the representatives (Belblidia & Perrin, section 2, "fusion
//! des sommets") are made of: the weight sum and weighted position sum (barycentre), the
//! heaviest vertex, and the box of the cluster's vertices (the quadric minimiser's bound).
//!
//! Summed as one pass over the vertices in fixed blocks ([`crate::blocks`]) would: each block
//! sums its part of a cluster in vertex order, and the parts are added in block order, so the
//! sums do not depend on the thread count. They are summed cluster by cluster when each
//! representative is placed, from the cluster's vertices — a range of the vertex order for the
//! adaptive partitions ([`of_points`]), the vertex lists of `Partition::members` for the grid
//! ([`of_members`]) — so no statistics are held for every cluster at once.

use crate::adaptive_partition::LeafPoints;
use crate::blocks;

/// The statistics of one cluster (one cache line).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stats {
    /// Σ w·x, Σ w·y, Σ w·z, Σ w.
    pub sum: [f64; 4],
    /// Lower corner of the vertices' box.
    pub lo: [f32; 3],
    /// Upper corner of the vertices' box.
    pub hi: [f32; 3],
    /// Weight of the heaviest vertex (the first met among equals).
    pub heaviest_w: f32,
    /// Index of that vertex.
    pub heaviest: u32,
}

impl Stats {
    /// No vertex yet.
    pub const EMPTY: Stats = Stats {
        sum: [0.0; 4],
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
        heaviest_w: f32::NEG_INFINITY,
        heaviest: u32::MAX,
    };

    /// Adds vertex `v` at `p` with weight `w`.
    #[inline]
    pub fn add(&mut self, v: u32, p: &[f32; 3], w: f32) {
        let wd = f64::from(w);
        for (k, &x) in p.iter().enumerate() {
            self.sum[k] += wd * f64::from(x);
            self.lo[k] = self.lo[k].min(x);
            self.hi[k] = self.hi[k].max(x);
        }
        self.sum[3] += wd;
        if w > self.heaviest_w {
            self.heaviest_w = w;
            self.heaviest = v;
        }
    }

    /// Adds the vertices of `o`, which all come after this one's.
    #[inline]
    pub fn merge(&mut self, o: &Stats) {
        for k in 0..3 {
            self.sum[k] += o.sum[k];
            self.lo[k] = self.lo[k].min(o.lo[k]);
            self.hi[k] = self.hi[k].max(o.hi[k]);
        }
        self.sum[3] += o.sum[3];
        if o.heaviest_w > self.heaviest_w {
            self.heaviest_w = o.heaviest_w;
            self.heaviest = o.heaviest;
        }
    }

    /// The weighted barycentre.
    #[inline]
    pub fn barycentre(&self) -> [f64; 3] {
        let s = self.sum;
        [s[0] / s[3], s[1] / s[3], s[2] / s[3]]
    }
}

/// The statistics of one cluster whose vertices are `points` (in any order; `scratch` is
/// reused between calls), summed exactly as a pass over the vertices in fixed blocks sums
/// them: each block's partial in index order, the partials added in block order. So an adaptive partition, which holds each cluster's vertices as a range of its
/// vertex order, places representatives without a statistics array for all its clusters, and
/// they are the same bits as if it had one.
pub(crate) fn of_points(points: LeafPoints<'_>, scratch: &mut Vec<u64>) -> Stats {
    // Sorted as (vertex index, place in `points`) pairs: eight bytes a vertex to move.
    scratch.clear();
    scratch.extend(
        points
            .iter()
            .enumerate()
            .map(|(i, q)| u64::from(q.id) << 32 | i as u64),
    );
    scratch.sort_unstable();
    let verts = scratch.iter().map(|&k| {
        let q = &points[k as u32 as usize];
        (q.id, q.p, points.weights[q.id as usize])
    });
    in_blocks(verts, false)
}

/// The statistics of a grid cluster whose vertices are `members` (in increasing index order),
/// summed as the grid summed them while it binned: each block's partial in index order, the
/// first block's partial taken as it is and the others added in block order.
pub(crate) fn of_members(members: &[u32], positions: &[[f32; 3]], weights: &[f32]) -> Stats {
    let verts = members
        .iter()
        .map(|&v| (v, positions[v as usize], weights[v as usize]));
    in_blocks(verts, true)
}

/// The sum of `verts` (index, position, weight; in increasing index order) block by block of
/// [`blocks::BLOCK`] indices. `copy_first`: the sum starts as the first block's partial (the
/// grid's way) rather than as that partial added to an empty sum (the adaptive partitions'
/// former way); the two differ only in the sign of a zero sum, and each is kept to the bit.
fn in_blocks(verts: impl Iterator<Item = (u32, [f32; 3], f32)>, copy_first: bool) -> Stats {
    let mut total = (!copy_first).then_some(Stats::EMPTY);
    let mut part = Stats::EMPTY;
    let mut block = None;
    let add = |total: &mut Option<Stats>, part: &Stats| match total {
        Some(t) => t.merge(part),
        None => *total = Some(*part),
    };
    for (v, p, w) in verts {
        let b = v as usize / blocks::BLOCK;
        if block.is_some_and(|block| block != b) {
            add(&mut total, &part);
            part = Stats::EMPTY;
        }
        block = Some(b);
        part.add(v, &p, w);
    }
    add(&mut total, &part);
    total.unwrap_or(Stats::EMPTY)
}
