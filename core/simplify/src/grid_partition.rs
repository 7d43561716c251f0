//! Regular partition (Belblidia & Perrin, section 2, after Rossignac & Borrel 1993): the
//! bounding box cut into a grid; every non-empty cell is one cluster. The cell size is the
//! largest detail that disappears.

use crate::cell_table::CellTable;
use crate::options::GridSize;
use crate::partition::{Cell, Partition, UNUSED};

/// Largest number of cells along one axis (keeps cell keys in 21 bits per axis).
pub const MAX_CELLS_PER_AXIS: u64 = 1 << 20;

/// Cells per axis and cell sides for a grid of `size` over `bounds`.
pub(crate) fn grid_dims(bounds: &Cell, size: GridSize) -> ([u64; 3], [f64; 3]) {
    let ext: [f64; 3] = std::array::from_fn(|k| f64::from(bounds.max[k] - bounds.min[k]));
    let largest = ext.iter().cloned().fold(0.0, f64::max);
    let dims: [u64; 3] = match size {
        GridSize::CellsPerAxis(n) => {
            // Flat axes (a plane, a line) get one cell.
            std::array::from_fn(|k| if ext[k] > 0.0 { u64::from(n.max(1)) } else { 1 })
        }
        GridSize::CellSize(s) => std::array::from_fn(|k| {
            let n = (ext[k] / s).ceil() as u64;
            n.clamp(1, MAX_CELLS_PER_AXIS)
        }),
    };
    let dims = dims.map(|d| d.min(MAX_CELLS_PER_AXIS));
    let side = std::array::from_fn(|k| {
        if ext[k] > 0.0 {
            ext[k] / dims[k] as f64
        } else {
            largest.max(1.0)
        }
    });
    (dims, side)
}

/// Assigns every vertex with non-zero weight to the grid cell containing it. With `classes`,
/// vertices of different classes never share a cluster (boundary preservation). Cluster ids
/// follow the order in which cells are first met, so the output is deterministic.
pub(crate) fn grid_partition(
    positions: &[[f32; 3]],
    weights: &[f32],
    classes: Option<&[u8]>,
    bounds: &Cell,
    size: GridSize,
    keep_cells: bool,
) -> Partition {
    let (dims, side) = grid_dims(bounds, size);
    let inv: [f64; 3] = std::array::from_fn(|k| 1.0 / side[k]);
    let lo: [f64; 3] = std::array::from_fn(|k| f64::from(bounds.min[k]));
    let cell_of = |p: &[f32; 3]| -> [u64; 3] {
        std::array::from_fn(|k| {
            let i = ((f64::from(p[k]) - lo[k]) * inv[k]) as i64;
            i.clamp(0, dims[k] as i64 - 1) as u64
        })
    };
    let mut cluster_of = vec![UNUSED; positions.len()];
    let mut table = CellTable::with_capacity(positions.len() / 4 + 16);
    let mut cells = Vec::new();
    for (v, (p, &w)) in positions.iter().zip(weights).enumerate() {
        if w <= 0.0 {
            continue;
        }
        let c = cell_of(p);
        let class = classes.map_or(0, |c| u64::from(c[v]));
        let key = (((c[0] << 21 | c[1]) << 21 | c[2]) << 1) | class;
        let id = table.id(key);
        if keep_cells && id as usize == cells.len() {
            cells.push(Cell {
                min: std::array::from_fn(|k| (lo[k] + c[k] as f64 * side[k]) as f32),
                max: std::array::from_fn(|k| (lo[k] + (c[k] + 1) as f64 * side[k]) as f32),
            });
        }
        cluster_of[v] = id;
    }
    Partition {
        cluster_of,
        clusters: table.len() as usize,
        cells,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_grid_clusters_to_the_known_cells() {
        // 11 × 11 points on [0,1]² clustered into 5 × 5 cells: each cell takes a 2 × 2 or
        // 3 × 3 block; 25 clusters.
        let positions: Vec<[f32; 3]> = (0..121)
            .map(|i| [(i % 11) as f32 / 10.0, (i / 11) as f32 / 10.0, 0.0])
            .collect();
        let w = vec![1.0; positions.len()];
        let b = Cell {
            min: [0.0; 3],
            max: [1.0, 1.0, 0.0],
        };
        let p = grid_partition(&positions, &w, None, &b, GridSize::CellsPerAxis(5), true);
        assert_eq!(p.clusters, 25);
        // Points 0 and 1 (x = 0, 0.1) share the first cell; point 2 (x = 0.2) starts the second.
        assert_eq!(p.cluster_of[0], p.cluster_of[1]);
        assert_ne!(p.cluster_of[1], p.cluster_of[2]);
        assert_eq!(
            p.cells[0],
            Cell {
                min: [0.0; 3],
                max: [0.2, 0.2, 1.0]
            }
        );
    }

    #[test]
    fn classes_split_cells() {
        let positions = vec![[0.0f32; 3], [0.01, 0.0, 0.0]];
        let b = Cell {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        let p = grid_partition(
            &positions,
            &[1.0, 1.0],
            Some(&[0, 1]),
            &b,
            GridSize::CellsPerAxis(2),
            false,
        );
        assert_eq!(p.clusters, 2);
    }
}
