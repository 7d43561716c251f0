//! Stencil tables: the apply phase of refinement (paper 002, section 6: the GPU part evaluates
//! one new vertex per thread from a fixed list of old vertices and weights).
//!
//! A level's table says, for every vertex of the refined mesh, which vertices of the coarser
//! mesh it is made of and with which weights: `new[i] = Σ weights[k] · old[sources[k]]` for
//! `k` in `offsets[i]..offsets[i + 1]`. Tables depend only on the cage's topology (and its
//! creases), so an animated sequence builds them once and applies them to every frame. The
//! same table applies to positions and to any per-vertex primvar, row by row.

use rayon::prelude::*;

/// One refinement level's stencils, in compressed-row form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StencilTable {
    /// Row starts: `offsets.len()` = new vertices + 1, `offsets[0] = 0`.
    pub offsets: Vec<u32>,
    /// Coarse vertex of each term.
    pub sources: Vec<u32>,
    /// Weight of each term (a row's weights sum to 1).
    pub weights: Vec<f32>,
    /// Vertices of the coarse level (every source is below this).
    pub source_count: u32,
}

/// Rows per parallel task: a row is a handful of multiply-adds, so tasks must be large.
const ROWS_PER_TASK: usize = 4096;

impl StencilTable {
    /// Number of refined vertices.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when the table makes no vertex.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The terms of row `i`: (source, weight) pairs.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f32)> + '_ {
        let (s, e) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
        self.sources[s..e]
            .iter()
            .copied()
            .zip(self.weights[s..e].iter().copied())
    }

    /// Applies the table to `src` (`source_count` rows of `stride` floats) and writes
    /// `len()` rows of `stride` floats to `dst`, in parallel. Sums are taken in f32 in row
    /// order, the same order the GPU kernel uses.
    ///
    /// # Panics
    /// If `src` or `dst` have the wrong length.
    pub fn apply(&self, src: &[f32], stride: usize, dst: &mut [f32]) {
        assert_eq!(
            src.len(),
            self.source_count as usize * stride,
            "source rows"
        );
        assert_eq!(dst.len(), self.len() * stride, "destination rows");
        if stride == 0 {
            return;
        }
        dst.par_chunks_mut(ROWS_PER_TASK * stride)
            .enumerate()
            .for_each(|(task, out)| {
                let first = task * ROWS_PER_TASK;
                for (r, row) in out.chunks_exact_mut(stride).enumerate() {
                    row.fill(0.0);
                    for (s, w) in self.row(first + r) {
                        let from = &src[s as usize * stride..][..stride];
                        for (o, x) in row.iter_mut().zip(from) {
                            *o += w * x;
                        }
                    }
                }
            });
    }

    /// Applies a chain of tables (level 1, 2, ...) to `src`, returning the last level's rows.
    pub fn apply_chain(tables: &[StencilTable], src: &[f32], stride: usize) -> Vec<f32> {
        let mut cur = src.to_vec();
        for t in tables {
            let mut next = vec![0.0; t.len() * stride];
            t.apply(&cur, stride, &mut next);
            cur = next;
        }
        cur
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn midpoint_table_averages_rows() {
        // Two old vertices, three new: the first, the midpoint, the second.
        let t = StencilTable {
            offsets: vec![0, 1, 3, 4],
            sources: vec![0, 0, 1, 1],
            weights: vec![1.0, 0.5, 0.5, 1.0],
            source_count: 2,
        };
        let src = [0.0, 10.0, 2.0, 20.0];
        let mut dst = [0.0; 6];
        t.apply(&src, 2, &mut dst);
        assert_eq!(dst, [0.0, 10.0, 1.0, 15.0, 2.0, 20.0]);
        assert_eq!(
            StencilTable::apply_chain(std::slice::from_ref(&t), &src, 2),
            dst.to_vec()
        );
    }
}
