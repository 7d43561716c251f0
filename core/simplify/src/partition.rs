//! What every partition produces: a cluster id per vertex and, for "show partition", the cells.

/// Marks vertices that no face uses (they belong to no cluster).
pub const UNUSED: u32 = u32::MAX;

/// An axis-aligned cell of a partition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Lower corner.
    pub min: [f32; 3],
    /// Upper corner.
    pub max: [f32; 3],
}

/// The result of partitioning the bounding volume.
#[derive(Clone, Debug, Default)]
pub struct Partition {
    /// Cluster of each input vertex, or [`UNUSED`].
    pub cluster_of: Vec<u32>,
    /// Number of clusters (non-empty cells).
    pub clusters: usize,
    /// The non-empty cells, indexed by cluster, when they were asked for.
    pub cells: Vec<Cell>,
}

impl Partition {
    /// The vertices of each cluster, in increasing index order: a counting sort of
    /// `cluster_of` (4 bytes a vertex and 4 a cluster).
    pub(crate) fn members(&self) -> Members {
        let mut start = vec![0u32; self.clusters + 1];
        for &c in self.cluster_of.iter().filter(|&&c| c != UNUSED) {
            start[c as usize] += 1;
        }
        for c in 1..=self.clusters {
            start[c] += start[c - 1];
        }
        // Filled from each list's end, vertices in decreasing order: the lists come out in
        // increasing order and `start` ends as their starts.
        let mut ids = vec![0u32; start[self.clusters] as usize];
        for (v, &c) in self.cluster_of.iter().enumerate().rev() {
            if c != UNUSED {
                start[c as usize] -= 1;
                ids[start[c as usize] as usize] = v as u32;
            }
        }
        Members { start, ids }
    }
}

/// The vertices of every cluster (see [`Partition::members`]).
pub(crate) struct Members {
    start: Vec<u32>,
    ids: Vec<u32>,
}

impl Members {
    /// The vertices of cluster `c`, in increasing order.
    pub(crate) fn of(&self, c: usize) -> &[u32] {
        &self.ids[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// Bounds of the vertices with non-zero weight (the referenced ones), or `None` if there are
/// none. Minima and maxima do not depend on the order they are taken in: every core takes them.
pub(crate) fn weighted_bounds(positions: &[[f32; 3]], weights: &[f32]) -> Option<Cell> {
    let parts = crate::blocks::map(positions.len(), |r| {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for (p, &w) in positions[r.clone()].iter().zip(&weights[r]) {
            if w > 0.0 {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        (lo, hi)
    });
    let (lo, hi) = parts.into_iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), (l, h)| {
            (
                std::array::from_fn(|k| lo[k].min(l[k])),
                std::array::from_fn(|k| hi[k].max(h[k])),
            )
        },
    );
    (lo[0] <= hi[0]).then_some(Cell { min: lo, max: hi })
}
