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
    /// order, the same order the GPU kernel uses. Every row of `dst` is overwritten (it need
    /// not be zeroed).
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
        // Rows of 1–4 floats (positions, UVs, colours) sum in registers.
        match stride {
            0 => {}
            1 => self.apply_rows::<1>(src, dst),
            2 => self.apply_rows::<2>(src, dst),
            3 => self.apply_rows::<3>(src, dst),
            4 => self.apply_rows::<4>(src, dst),
            _ => self.apply_any(src, stride, dst),
        }
    }

    /// [`StencilTable::apply`] for rows of `N` floats.
    fn apply_rows<const N: usize>(&self, src: &[f32], dst: &mut [f32]) {
        let src: &[[f32; N]] = src.as_chunks::<N>().0;
        dst.par_chunks_mut(ROWS_PER_TASK * N)
            .enumerate()
            .for_each(|(task, out)| {
                let first = task * ROWS_PER_TASK;
                for (r, row) in out.as_chunks_mut::<N>().0.iter_mut().enumerate() {
                    let i = first + r;
                    let (s, e) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
                    let mut acc = [0.0f32; N];
                    for (&v, &w) in self.sources[s..e].iter().zip(&self.weights[s..e]) {
                        let x = &src[v as usize];
                        for c in 0..N {
                            acc[c] += w * x[c];
                        }
                    }
                    *row = acc;
                }
            });
    }

    /// [`StencilTable::apply`] for rows of any length.
    fn apply_any(&self, src: &[f32], stride: usize, dst: &mut [f32]) {
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
        let mut levels = Vec::new();
        Self::apply_chain_into(tables, src, stride, &mut levels);
        levels.pop().unwrap_or_else(|| src.to_vec())
    }

    /// [`StencilTable::apply_chain`] into `levels` (one buffer per table, resized as needed
    /// and reused across calls: animation frames then write into memory already mapped).
    /// Returns the last level's rows (`src` when there are no tables).
    pub fn apply_chain_into<'a>(
        tables: &[StencilTable],
        src: &'a [f32],
        stride: usize,
        levels: &'a mut Vec<Vec<f32>>,
    ) -> &'a [f32] {
        levels.resize_with(tables.len(), Vec::new);
        for (i, t) in tables.iter().enumerate() {
            let (done, rest) = levels.split_at_mut(i);
            let from = done.last().map_or(src, |v| v.as_slice());
            let to = &mut rest[0];
            to.resize(t.len() * stride, 0.0);
            t.apply(from, stride, to);
        }
        levels.last().map_or(src, |v| v.as_slice())
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

    #[test]
    fn every_stride_and_reused_buffers_give_the_same_rows() {
        // Rows mixing 1 to 5 terms over 7 sources; data of every stride from 1 to 6.
        let mut t = StencilTable {
            offsets: vec![0],
            source_count: 7,
            ..StencilTable::default()
        };
        for r in 0..50u32 {
            let n = 1 + r % 5;
            for k in 0..n {
                t.sources.push((r * 3 + k * 5) % 7);
                t.weights.push(1.0 / n as f32);
            }
            t.offsets.push(t.sources.len() as u32);
        }
        let second = StencilTable {
            source_count: 50,
            offsets: (0..=20).collect(),
            sources: (0..20).map(|i| i * 2).collect(),
            weights: vec![1.0; 20],
        };
        let tables = [t, second];
        let mut levels = Vec::new();
        for stride in 1..=6usize {
            let src: Vec<f32> = (0..7 * stride).map(|i| (i * i % 11) as f32).collect();
            // The reference: each row summed term by term, component by component.
            let want: Vec<f32> = (0..20)
                .flat_map(|i| {
                    let row = 2 * i;
                    let src = &src;
                    let t = &tables[0];
                    (0..stride).map(move |c| {
                        t.row(row)
                            .map(|(s, w)| w * src[s as usize * stride + c])
                            .fold(0.0, |a, x| a + x)
                    })
                })
                .collect();
            assert_eq!(
                StencilTable::apply_chain(&tables, &src, stride),
                want,
                "stride {stride}"
            );
            for _ in 0..2 {
                let got = StencilTable::apply_chain_into(&tables, &src, stride, &mut levels);
                assert_eq!(got, want.as_slice(), "stride {stride}, reused");
            }
        }
    }
}
