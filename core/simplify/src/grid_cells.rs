//! The regular partition's cells (Belblidia & Perrin, section 2, after Rossignac & Borrel
//! 1993) as a dense table instead of a hash: pass V of the grid's fused passes (issue 33).
//!
//! The grid is cut into bricks of 4 × 4 × 4 cells. A top-level array holds one slot per brick
//! of the bounding box; only bricks that hold a vertex get their 64 cells (128 with feature
//! classes, which split every cell in two) in a pool. A vertex's cluster is then two array
//! reads away, with no probing, and the pool is dense where surfaces are.
//!
//! Cluster ids follow the order in which vertices first meet their cells (the same order as
//! `grid_partition.rs`, so the same ids). That order is the cells first met in any prefix of
//! the vertices, in their order, then those of the rest not met before, in theirs. On one
//! core that is one sequential pass, which sums too (pass S). On more, each core numbers a
//! contiguous chunk of the vertices on its own, in one sequential pass (its own brick table
//! and local ids); a short serial pass over the later chunks' cells (not their vertices)
//! gives each its global id; and one parallel pass has every vertex read its global id and
//! add itself into its cluster's sums (integers, maxima and minima: the same bits in any
//! order). The result is the sequential numbering exactly, whatever the number of chunks,
//! in two passes over the vertices (the design's atomic-minimum numbering took five).

use crate::blocks;
use crate::grid_frame::Grid;
use crate::grid_sums::{self, Sums};
use crate::options::GridSize;
use crate::partition::{Cell, Partition, UNUSED};
use rayon::prelude::*;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::atomic::{AtomicU32, AtomicU64};

