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

/// The vertices of every cluster, each list in increasing vertex order (the grid partition
/// builds them as it bins: `grid_partition.rs`).
pub(crate) struct Members {
    /// Where each cluster's list starts in `ids`, and the end of the last.
    pub start: Vec<u32>,
    /// The lists, one after the other.
    pub ids: Vec<u32>,
}

impl Members {
    /// The vertices of cluster `c`, in increasing order.
    pub(crate) fn of(&self, c: usize) -> &[u32] {
        &self.ids[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// Bounds of the vertices with non-zero weight (the referenced ones) and their number, or
/// `None` if there are none. Minima, maxima and counts do not depend on the order they are
/// taken in: every core takes them.
pub(crate) fn referenced_bounds(positions: &[[f32; 3]], weights: &[f32]) -> Option<(Cell, u64)> {
    bounds_of::<false>(positions, weights).0
}

/// [`referenced_bounds`] of positions not yet validated, and whether every position (referenced
/// or not) is finite, taken in the same pass (issue 33's pass B; [`tessd_mesh::Mesh::validate`]
/// names the first that is not).
pub(crate) fn checked_bounds(
    positions: &[[f32; 3]],
    weights: &[f32],
) -> (Option<(Cell, u64)>, bool) {
    bounds_of::<true>(positions, weights)
}

fn bounds_of<const CHECK: bool>(
    positions: &[[f32; 3]],
    weights: &[f32],
) -> (Option<(Cell, u64)>, bool) {
    let parts = crate::blocks::map(positions.len(), |r| {
        let (block, w) = (&positions[r.clone()], &weights[r]);
        let count = w.iter().map(|&w| u64::from(w > 0.0)).sum::<u64>();
        if count == w.len() as u64 {
            // Every vertex referenced (the usual case): minima and maxima over the flat
            // coordinates, four vertices (twelve lanes, lane `l` holding coordinate `l % 3`) a
            // step, which the compiler turns into vector instructions. `<` rather than
            // `f32::min`: positions are finite (validated).
            let flat = block.as_flattened();
            let mut lo = [f32::INFINITY; 12];
            let mut hi = [f32::NEG_INFINITY; 12];
            // Any infinity or NaN turns `x · 0` into NaN, and a sum with one NaN: no branch.
            let mut nan = [0f32; 12];
            let steps = flat.chunks_exact(12);
            let rest = steps.remainder();
            for p in steps {
                for l in 0..12 {
                    lo[l] = if p[l] < lo[l] { p[l] } else { lo[l] };
                    hi[l] = if p[l] > hi[l] { p[l] } else { hi[l] };
                    if CHECK {
                        nan[l] += p[l] * 0.0;
                    }
                }
            }
            for (l, &p) in rest.iter().enumerate() {
                lo[l] = lo[l].min(p);
                hi[l] = hi[l].max(p);
                if CHECK {
                    nan[l] += p * 0.0;
                }
            }
            let lane = |a: &[f32; 12], k: usize, f: fn(f32, f32) -> f32| {
                (k..12).step_by(3).map(|l| a[l]).reduce(f).unwrap()
            };
            let lo: [f32; 3] = std::array::from_fn(|k| lane(&lo, k, f32::min));
            let hi: [f32; 3] = std::array::from_fn(|k| lane(&hi, k, f32::max));
            return (lo, hi, count, nan.iter().sum::<f32>() == 0.0);
        }
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut nan = 0f32;
        for (p, &w) in block.iter().zip(w) {
            if CHECK {
                nan += p[0] * 0.0 + p[1] * 0.0 + p[2] * 0.0;
            }
            if w > 0.0 {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        (lo, hi, count, nan == 0.0)
    });
    let (lo, hi, count, finite) = parts.into_iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3], 0, true),
        |(lo, hi, n, ok), (l, h, c, f)| {
            (
                std::array::from_fn(|k| lo[k].min(l[k])),
                std::array::from_fn(|k| hi[k].max(h[k])),
                n + c,
                ok && f,
            )
        },
    );
    let bounds = (count > 0).then_some((Cell { min: lo, max: hi }, count));
    (bounds, finite || !CHECK)
}
