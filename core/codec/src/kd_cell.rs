//! The kd-tree's cells (paper 003 §3, GD02): a vertex's key in kd order, the side of a cell's
//! high half, and which half a vertex lies in. Shared by the coder, its contexts, the geometry
//! ahead and the decoder's assembly.

use crate::complex::{Vertex, axis_bits};

/// The full-precision kd key of a vertex at kd level `level`: its split decisions, first on top.
pub fn kd_key(corner: [u32; 3], level: usize, bits: u32) -> u64 {
    let mut key = 0u64;
    for j in 0..level {
        let axis = j % 3;
        let bit = (corner[axis] >> (bits - 1 - (j / 3) as u32)) & 1;
        key |= (bit as u64) << (63 - j);
    }
    key
}

/// Side of the high half of a split at kd `level`, in grid units.
pub fn half(level: usize, bits: u32) -> u32 {
    1u32 << (bits - axis_bits(level, level % 3) - 1)
}

/// Whether `w` lies in the high half-space of the split of a cell at `level` with lower corner
/// `corner`.
pub(crate) fn high_side(w: &Vertex, corner: [u32; 3], level: usize, bits: u32) -> bool {
    let a = level % 3;
    w.corner[a] >= corner[a] + half(level, bits)
}
