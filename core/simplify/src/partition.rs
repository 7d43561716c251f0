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

/// Bounds of the vertices with non-zero weight (the referenced ones), or `None` if there are none.
pub(crate) fn weighted_bounds(positions: &[[f32; 3]], weights: &[f32]) -> Option<Cell> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut any = false;
    for (p, &w) in positions.iter().zip(weights) {
        if w > 0.0 {
            any = true;
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    any.then_some(Cell { min: lo, max: hi })
}
