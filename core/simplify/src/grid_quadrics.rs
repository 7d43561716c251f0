//! The grid's face pass with the quadrics in it: pass F of issue 33's order B, V, F, S, C, O
//! for the quadric representative (Lindstrom 2000, section 3.2: each triangle's plane quadric
//! goes to the cells of its corners, once per distinct cell). The pass that decides each
//! face's fate from its clusters and writes the kept faces (`elimination.rs`) reads the same
//! corners and cluster ids the quadrics need, so one pass over the faces does both, before the
//! representatives; the zero-area test, which needs the representatives, moves after them
//! onto the kept faces (pass O, [`elimination::Fates::eliminate`]).
//!
//! The sums are the ones `representative.rs` computes, to the bit: a cluster's quadric is its
//! blocks' partial sums (each block's faces in face order, from zero) added in block order.
//! On one core a cluster's first block adds straight into its total (zero plus the same terms
//! in the same order) and later blocks into partials, found through a tag per cluster rather
//! than a hash table; on several, every block sums into partials of its own (a tag array per
//! core) and the partials are added in block order, a wave of blocks merging while the next
//! one sums.
//!
//! Every cluster's quadric is held at once (80 bytes a cluster), so the pass is taken only
//! when they fit in the share `representative.rs`'s chunks keep to ([`most_clusters`]); larger
//! partitions (targets above a sixth of the vertices) take the chunked passes.

use crate::blocks;
use crate::elimination::{Fate, Fates};
use crate::quadric::Quadric;
use crate::representative::{self, GRID_SHARE};
use rayon::prelude::*;
use std::sync::Mutex;

/// The most clusters of a mesh of `vertices` vertices whose quadrics are held at once: the
/// size of one of `representative.rs`'s chunks.
pub(crate) fn most_clusters(vertices: usize) -> usize {
    (vertices / GRID_SHARE).max(1 << 15)
}

/// A tag's slot for "sums straight into the total" (one core, the cluster's first block).
const DIRECT: u32 = u32::MAX;

/// What one block of faces leaves: its fate counts and kept faces (as `elimination::fates`
/// for triangles, before the area test), the clusters it touched that need a partial, and
/// their partial quadrics.
struct Part {
    counts: [u64; 4],
    written: Vec<u32>,
    keys: Vec<u32>,
    partials: Vec<Quadric>,
}

/// Pass F for the triangles `triangles` of a mesh at `positions` partitioned by `cluster_of`
/// into `n` clusters: every face's fate (collapsed when its corners are not in three distinct
/// clusters; the zero-area test is left to elimination), the kept faces, and every cluster's
/// quadric.
pub(crate) fn faces_and_quadrics(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    cluster_of: &[u32],
    n: usize,
) -> (Fates, Vec<Quadric>) {
    let mut fate = vec![Fate::Kept; triangles.len()];
    let mut q = vec![Quadric::default(); n];
    let blocks = triangles.len().div_ceil(blocks::BLOCK);
    let mut parts: Vec<([u64; 4], Vec<u32>)> = Vec::with_capacity(blocks);
    if blocks::single_thread() {
        // Tag of each cluster: the last block that touched it (high half) and its partial
        // there, or DIRECT while that block is its first.
        let mut tag = vec![u64::MAX; n];
        let (mut keys, mut partials) = (Vec::<u32>::new(), Vec::<Quadric>::new());
        for (b, fates) in fate.chunks_mut(blocks::BLOCK).enumerate() {
            let mut sink = OneCore {
                tag: &mut tag,
                q: &mut q,
                keys: &mut keys,
                partials: &mut partials,
                b: b as u64,
            };
            let part = block_pass(positions, triangles, cluster_of, b, fates, &mut sink);
            for (&c, p) in keys.iter().zip(&partials) {
                q[c as usize].add(p);
            }
            keys.clear();
            partials.clear();
            parts.push(part);
        }
    } else {
        // A tag array per core (the stamp is the block + 1, so no array is ever cleared).
        let scratch: Vec<Mutex<Vec<u64>>> = (0..rayon::current_num_threads())
            .map(|_| Mutex::new(Vec::new()))
            .collect();
        let block = |b: usize, fates: &mut [Fate]| -> Part {
            let core = rayon::current_thread_index().unwrap_or(0) % scratch.len();
            let mut tag = scratch[core].lock().expect("a core's own tags");
            if tag.len() != n {
                *tag = vec![0; n];
            }
            let mut sink = OneBlock {
                tag: &mut tag,
                keys: Vec::new(),
                partials: Vec::new(),
                stamp: (b as u64 + 1) << 32,
            };
            let (counts, written) =
                block_pass(positions, triangles, cluster_of, b, fates, &mut sink);
            Part {
                counts,
                written,
                keys: sink.keys,
                partials: sink.partials,
            }
        };
        let merge = |q: &mut [Quadric], done: Vec<Part>| -> Vec<([u64; 4], Vec<u32>)> {
            done.into_iter()
                .map(|p| {
                    for (&c, s) in p.keys.iter().zip(&p.partials) {
                        q[c as usize].add(s);
                    }
                    (p.counts, p.written)
                })
                .collect()
        };
        // A block per core a wave (the wave size does not change the sums: they are added in
        // block order whatever it is); one wave's partials merge while the next sums.
        let wave = rayon::current_num_threads().max(2);
        let mut chunks: Vec<&mut [Fate]> = fate.chunks_mut(blocks::BLOCK).collect();
        let mut pending: Option<Vec<Part>> = None;
        for first in (0..blocks).step_by(wave) {
            let these: Vec<&mut [Fate]> = chunks.drain(..wave.min(blocks - first)).collect();
            let sum = || {
                these
                    .into_par_iter()
                    .enumerate()
                    .map(|(i, fates)| block(first + i, fates))
                    .collect::<Vec<Part>>()
            };
            let previous = pending.take();
            let (done, merged) = rayon::join(sum, || previous.map(|p| merge(&mut q, p)));
            parts.extend(merged.into_iter().flatten());
            pending = Some(done);
        }
        if let Some(p) = pending {
            parts.extend(merge(&mut q, p));
        }
    }
    let (counts, written) = parts.into_iter().unzip();
    (Fates::before_areas(fate, counts, written), q)
}

