//! Regular partition (Belblidia & Perrin, section 2, after Rossignac & Borrel 1993): the
//! bounding box cut into a grid; every non-empty cell is one cluster. The cell size is the
//! largest detail that disappears.
//!
//! The grid goal takes `grid_cells.rs` (a dense brick table, sums streamed as it numbers);
//! this hash-table binning with member lists remains for grids whose box holds more bricks
//! than a dense table should (cells far below the mesh's detail); both place the cells by
//! `grid_frame.rs`.

use crate::blocks::{self, DisjointWrites};
use crate::cell_table::CellTable;
use crate::grid_frame::Grid;
use crate::options::GridSize;
use crate::partition::{Cell, Members, Partition, UNUSED};
use rayon::prelude::*;

/// Blocks binned per wave (see [`grid_partition`]): enough for every core, few enough that
/// a wave's block-local tables stay a fraction of the mesh.
const WAVE_BLOCKS: usize = 8;

/// Assigns every vertex with non-zero weight to the grid cell containing it, and lists the
/// vertices of every cluster. With `classes`, vertices of different classes never share a
/// cluster (boundary preservation). Cluster ids follow the order in which cells are first met,
/// so the output is deterministic.
///
/// Every core bins (see [`crate::blocks`]): each block of vertices finds its cells in a small
/// table of its own (in cache, where one table for the whole mesh would miss on almost every
/// vertex), numbering them in the order it meets them and counting their vertices; the blocks'
/// cells are then numbered in block order — which is the order in which the whole vertex
/// sequence meets them — a wave of blocks at a time, and each block-local cell learns how many
/// vertices of its cluster earlier blocks hold. A last parallel pass turns each vertex's
/// block-local id into its cluster id and writes the vertex into its cluster's list at once
/// (a counting sort whose counts the binning gave for free), so the lists come out in
/// increasing vertex order. The cells' statistics are summed afterwards, cluster by cluster,
/// over those lists (`cluster_stats::of_members`): holding them for every cell while binning
/// took more memory than the mesh.
pub(crate) fn grid_partition(
    positions: &[[f32; 3]],
    weights: &[f32],
    classes: Option<&[u8]>,
    bounds: &Cell,
    size: GridSize,
    keep_cells: bool,
) -> (Partition, Members) {
    let (grid, _) = Grid::new(bounds, size);
    let key_of = |p: &[f32; 3], class: u64| -> u64 {
        let c = grid.locate(p).0.map(u64::from);
        (((c[0] << 21 | c[1]) << 21 | c[2]) << 1) | class
    };
    let mut cluster_of = vec![UNUSED; positions.len()];
    let cell_box = |key: u64| {
        let c = [key >> 43, (key >> 22) & 0x1f_ffff, (key >> 1) & 0x1f_ffff];
        grid.cell_box(c.map(|x| x as u32))
    };
    let mut table = CellTable::with_capacity(blocks::BLOCK);
    let mut cells = Vec::new();
    // Vertices per cluster so far (in block order).
    let mut count: Vec<u32> = Vec::new();
    // Per block: the cluster id of each block-local cell, and how many vertices of that
    // cluster the earlier blocks hold.
    let mut maps: Vec<(Vec<u32>, Vec<u32>)> =
        Vec::with_capacity(positions.len().div_ceil(blocks::BLOCK));
    // Pass 2 (sequential, one step per block-local cell): cluster ids in first-met order,
    // and where each block's vertices of a cluster start within its list.
    let mut number = |local: Vec<(Vec<u64>, Vec<u32>)>| {
        for (keys, mut sizes) in local {
            let map = keys
                .iter()
                .zip(&mut sizes)
                .enumerate()
                .map(|(i, (&key, size))| {
                    if let Some(&ahead) = keys.get(i + 8) {
                        table.prefetch(ahead);
                    }
                    let id = table.id(key);
                    if id as usize == count.len() {
                        count.push(0);
                        if keep_cells {
                            cells.push(cell_box(key));
                        }
                    }
                    let before = count[id as usize];
                    count[id as usize] += *size;
                    *size = before;
                    id
                })
                .collect();
            maps.push((map, sizes));
        }
    };
    // The blocks go in waves of WAVE_BLOCKS, so that only one wave's tables are held at once;
    // the wave size does not depend on the thread count, and neither does the order in which
    // the blocks' cells are numbered (block order). While one wave is numbered (pass 2, one
    // core), the next one bins (pass 1, the other cores).
    let mut binned: Option<Vec<(Vec<u64>, Vec<u32>)>> = None;
    for (wave, chunk) in cluster_of
        .chunks_mut(WAVE_BLOCKS * blocks::BLOCK)
        .enumerate()
    {
        // Pass 1 (parallel): local ids, and the cell key and vertex count of each, per block.
        let bin = || {
            chunk
                .par_chunks_mut(blocks::BLOCK)
                .enumerate()
                .map(|(b, out)| {
                    let start = (wave * WAVE_BLOCKS + b) * blocks::BLOCK;
                    let mut table = CellTable::with_capacity(out.len());
                    let (mut keys, mut sizes) = (Vec::new(), Vec::new());
                    for (i, slot) in out.iter_mut().enumerate() {
                        let v = start + i;
                        if weights[v] <= 0.0 {
                            continue;
                        }
                        let class = classes.map_or(0, |c| u64::from(c[v]));
                        let key = key_of(&positions[v], class);
                        let id = table.id(key);
                        if id as usize == keys.len() {
                            keys.push(key);
                            sizes.push(0);
                        }
                        sizes[id as usize] += 1;
                        *slot = id;
                    }
                    (keys, sizes)
                })
                .collect()
        };
        let previous = binned.take();
        let (local, ()) = rayon::join(bin, || previous.into_iter().for_each(&mut number));
        binned = Some(local);
    }
    binned.into_iter().for_each(&mut number);
    // Cluster list starts: the counts turned, in place, into their exclusive prefix sum.
    let mut start = count;
    let mut total = 0u32;
    for s in &mut start {
        let n = *s;
        *s = total;
        total += n;
    }
    start.push(total);
    // Pass 3 (parallel): block-local ids to cluster ids, and every vertex into its list.
    let mut ids = vec![0u32; total as usize];
    // The places of a block's vertices in the lists are fixed by pass 2 (cluster start +
    // vertices of earlier blocks + rank within the block): no two blocks write the same one.
    let lists = DisjointWrites::new(&mut ids);
    cluster_of
        .par_chunks_mut(blocks::BLOCK)
        .zip(maps)
        .enumerate()
        .for_each(|(b, (out, (map, mut next)))| {
            let lists = &lists;
            for (i, c) in out.iter_mut().enumerate() {
                if *c == UNUSED {
                    continue;
                }
                let local = *c as usize;
                *c = map[local];
                let at = start[*c as usize] + next[local];
                next[local] += 1;
                lists.write(at as usize, (b * blocks::BLOCK + i) as u32);
            }
        });
    let partition = Partition {
        cluster_of,
        clusters: table.len() as usize,
        cells,
    };
    (partition, Members { start, ids })
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
        let (p, m) = grid_partition(&positions, &w, None, &b, GridSize::CellsPerAxis(5), true);
        assert_eq!(p.clusters, 25);
        // Every cluster lists exactly its vertices, in increasing order.
        for c in 0..p.clusters {
            let list = m.of(c);
            assert!(list.is_sorted() && !list.is_empty());
            assert!(list.iter().all(|&v| p.cluster_of[v as usize] == c as u32));
        }
        assert_eq!((0..p.clusters).map(|c| m.of(c).len()).sum::<usize>(), 121);
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
        let (p, _) = grid_partition(
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
