//! The frame of a regular grid (Belblidia & Perrin, section 2): which cell a point falls in
//! and where inside it, shared by the grid's passes (`grid_cells.rs`, `grid_sums.rs`) and
//! the hash of `grid_partition.rs`.

use crate::options::GridSize;
use crate::partition::Cell;

/// Largest number of cells along one axis (keeps cell keys in 21 bits per axis).
const MAX_CELLS_PER_AXIS: u64 = 1 << 20;

/// Cells per axis and cell sides for a grid of `size` over `bounds`.
fn grid_dims(bounds: &Cell, size: GridSize) -> ([u64; 3], [f64; 3]) {
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

/// The cell coordinates of a point, as every grid pass computes them (`grid_cells.rs`,
/// `grid_sums.rs`, and the hash of `grid_partition.rs`).
#[derive(Clone, Copy)]
pub(crate) struct Grid {
    lo: [f64; 3],
    inv: [f64; 3],
    side: [f64; 3],
    top: [i64; 3],
}

impl Grid {
    /// The grid of `size` over `bounds`.
    pub(crate) fn new(bounds: &Cell, size: GridSize) -> (Grid, [u64; 3]) {
        let (dims, side) = grid_dims(bounds, size);
        let grid = Grid {
            lo: std::array::from_fn(|k| f64::from(bounds.min[k])),
            inv: std::array::from_fn(|k| 1.0 / side[k]),
            side,
            top: std::array::from_fn(|k| dims[k] as i64 - 1),
        };
        (grid, dims)
    }

    /// The cell of `p`, and where `p` lies inside it along each axis (0 at the cell's low
    /// side, 1 at its high side; beyond those in the clamped outer cells only by rounding).
    #[inline]
    pub(crate) fn locate(&self, p: &[f32; 3]) -> ([u32; 3], [f64; 3]) {
        let mut c = [0u32; 3];
        let mut u = [0f64; 3];
        for k in 0..3 {
            // Clamped as a float first, so that the conversion needs no saturation (Rust's
            // `as` adds compares and branches for NaN and overflow).
            let t = (f64::from(p[k]) - self.lo[k]) * self.inv[k];
            let f = t.max(0.0).min(self.top[k] as f64);
            // SAFETY: `f` is finite (positions are validated finite, the bounds hold them, so
            // `t` is finite) and within 0..=top < 2²¹, which fits an i64.
            let i: i64 = unsafe { f.to_int_unchecked() };
            c[k] = i as u32;
            u[k] = t - i as f64;
        }
        (c, u)
    }

    /// The lower corner of cell `c`.
    #[inline]
    pub(crate) fn corner(&self, c: [u32; 3]) -> [f64; 3] {
        std::array::from_fn(|k| self.lo[k] + f64::from(c[k]) * self.side[k])
    }

    /// The sides of a cell.
    pub(crate) fn side(&self) -> [f64; 3] {
        self.side
    }

    /// The box of cell `c` ("show partition").
    pub(crate) fn cell_box(&self, c: [u32; 3]) -> Cell {
        let (lo, side) = (self.lo, self.side);
        Cell {
            min: std::array::from_fn(|k| (lo[k] + f64::from(c[k]) * side[k]) as f32),
            max: std::array::from_fn(|k| (lo[k] + f64::from(c[k] + 1) * side[k]) as f32),
        }
    }
}
