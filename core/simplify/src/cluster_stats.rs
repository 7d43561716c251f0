//! Per-cluster statistics, what the representatives (Belblidia & Perrin, section 2, "fusion
//! des sommets") are made of: the weight sum and weighted position sum (barycentre), the
//! heaviest vertex, and the box of the cluster's vertices (the quadric minimiser's bound).
//!
//! Accumulated in one pass over the vertices in fixed blocks ([`crate::blocks`]): each block
//! sums into its own partials, and the partials are added into the clusters in block order,
//! so the sums do not depend on the thread count. The grid partition accumulates them while
//! it bins (`grid_partition.rs`); the adaptive partitions gather them from the cluster ids.

use crate::blocks;
use crate::cell_table::CellTable;
use crate::partition::UNUSED;

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

/// One block's partials: the clusters it met (in first-met order), their keys and their sums.
pub(crate) struct BlockStats {
    /// Key of each local cluster.
    pub keys: Vec<u64>,
    /// Partial statistics of each local cluster.
    pub stats: Vec<Stats>,
}

impl BlockStats {
    /// Empty partials for a block of `n` items, and a table that never grows for them.
    pub fn new(n: usize) -> (BlockStats, CellTable) {
        let table = CellTable::with_capacity(n);
        let out = BlockStats {
            keys: Vec::with_capacity(n / 4),
            stats: Vec::with_capacity(n / 4),
        };
        (out, table)
    }

    /// Adds vertex `v` to the cluster of `key`; returns its local id.
    #[inline]
    pub fn add(&mut self, table: &mut CellTable, key: u64, v: u32, p: &[f32; 3], w: f32) -> u32 {
        let id = table.id(key);
        if id as usize == self.stats.len() {
            self.keys.push(key);
            self.stats.push(Stats::EMPTY);
        }
        self.stats[id as usize].add(v, p, w);
        id
    }
}

/// The statistics of every cluster of `cluster_of` (`clusters` of them).
pub(crate) fn gather(
    positions: &[[f32; 3]],
    weights: &[f32],
    cluster_of: &[u32],
    clusters: usize,
) -> Vec<Stats> {
    let partials = blocks::map(positions.len(), |r| {
        let (mut b, mut table) = BlockStats::new(r.len());
        for v in r {
            let c = cluster_of[v];
            if c != UNUSED {
                b.add(
                    &mut table,
                    u64::from(c),
                    v as u32,
                    &positions[v],
                    weights[v],
                );
            }
        }
        b
    });
    let mut stats = vec![Stats::EMPTY; clusters];
    for b in &partials {
        for (&k, s) in b.keys.iter().zip(&b.stats) {
            stats[k as usize].merge(s);
        }
    }
    stats
}
