//! The nSP-tree (paper 003 §5.1): a space-partitioning tree with `n` regular subdivisions per
//! axis, in which the kd-trees and complexes of §3 are embedded.
//!
//! The root refines the whole mesh from 0 to `p_r` bits per coordinate; each deeper level adds
//! `p_l = log2 n` bits (the last one possibly fewer, to end at `p`). A cell is split only when at
//! least `N_min` top simplices belong to it, a simplex belonging to every cell one of its vertices
//! lies in (duplication along cell borders, "Duplication de simplexes"), and here also only when
//! its children would hold `N_min / 8` on average (issue 34: tiny cells cost bits at their
//! borders). Because `n` is a power of two and `p_r ≥ p_l`, the kd-cells a cell ends with never
//! straddle two of its children.

use crate::error::CodecError;

/// Most bits of geometry ahead of the connectivity (§6.4 shows one and two).
pub const MAX_AHEAD: u32 = 4;

/// The user's parameters of the partition and the quantisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Params {
    /// Bits per coordinate, `p`.
    pub bits: u32,
    /// Subdivisions per axis, `n` (2 or 4: the index stores `n³` children in 64 bits).
    pub cell_split: u32,
    /// Fewest top simplices a cell must hold to be split, `N_min`; its children must also hold
    /// `N_min / 8` on average (`partition::worth_splitting`).
    pub min_cell: u64,
    /// Precision the root reaches before it is split, `p_r`.
    pub root_bits: u32,
    /// Bits of geometry coded ahead of the connectivity, `m` (§6.4; 0 = none).
    pub ahead: u32,
}

impl Default for Params {
    /// The paper's `n = 4` and Table 1's `p_r = 7` at 12 bits; `N_min` = 50 000 rather than §7's
    /// 5 000 to 8 000, with the split also waiting until its children are not tiny
    /// (`partition::worth_splitting`): every border vertex is refined again in each child cell
    /// holding one of its simplices, 2.3 b/v on the bunny, which 43 cells cost against one.
    fn default() -> Self {
        Params {
            bits: 12,
            cell_split: 4,
            min_cell: 50_000,
            root_bits: 7,
            ahead: 0,
        }
    }
}

impl Params {
    /// Checks the ranges the format supports.
    pub fn validate(&self) -> Result<(), CodecError> {
        let bad = |name, why: String| Err(CodecError::Parameter { name, why });
        if !(1..=crate::quantize::MAX_BITS).contains(&self.bits) {
            return bad(
                "--bits",
                format!("{} is outside 1..={}", self.bits, crate::quantize::MAX_BITS),
            );
        }
        if self.cell_split != 2 && self.cell_split != 4 {
            return bad("--cell-split", format!("{} is not 2 or 4", self.cell_split));
        }
        if self.min_cell == 0 {
            return bad(
                "--min-cell",
                "0: a cell needs at least one simplex to be split".into(),
            );
        }
        if self.root_bits < self.level_bits() || self.root_bits > self.bits {
            return bad(
                "--root-bits",
                format!(
                    "{} is outside {}..={} (log2 of --cell-split up to --bits)",
                    self.root_bits,
                    self.level_bits(),
                    self.bits
                ),
            );
        }
        if self.ahead > MAX_AHEAD {
            return bad(
                "--ahead",
                format!("{} is outside 0..={MAX_AHEAD}", self.ahead),
            );
        }
        Ok(())
    }

    /// kd levels of geometry ahead of the connectivity: three per bit.
    pub fn advance(&self) -> usize {
        3 * self.ahead as usize
    }

    /// Bits each level below the root adds, `p_l = log2 n`.
    pub fn level_bits(&self) -> u32 {
        self.cell_split.trailing_zeros()
    }

    /// Precision range `(start, end)` in bits of a cell at tree `depth`.
    pub fn precision(&self, depth: u32) -> (u32, u32) {
        if depth == 0 {
            return (0, self.root_bits.min(self.bits));
        }
        let start = (self.root_bits + (depth - 1) * self.level_bits()).min(self.bits);
        (start, (start + self.level_bits()).min(self.bits))
    }

    /// log2 of the side of a cell at `depth`, in grid units.
    pub fn side_log2(&self, depth: u32) -> u32 {
        self.bits.saturating_sub(depth * self.level_bits())
    }

    /// The cell at `depth` holding grid point `q`, as integer cell coordinates.
    pub fn cell_at(&self, depth: u32, q: [u32; 3]) -> [u32; 3] {
        q.map(|x| x >> self.side_log2(depth))
    }

    /// Which child (`x + n (y + n z)`) of `cell` (at `depth`) holds grid point `q`; `None` when
    /// `q` lies outside `cell` (a vertex of a border simplex, owned by a neighbour).
    pub fn child_of(&self, depth: u32, cell: [u32; 3], q: [u32; 3]) -> Option<usize> {
        if self.cell_at(depth, q) != cell {
            return None;
        }
        let n = self.cell_split as usize;
        let c = self.cell_at(depth + 1, q).map(|x| (x as usize) & (n - 1));
        Some(c[0] + n * (c[1] + n * c[2]))
    }

    /// Cell coordinates of child `position` of `cell`.
    pub fn child_cell(&self, cell: [u32; 3], position: usize) -> [u32; 3] {
        let n = self.cell_split as usize;
        let c = [position % n, (position / n) % n, position / (n * n)];
        std::array::from_fn(|a| cell[a] * n as u32 + c[a] as u32)
    }
}

/// One cell of the tree as the file's index records it (pre-order).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Node {
    /// Depth in the tree (0 = root).
    pub depth: u32,
    /// Integer coordinates of the cell among the cells of its depth (not stored: implied by the
    /// tree).
    pub cell: [u32; 3],
    /// Children present, as a bit mask over the `n³` positions.
    pub child_mask: u64,
    /// Indices of the children in the node list, in position order.
    pub children: Vec<usize>,
    /// Offset of the cell's code chunk in the file.
    pub offset: u64,
    /// Length of that chunk in bytes.
    pub len: u64,
    /// Vertices of the cell's complex when its codes are all applied.
    pub end_vertices: u64,
    /// Live simplices then.
    pub end_simplices: u64,
}
