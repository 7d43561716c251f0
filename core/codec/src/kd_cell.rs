//! The kd-tree's cells (paper 003 §3, GD02): a vertex's key in kd order and the side of a
//! cell's high half. Shared by the coder, its contexts, the geometry
//! ahead and the decoder's assembly.

use crate::complex::axis_bits;

/// Spreads the low 21 bits of `x` to every third bit (bit `i` to bit `3i`).
fn spread(x: u32) -> u64 {
    let mut x = (x & 0x1f_ffff) as u64;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// The full kd key of a grid point of a `bits`-bit grid: its coordinates' bits interleaved
/// x, y, z from the top (a Morton code), left-aligned in 64 bits, so that every kd level's key
/// is a prefix of it ([`kd_key`] is this key cut to `level` bits). Compute it once per vertex
/// and sort on it: the kd order of a cell's vertices at any level is this key's order.
pub fn morton_key(corner: [u32; 3], bits: u32) -> u64 {
    if bits == 0 {
        return 0;
    }
    let mask = if bits >= 32 {
        u32::MAX
    } else {
        (1u32 << bits) - 1
    };
    let m = (spread(corner[0] & mask) << 2)
        | (spread(corner[1] & mask) << 1)
        | spread(corner[2] & mask);
    m << (64 - 3 * bits)
}

/// The top `level` bits of a key (the key of the kd-cell at that level holding the point).
pub fn key_prefix(key: u64, level: usize) -> u64 {
    if level == 0 {
        0
    } else {
        key & (u64::MAX << (64 - level))
    }
}

/// The full-precision kd key of a vertex at kd level `level`: its split decisions, first on top
/// (bit `63 − j` is the side of the `j`-th split, axes x, y, z in turn).
pub fn kd_key(corner: [u32; 3], level: usize, bits: u32) -> u64 {
    key_prefix(morton_key(corner, bits), level)
}

/// Side of the high half of a split at kd `level`, in grid units.
pub fn half(level: usize, bits: u32) -> u32 {
    1u32 << (bits - axis_bits(level, level % 3) - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition: one split decision per level, read bit by bit.
    fn kd_key_by_levels(corner: [u32; 3], level: usize, bits: u32) -> u64 {
        let mut key = 0u64;
        for j in 0..level {
            let axis = j % 3;
            let bit = (corner[axis] >> (bits - 1 - (j / 3) as u32)) & 1;
            key |= (bit as u64) << (63 - j);
        }
        key
    }

    #[test]
    fn the_interleave_is_the_split_decisions() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for bits in 1..=20u32 {
            for _ in 0..200 {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let c =
                    [x as u32, (x >> 21) as u32, (x >> 42) as u32].map(|q| q & ((1 << bits) - 1));
                for level in 0..=3 * bits as usize {
                    assert_eq!(
                        kd_key(c, level, bits),
                        kd_key_by_levels(c, level, bits),
                        "{c:?} {level} {bits}"
                    );
                }
            }
            let top = (1u32 << bits) - 1;
            assert_eq!(
                morton_key([top; 3], bits),
                kd_key_by_levels([top; 3], 3 * bits as usize, bits)
            );
        }
    }
}