/// Where a face's quadric goes for one of its clusters (a trait, not a closure, so that it
/// is inlined into the face loop).
trait Sink {
    fn add(&mut self, c: u32, fq: &Quadric);
}

/// One core, block `b`: a cluster's first block adds into its total, later ones into
/// partials (`tag`: the last block that touched each cluster, high half, and its partial
/// there or [`DIRECT`]).
struct OneCore<'a> {
    tag: &'a mut [u64],
    q: &'a mut [Quadric],
    keys: &'a mut Vec<u32>,
    partials: &'a mut Vec<Quadric>,
    b: u64,
}

impl Sink for OneCore<'_> {
    #[inline(always)]
    fn add(&mut self, c: u32, fq: &Quadric) {
        let t = &mut self.tag[c as usize];
        if *t == u64::MAX {
            *t = self.b << 32 | u64::from(DIRECT);
            self.q[c as usize].add(fq);
        } else if *t >> 32 == self.b {
            match *t as u32 {
                DIRECT => self.q[c as usize].add(fq),
                slot => self.partials[slot as usize].add(fq),
            }
        } else {
            *t = self.b << 32 | self.keys.len() as u64;
            self.keys.push(c);
            let mut p = Quadric::default();
            p.add(fq);
            self.partials.push(p);
        }
    }
}

/// One block on one of several cores: every cluster into a partial of the block's (`tag`:
/// the core's, `stamp` the block + 1 in the high half, the partial in the low half).
struct OneBlock<'a> {
    tag: &'a mut [u64],
    keys: Vec<u32>,
    partials: Vec<Quadric>,
    stamp: u64,
}

impl Sink for OneBlock<'_> {
    #[inline(always)]
    fn add(&mut self, c: u32, fq: &Quadric) {
        let t = &mut self.tag[c as usize];
        if *t & !0xffff_ffff != self.stamp {
            *t = self.stamp | self.keys.len() as u64;
            self.keys.push(c);
            self.partials.push(Quadric::default());
        }
        self.partials[*t as u32 as usize].add(fq);
    }
}

/// One block's faces: fates, counts and kept faces as `elimination::fates` gives them for
/// triangles (without the area test), and `sink.add(cluster, quadric)` for each face of non-zero
/// area once per distinct cluster of its corners.
#[inline(always)]
fn block_pass(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    cluster_of: &[u32],
    b: usize,
    fates: &mut [Fate],
    sink: &mut impl Sink,
) -> ([u64; 4], Vec<u32>) {
    let mut c = [0u64; 4];
    let start = b * blocks::BLOCK;
    // Room for every face of the block, as `elimination::fates` takes.
    let mut out = Vec::with_capacity(3 * fates.len());
    for (slot, t) in fates.iter_mut().zip(&triangles[start..]) {
        let v = t.map(|i| cluster_of[i as usize]);
        let distinct = v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
        if distinct {
            out.extend_from_slice(&v);
            c[0] += 1;
        } else {
            *slot = Fate::Collapsed;
            c[2] += 1;
        }
        if let Some(fq) = representative::triangle_quadric(t.map(|i| positions[i as usize])) {
            sink.add(v[0], &fq);
            if v[1] != v[0] {
                sink.add(v[1], &fq);
            }
            if v[2] != v[0] && v[2] != v[1] {
                sink.add(v[2], &fq);
            }
        }
    }
    c[1] = 3 * c[0];
    (c, out)
}
