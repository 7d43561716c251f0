//! The regular partition's cells (Belblidia & Perrin, section 2, after Rossignac & Borrel
//! 1993) as a dense table instead of a hash: pass V of the grid's fused passes (issue 33).
//!
//! The grid is cut into bricks of 4 × 4 × 4 cells. A top-level array holds one slot per brick
//! of the bounding box; only bricks that hold a vertex get their 64 cells (128 with feature
//! classes, which split every cell in two) in a pool. A vertex's cluster is then two array
//! reads away, with no probing, and the pool is dense where surfaces are.
//!
//! Cluster ids follow the order in which vertices first meet their cells (the same order as
//! `grid_partition.rs`, so the same ids). On one thread that is one sequential pass. On more,
//! every core takes part: each cell keeps the smallest index of its vertices (atomic min); a
//! vertex is its cell's first when it holds that minimum; blocks count their first vertices,
//! a prefix over the blocks numbers them, and every vertex reads its cell's number back. The
//! result is the sequential numbering exactly, with no serial step over the vertices.

use crate::blocks;
use crate::grid_frame::Grid;
use crate::grid_sums::{self, Sums};
use crate::options::GridSize;
use crate::partition::{Cell, Partition, UNUSED};
use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::atomic::{AtomicU32, AtomicU64};

/// Marks a vertex that is the first of its cell while the clusters are numbered.
const FIRST: u32 = 1 << 31;