/// The grid partition of the vertices with non-zero weight, through the brick table, and the
/// heaviest vertex of each cluster as `weight bits << 32 | !index` (the largest weight, the
/// first met among equals: pass S's first half, taken while the ids are read) and, with
/// the box of each cluster's vertices (the quadric representative's bound) while there are
/// at most `box_limit` clusters (beyond, none: a later pass takes them once the sums are
/// freed, so that the boxes do not raise the peak memory); `None`
/// when the box holds too many bricks for a dense top level (a cell size far below the
/// mesh's detail), where the caller falls back to `grid_partition.rs`'s hash.
pub(crate) fn grid_cells(
    positions: &[[f32; 3]],
    weights: &[f32],
    classes: Option<&[u8]>,
    bounds: &Cell,
    size: GridSize,
    keep_cells: bool,
    box_limit: usize,
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
    let key = |v: usize| grid_sums::heavy_key(v, weights[v]);
    let scale = grid_sums::weight_scale(weights);
    let n = positions.len();
    let mut cluster_of = vec![UNUSED; n];
    // One chunk of vertices a core (the ids do not depend on how many: see the module's
    // note), each numbered on its own; on one core the same pass sums.
    let chunks = rayon::current_num_threads().clamp(1, n.div_ceil(blocks::BLOCK).max(1));
    let single = chunks == 1;
    let len = n.div_ceil(chunks).max(1);
    let mut parts: Vec<Chunk> = cluster_of
        .par_chunks_mut(len)
        .enumerate()
        .map(|(k, out)| {
            let first = k * len;
            let capacity = if k == 0 { n } else { out.len() };
            let mut c = Chunk::new(bricks as usize, capacity, box_limit, single);
            for (i, o) in out.iter_mut().enumerate() {
                let v = first + i;
                if !referenced(v) {
                    continue;
                }
                let p = &positions[v];
                let (cell, u) = grid.locate(p);
                let brick = brick_of(cell);
                let slot = local_of(cell, v);
                let id = c.id(brick, slot, per_brick, v as u32, keep_cells);
                *o = id as u32;
                if single {
                    let add = grid_sums::contribution(u, weights[v], scale);
                    c.add(id, key(v), &add, p);
                }
            }
            if k > 0 {
                // A later chunk's table is done with: its cells list what the merge needs.
                (c.top, c.pool) = (Vec::new(), Vec::new());
            }
            c
        })
        .collect();
    if parts.is_empty() {
        parts.push(Chunk::new(bricks as usize, 0, box_limit, single));
    }
    let rest = parts.split_off(1);
    let mut all = parts.pop().expect("one chunk at least");
    if single {
        let firsts = std::mem::take(&mut all.firsts);
        let sums = Sums {
            heavy: all.heavy,
            sums: all.sums,
            boxes: all.bounds,
        };
        let clusters = sums.heavy.len();
        return Some(finish(cluster_of, clusters, firsts, sums, positions, &grid));
    }
    // The later chunks' cells into the first's table (a serial pass over cells, not
    // vertices): a cell already met keeps its id, a new one is numbered next.
    let maps: Vec<Vec<u32>> = std::iter::once(Vec::new())
        .chain(rest.into_iter().map(|c| {
            (0..c.cells.len())
                .map(|l| {
                    let cell = c.cells[l] as usize;
                    let (brick, slot) = (cell / per_brick, cell % per_brick);
                    let first = if keep_cells { c.firsts[l] } else { 0 };
                    all.id(brick, slot, per_brick, first, keep_cells) as u32
                })
                .collect()
        }))
        .collect();
    let clusters = all.cells.len();
    drop((all.top, all.pool, all.cells));
    // Pass S: every vertex reads its global id and adds itself into the cluster's sums,
    // maxima and minima (integers: the same whichever core adds first).
    let atomics = |n: usize, init: &dyn Fn(usize) -> u64| -> Vec<AtomicU64> {
        (0..n).map(|k| AtomicU64::new(init(k))).collect()
    };
    let heavy = atomics(clusters, &|_| 0);
    let sum = atomics(clusters * grid_sums::SLOTS, &|_| 0);
    let boxes = if clusters <= box_limit {
        6 * clusters
    } else {
        0
    };
    let bounds: Vec<AtomicU32> = (0..boxes)
        .map(|k| AtomicU32::new(grid_sums::EMPTY_BOX[k % 6]))
        .collect();
    cluster_of
        .par_chunks_mut(len)
        .zip(maps)
        .enumerate()
        .for_each(|(k, (out, map))| {
            for (i, o) in out.iter_mut().enumerate() {
                if *o == UNUSED {
                    continue;
                }
                if k > 0 {
                    *o = map[*o as usize];
                }
                let (v, id) = (k * len + i, *o as usize);
                let h = key(v);
                if h > heavy[id].load(Relaxed) {
                    heavy[id].fetch_max(h, Relaxed);
                }
                let p = &positions[v];
                let add = grid_sums::contribution(grid.locate(p).1, weights[v], scale);
                let s = &sum[id * grid_sums::SLOTS..][..7];
                for k in 0..7 {
                    s[k].fetch_add(add[k], Relaxed);
                }
                if boxes != 0 {
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
    let sums = Sums {
        heavy: plain(heavy),
        sums: plain(sum),
        boxes: bounds.into_iter().map(AtomicU32::into_inner).collect(),
    };
    Some(finish(
        cluster_of, clusters, all.firsts, sums, positions, &grid,
    ))
}

/// The partition from its ids and the cells' first vertices (their boxes, when kept).
fn finish(
    cluster_of: Vec<u32>,
    clusters: usize,
    firsts: Vec<u32>,
    sums: Sums,
    positions: &[[f32; 3]],
    grid: &Grid,
) -> (Partition, Sums) {
    let cells = firsts
        .par_iter()
        .map(|&v| grid.cell_box(grid.locate(&positions[v as usize]).0))
        .collect();
    let partition = Partition {
        cluster_of,
        clusters,
        cells,
    };
    (partition, sums)
}

/// One chunk's cells, numbered as its vertices meet them (bricks taken as they are met too),
/// and on one core each cell's sums ([`Sums`]).
struct Chunk {
    /// Pool place of each brick of the box that holds a vertex of the chunk.
    top: Vec<u32>,
    /// Local id of each cell of the pool's bricks.
    pool: Vec<u32>,
    heavy: Vec<u64>,
    sums: Vec<u64>,
    bounds: Vec<u32>,
    /// First vertex of each cell (kept cells only).
    firsts: Vec<u32>,
    /// Each cell as brick × cells a brick + its place in the brick (several cores only).
    cells: Vec<u32>,
    /// Most cells the boxes are taken for (0: none).
    box_limit: usize,
    /// Whether the sums are taken (one core: one pass does all).
    with_sums: bool,
}

impl Chunk {
    /// A chunk of a box of `bricks` bricks, with room for `capacity` cells (address space
    /// only: the pages of a buffer this large are its own mapping and count once touched,
    /// where growing by doubling would copy the sums and leave the smaller copies behind).
    fn new(bricks: usize, capacity: usize, box_limit: usize, with_sums: bool) -> Self {
        let room = if with_sums { capacity } else { 0 };
        Chunk {
            top: vec![UNUSED; bricks],
            pool: Vec::new(),
            heavy: Vec::with_capacity(room),
            sums: Vec::with_capacity(room * grid_sums::SLOTS),
            // (At least 4 MiB: its own mapping, so that its pages go back to the system
            // when it is dropped past the limit, not to a heap that keeps them.)
            bounds: Vec::with_capacity((6 * room.min(box_limit)).max(1 << 20)),
            firsts: Vec::new(),
            cells: Vec::with_capacity(if with_sums { 0 } else { capacity }),
            box_limit: if with_sums { box_limit } else { 0 },
            with_sums,
        }
    }

    /// The id of cell `slot` of brick `brick`, numbered next (first vertex `first`) when the
    /// chunk meets it for the first time.
    #[inline(always)]
    fn id(&mut self, brick: usize, slot: usize, per_brick: usize, first: u32, keep: bool) -> usize {
        let t = &mut self.top[brick];
        if *t == UNUSED {
            *t = (self.pool.len() / per_brick) as u32;
            self.pool.resize(self.pool.len() + per_brick, UNUSED);
        }
        let id = &mut self.pool[*t as usize * per_brick + slot];
        if *id == UNUSED {
            if self.with_sums {
                *id = self.heavy.len() as u32;
                self.heavy.push(0);
                self.sums.extend([0u64; grid_sums::SLOTS]);
                if self.heavy.len() > self.box_limit {
                    self.box_limit = 0;
                    self.bounds = Vec::new();
                } else {
                    self.bounds.extend(grid_sums::EMPTY_BOX);
                }
            } else {
                *id = self.cells.len() as u32;
                self.cells.push((brick * per_brick + slot) as u32);
            }
            if keep {
                self.firsts.push(first);
            }
        }
        *id as usize
    }

    /// Vertex at `p` with heaviest key `key` and sums `add` into cell `id`.
    #[inline(always)]
    fn add(&mut self, id: usize, key: u64, add: &[u64; 7], p: &[f32; 3]) {
        self.heavy[id] = self.heavy[id].max(key);
        let s = &mut self.sums[id * grid_sums::SLOTS..][..7];
        for k in 0..7 {
            s[k] += add[k];
        }
        if self.box_limit != 0 {
            let b = &mut self.bounds[6 * id..6 * id + 6];
            for k in 0..3 {
                let o = grid_sums::ordered(p[k]);
                b[k] = b[k].min(o);
                b[3 + k] = b[3 + k].max(o);
            }
        }
    }
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
                        .install(|| grid_cells(&positions, &weights, k, &bounds, size, true, 0))
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
