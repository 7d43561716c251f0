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