/// The grid partition of the vertices with non-zero weight, through the brick table, and the
/// heaviest vertex of each cluster as `weight bits << 32 | !index` (the largest weight, the
/// first met among equals: pass S's first half, taken while the ids are read) and, with
/// `boxes` (the quadric representative's bound), the box of each cluster's vertices; `None`
/// when the box holds too many bricks for a dense top level (a cell size far below the
/// mesh's detail), where the caller falls back to `grid_partition.rs`'s hash.
pub(crate) fn grid_cells(
    positions: &[[f32; 3]],
    weights: &[f32],
    classes: Option<&[u8]>,
    bounds: &Cell,
    size: GridSize,
    keep_cells: bool,
    boxes: bool,
) -> Option<(Partition, Sums)> {
    let (grid, dims) = Grid::new(bounds, size);
    let bd: [u64; 3] = dims.map(|d| d.div_ceil(4));
    let bricks = bd[0].checked_mul(bd[1])?.checked_mul(bd[2])?;
    // The top level costs 4 bytes a brick: at most about what the positions take, and the
    // pool's slot ids must leave the FIRST bit free.
    let limit = (3 * positions.len() as u64).clamp(1 << 16, 1 << 24);
    if bricks > limit {
        return None;
    }
    let per_brick = if classes.is_some() { 128 } else { 64 };
    let referenced = |v: usize| weights[v] > 0.0;
    let brick_of = |c: [u32; 3]| {
        let b = [c[0] >> 2, c[1] >> 2, c[2] >> 2].map(u64::from);
        ((b[0] * bd[1] + b[1]) * bd[2] + b[2]) as usize
    };
    let local_of = |c: [u32; 3], v: usize| {
        let l = ((c[0] & 3) << 4 | (c[1] & 3) << 2 | (c[2] & 3)) as usize;
        match classes {
            Some(k) => 2 * l + usize::from(k[v] & 1),
            None => l,
        }
    };
    // Where each block's items start, from the blocks' counts.
    let firsts_of = |counts: &[u32]| {
        counts
            .iter()
            .scan(0u32, |n, &c| {
                let first = *n;
                *n += c;
                Some(first)
            })
            .collect::<Vec<u32>>()
    };
    let key = |v: usize| grid_sums::heavy_key(v, weights[v]);
    let scale = grid_sums::weight_scale(weights);
    let mut cluster_of = vec![UNUSED; positions.len()];
    let mut firsts: Vec<u32> = Vec::new();
    let clusters;
    let sums: Sums;
    if blocks::single_thread() {
        // One core: one pass numbers the cells as the vertices meet them (bricks taken as
        // they are met too) and finds each cluster's heaviest vertex.
        let mut top = vec![UNUSED; bricks as usize];
        let mut pool: Vec<u32> = Vec::new();
        // Reserved for as many clusters as vertices: address space only (the pages of a
        // buffer this large are its own mapping and count once touched), where growing by
        // doubling would copy the sums and leave the smaller copies on the heap.
        let n = cluster_of.len();
        let (mut heavy, mut sum) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n * grid_sums::SLOTS),
        );
        let mut bounds: Vec<u32> = Vec::with_capacity(if boxes { 6 * n } else { 0 });
        for (v, out) in cluster_of.iter_mut().enumerate() {
            if !referenced(v) {
                continue;
            }
            let p = &positions[v];
            let (c, u) = grid.locate(p);
            let t = &mut top[brick_of(c)];
            if *t == UNUSED {
                *t = (pool.len() / per_brick) as u32;
                pool.resize(pool.len() + per_brick, UNUSED);
            }
            let id = &mut pool[*t as usize * per_brick + local_of(c, v)];
            if *id == UNUSED {
                *id = heavy.len() as u32;
                heavy.push(0);
                sum.extend([0u64; grid_sums::SLOTS]);
                if boxes {
                    bounds.extend(grid_sums::EMPTY_BOX);
                }
                if keep_cells {
                    firsts.push(v as u32);
                }
            }
            let id = *id as usize;
            *out = id as u32;
            heavy[id] = heavy[id].max(key(v));
            let add = grid_sums::contribution(u, weights[v], scale);
            let s = &mut sum[id * grid_sums::SLOTS..][..7];
            for k in 0..7 {
                s[k] += add[k];
            }
            if boxes {
                let b = &mut bounds[6 * id..6 * id + 6];
                for k in 0..3 {
                    let o = grid_sums::ordered(p[k]);
                    b[k] = b[k].min(o);
                    b[3 + k] = b[3 + k].max(o);
                }
            }
        }
        clusters = heavy.len();
        sums = Sums {
            heavy,
            sums: sum,
            boxes: bounds,
        };
    } else {
        // V1: which bricks hold a vertex.
        let top: Vec<AtomicU32> = (0..bricks).map(|_| AtomicU32::new(UNUSED)).collect();
        blocks::ranges(positions.len()).for_each(|r| {
            let mut last = usize::MAX;
            for v in r {
                if referenced(v) {
                    let b = brick_of(grid.locate(&positions[v]).0);
                    if b != last {
                        top[b].store(0, Relaxed);
                        last = b;
                    }
                }
            }
        });
        // Bricks numbered in box order (their place in the pool).
        let mut top: Vec<u32> = top.into_iter().map(AtomicU32::into_inner).collect();
        let counts = blocks::map(top.len(), |r| {
            top[r].iter().filter(|&&t| t != UNUSED).count() as u32
        });
        let used_bricks: u32 = counts.iter().sum();
        top.par_chunks_mut(blocks::BLOCK)
            .zip(firsts_of(&counts))
            .for_each(|(chunk, mut next)| {
                for t in chunk.iter_mut().filter(|t| **t != UNUSED) {
                    *t = next;
                    next += 1;
                }
            });
        let slots = used_bricks as usize * per_brick;
        let slot_of = |v: usize| {
            let c = grid.locate(&positions[v]).0;
            top[brick_of(c)] as usize * per_brick + local_of(c, v)
        };
        // V2: each cell's smallest vertex; each vertex's slot meanwhile.
        let pool: Vec<AtomicU32> = (0..slots).map(|_| AtomicU32::new(UNUSED)).collect();
        cluster_of
            .par_chunks_mut(blocks::BLOCK)
            .enumerate()
            .for_each(|(b, out)| {
                for (i, o) in out.iter_mut().enumerate() {
                    let v = b * blocks::BLOCK + i;
                    if referenced(v) {
                        let s = slot_of(v);
                        if pool[s].load(Relaxed) > v as u32 {
                            pool[s].fetch_min(v as u32, Relaxed);
                        }
                        *o = s as u32;
                    }
                }
            });
        // V3: first vertices flagged and counted per block.
        let counts: Vec<u32> = cluster_of
            .par_chunks_mut(blocks::BLOCK)
            .enumerate()
            .map(|(b, out)| {
                let mut n = 0;
                for (i, o) in out.iter_mut().enumerate() {
                    let v = (b * blocks::BLOCK + i) as u32;
                    if *o != UNUSED && pool[*o as usize].load(Relaxed) == v {
                        *o |= FIRST;
                        n += 1;
                    }
                }
                n
            })
            .collect();
        clusters = counts.iter().sum::<u32>() as usize;
        // V4: the first vertices number their cells (each writes its own cell).
        cluster_of
            .par_chunks(blocks::BLOCK)
            .zip(firsts_of(&counts))
            .for_each(|(out, mut next)| {
                for &o in out.iter().filter(|&&o| o != UNUSED && o & FIRST != 0) {
                    pool[(o & !FIRST) as usize].store(next, Relaxed);
                    next += 1;
                }
            });
        if keep_cells {
            firsts = vec![0; clusters];
            let writes = blocks::DisjointWrites::new(&mut firsts);
            cluster_of
                .par_chunks(blocks::BLOCK)
                .enumerate()
                .for_each(|(b, out)| {
                    for (i, &o) in out.iter().enumerate() {
                        if o != UNUSED && o & FIRST != 0 {
                            let id = pool[(o & !FIRST) as usize].load(Relaxed);
                            writes.write(id as usize, (b * blocks::BLOCK + i) as u32);
                        }
                    }
                });
        }
        // V5 (with pass S): every vertex reads its cell's number and adds itself into the
        // cluster's sums and maxima (integers: the same whichever core adds first).
        let atomics = |n: usize, init: &dyn Fn(usize) -> u64| -> Vec<AtomicU64> {
            (0..n).map(|k| AtomicU64::new(init(k))).collect()
        };
        let heavy = atomics(clusters, &|_| 0);
        let sum = atomics(clusters * grid_sums::SLOTS, &|_| 0);
        let empty = |k: usize| u64::from(grid_sums::EMPTY_BOX[k % 6]);
        let bounds: Vec<AtomicU32> = (0..if boxes { 6 * clusters } else { 0 })
            .map(|k| AtomicU32::new(empty(k) as u32))
            .collect();
        cluster_of
            .par_chunks_mut(blocks::BLOCK)
            .enumerate()
            .for_each(|(b, out)| {
                for (i, o) in out.iter_mut().enumerate() {
                    if *o == UNUSED {
                        continue;
                    }
                    let v = b * blocks::BLOCK + i;
                    let id = pool[(*o & !FIRST) as usize].load(Relaxed) as usize;
                    *o = id as u32;
                    let k = key(v);
                    if k > heavy[id].load(Relaxed) {
                        heavy[id].fetch_max(k, Relaxed);
                    }
                    let p = &positions[v];
                    let add = grid_sums::contribution(grid.locate(p).1, weights[v], scale);
                    let s = &sum[id * grid_sums::SLOTS..][..7];
                    for k in 0..7 {
                        s[k].fetch_add(add[k], Relaxed);
                    }
                    if boxes {
                        let b = &bounds[6 * id..6 * id + 6];
                        for k in 0..3 {
                            let o = grid_sums::ordered(p[k]);
                            b[k].fetch_min(o, Relaxed);
                            b[3 + k].fetch_max(o, Relaxed);
                        }
                    }
                }
            });
        let plain = |a: Vec<AtomicU64>| a.into_iter().map(AtomicU64::into_inner).collect();
        sums = Sums {
            heavy: plain(heavy),
            sums: plain(sum),
            boxes: bounds.into_iter().map(AtomicU32::into_inner).collect(),
        };
    }
    let cells = firsts
        .par_iter()
        .map(|&v| grid.cell_box(grid.locate(&positions[v as usize]).0))
        .collect();
    let partition = Partition {
        cluster_of,
        clusters,
        cells,
    };
    Some((partition, sums))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid_partition::grid_partition;

    /// The brick table gives the hash's partition exactly (ids, count, cells), with and
    /// without classes, on one thread and on several.
    #[test]
    fn bricks_number_cells_as_the_hash_does() {
        let mut state = 99u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let n = 3 * blocks::BLOCK + 17;
        let positions: Vec<[f32; 3]> = (0..n).map(|_| [next(), next(), next() * 0.3]).collect();
        let weights: Vec<f32> = (0..n)
            .map(|v| if v % 11 == 3 { 0.0 } else { 1.0 })
            .collect();
        let classes: Vec<u8> = (0..n).map(|v| (v % 7 == 0) as u8).collect();
        let (bounds, _) = crate::partition::referenced_bounds(&positions, &weights).unwrap();
        for cells in [1, 5, 37, 150] {
            for k in [None, Some(&classes[..])] {
                let size = GridSize::CellsPerAxis(cells);
                let (want, _) = grid_partition(&positions, &weights, k, &bounds, size, true);
                for threads in [1, 2, 7] {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap();
                    let got = pool
                        .install(|| grid_cells(&positions, &weights, k, &bounds, size, true, false))
                        .unwrap()
                        .0;
                    assert_eq!(got.clusters, want.clusters, "{cells} cells, {threads}");
                    assert!(
                        got.cluster_of == want.cluster_of,
                        "{cells} cells, {threads}"
                    );
                    assert_eq!(got.cells, want.cells, "{cells} cells, {threads}");
                }
            }
        }
    }
}
