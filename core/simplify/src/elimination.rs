//! Elimination (Belblidia & Perrin, section 2, "élimination"): after every vertex moved to its
//! cluster, remove what collapsed — zero-length edges, zero-angle corners, zero-area faces and
//! duplicate faces (also reversed ones, as stacked CAD solids produce) — so that the
//! simplification actually lowers the complexity.

use crate::area_vector;
use crate::blocks::{self, DisjointWrites};
use crate::partition::UNUSED;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use tessd_mesh::Mesh;

/// What became of an input face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum Fate {
    /// It is an output face.
    Kept,
    /// It collapsed: fewer than 3 distinct corners, or zero area (its image is a segment or a
    /// point, see `coverage.rs`).
    Collapsed,
    /// It repeats an earlier kept face.
    Duplicate,
}

/// Faces over cluster ids, with where each came from.
#[derive(Debug, Default)]
pub(crate) struct Eliminated {
    /// Compressed-row faces, as in [`Mesh`].
    pub face_offsets: Vec<u32>,
    /// Cluster id of each corner.
    pub face_indices: Vec<u32>,
    /// The fate of each input face (one byte a face: the output faces are the kept ones, in
    /// order, so no list of source faces is held).
    pub fate: Vec<Fate>,
    /// The input corner (index into the input's `face_indices`) of each output corner.
    pub source_corner: Vec<u32>,
    /// Faces removed because they collapsed (fewer than 3 distinct corners or zero area).
    pub degenerate: u64,
    /// Of those, faces with 3 distinct clusters whose representatives are collinear.
    pub flattened: u64,
    /// Faces removed as duplicates of an earlier face.
    pub duplicates: u64,
}

impl Eliminated {
    /// The input face of each output face, in order.
    pub(crate) fn source_faces(&self) -> impl Iterator<Item = u32> + '_ {
        self.faces_with(Fate::Kept)
    }

    /// The input faces that collapsed, in order.
    pub(crate) fn collapsed(&self) -> impl Iterator<Item = u32> + '_ {
        self.faces_with(Fate::Collapsed)
    }

    fn faces_with(&self, fate: Fate) -> impl Iterator<Item = u32> + '_ {
        (self.fate.iter().enumerate())
            .filter(move |(_, f)| **f == fate)
            .map(|(f, _)| f as u32)
    }
}

/// Maps every face of `mesh` through `cluster_of` and removes collapsed and duplicate faces.
/// The first of several duplicates is kept, so the result is deterministic. `corners`: also
/// record each output corner's input corner (needed only to carry face-varying attributes).
///
/// Two passes over fixed blocks of faces, on every core ([`crate::blocks`]): the first decides
/// each face's fate and counts what each block keeps, the second writes the surviving faces
/// straight into their final place in outputs of the exact size (no per-block parts to join,
/// so the faces are never held twice); duplicates are then found by bucketing faces by their
/// smallest cluster ([`find_duplicates`]) and squeezed out in place.
///
/// (The pipeline runs the two steps itself, [`fates`] then [`Fates::eliminate`], to free what
/// it can in between.)
#[cfg(test)]
pub(crate) fn eliminate(
    mesh: &Mesh,
    cluster_of: &[u32],
    reps: &[[f32; 3]],
    corners: bool,
) -> Eliminated {
    fates(mesh, cluster_of, reps).eliminate(mesh, cluster_of, reps, corners)
}

/// [`eliminate`]'s first pass: the fate of every face, and what each block keeps.
pub(crate) struct Fates {
    fate: Vec<Fate>,
    /// Per block: kept faces, kept corners, degenerate faces, flattened faces.
    counts: Vec<[u64; 4]>,
    /// All-triangle meshes: the kept faces' clusters, written by the fate pass itself (pass
    /// F: one pass over the faces), block by block; [`Fates::eliminate`] copies them into
    /// place.
    written: Option<Vec<Vec<u32>>>,
    /// The zero-area test is still to run on the written faces (pass O): the grid's face
    /// pass decided the fates from the clusters alone, before the representatives.
    areas_pending: bool,
}

impl Fates {
    /// Faces with 3 distinct clusters whose representatives are collinear.
    pub(crate) fn flattened(&self) -> u64 {
        self.counts.iter().map(|c| c[3]).sum()
    }

    /// The fates of a triangle mesh decided from its clusters alone, block by block (`fate`,
    /// per block `counts` as [`fates`] keeps them and the `written` kept faces): a face is
    /// kept when its corners are in three distinct clusters. [`Fates::eliminate`] then
    /// runs the zero-area test on the kept faces only (issue 33's pass O: a duplicate of a
    /// zero-area face is zero-area too), with the same result as [`fates`].
    pub(crate) fn before_areas(
        fate: Vec<Fate>,
        counts: Vec<[u64; 4]>,
        written: Vec<Vec<u32>>,
    ) -> Fates {
        Fates {
            fate,
            counts,
            written: Some(written),
            areas_pending: true,
        }
    }
}

/// Decides the fate of every face of `mesh` under `cluster_of` and `reps` (collapsed or kept;
/// duplicates are found later).
pub(crate) fn fates(mesh: &Mesh, cluster_of: &[u32], reps: &[[f32; 3]]) -> Fates {
    let mut fate = vec![Fate::Kept; mesh.face_count()];
    if let Some(triangles) = mesh.triangles() {
        // All triangles, the common case: three ids to compare, no offsets to read, and the
        // kept faces written at once, each block's into a buffer of its own (kept faces
        // only: a few KiB to a few hundred, on the heap) that elimination copies into place.
        let parts: Vec<([u64; 4], Vec<u32>)> = fate
            .par_chunks_mut(blocks::BLOCK)
            .enumerate()
            .map(|(b, fates)| {
                let mut c = [0u64; 4];
                let start = b * blocks::BLOCK;
                // Room for every face of the block: one size for every block and call, so
                // that the heap hands the same chunks back (pages touched only where kept).
                let mut out = Vec::with_capacity(3 * fates.len());
                for (slot, t) in fates.iter_mut().zip(&triangles[start..]) {
                    let v = t.map(|i| cluster_of[i as usize]);
                    let distinct = v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
                    if distinct && !zero_area_triangle(v, reps) {
                        out.extend_from_slice(&v);
                        c[0] += 1;
                    } else {
                        *slot = Fate::Collapsed;
                        c[2] += 1;
                        c[3] += u64::from(distinct);
                    }
                }
                c[1] = 3 * c[0];
                (c, out)
            })
            .collect();
        let (counts, written) = parts.into_iter().unzip();
        return Fates {
            fate,
            counts,
            written: Some(written),
            areas_pending: false,
        };
    }
    // Pass 1: fates, and per block (kept faces, kept corners, degenerate, flattened).
    let counts: Vec<[u64; 4]> = fate
        .par_chunks_mut(blocks::BLOCK)
        .enumerate()
        .map(|(b, fates)| {
            let mut c = [0u64; 4];
            let start = b * blocks::BLOCK;
            let mut ring = Vec::new();
            for (i, slot) in fates.iter_mut().enumerate() {
                let f = start + i;
                match image(mesh, cluster_of, reps, f, &mut ring) {
                    Image::Face(corners) => {
                        c[0] += 1;
                        c[1] += corners as u64;
                    }
                    Image::Collapsed { distinct } => {
                        *slot = Fate::Collapsed;
                        c[2] += 1;
                        c[3] += u64::from(distinct);
                    }
                }
            }
            c
        })
        .collect();
    Fates {
        fate,
        counts,
        written: None,
        areas_pending: false,
    }
}

impl Fates {
    /// [`eliminate`]'s second pass and the removal of duplicates.
    pub(crate) fn eliminate(
        self,
        mesh: &Mesh,
        cluster_of: &[u32],
        reps: &[[f32; 3]],
        corners: bool,
    ) -> Eliminated {
        let Fates {
            mut fate,
            mut counts,
            mut written,
            areas_pending,
        } = self;
        let n = mesh.face_count();
        if let (Some(parts), true) = (&mut written, areas_pending) {
            // Pass O: the kept faces' area test, each block's in place.
            parts
                .par_iter_mut()
                .zip(fate.par_chunks_mut(blocks::BLOCK))
                .zip(counts.par_iter_mut())
                .for_each(|((part, fates), c)| {
                    let mut w = 0;
                    let kept = fates.iter_mut().filter(|f| **f == Fate::Kept);
                    for (k, slot) in kept.enumerate() {
                        let t = [part[3 * k], part[3 * k + 1], part[3 * k + 2]];
                        if zero_area_triangle(t, reps) {
                            *slot = Fate::Collapsed;
                            c[0] -= 1;
                            c[1] -= 3;
                            c[2] += 1;
                            c[3] += 1;
                        } else {
                            part[w..w + 3].copy_from_slice(&t);
                            w += 3;
                        }
                    }
                    part.truncate(w);
                });
        }
        let faces: usize = counts.iter().map(|c| c[0] as usize).sum();
        let total: usize = counts.iter().map(|c| c[1] as usize).sum();
        if let Some(parts) = written {
            // Triangles the fate pass wrote: each block's copied into its place (parallel;
            // every block's place follows from the counts).
            let mut indices = vec![0u32; total];
            blocks::disjoint_slices(
                &mut indices,
                blocks::consecutive(parts.iter().map(Vec::len)),
            )
            .into_par_iter()
            .zip(&parts)
            .for_each(|(to, part)| to.copy_from_slice(part));
            drop(parts);
            let mut out = Eliminated {
                face_offsets: (0..=faces as u32).into_par_iter().map(|f| 3 * f).collect(),
                face_indices: indices,
                source_corner: Vec::new(),
                degenerate: counts.iter().map(|c| c[2]).sum(),
                flattened: counts.iter().map(|c| c[3]).sum(),
                ..Eliminated::default()
            };
            if corners {
                out.source_corner = vec![0; total];
                let fate = &fate;
                let lengths = counts.iter().map(|c| c[1] as usize);
                let parts =
                    blocks::disjoint_slices(&mut out.source_corner, blocks::consecutive(lengths));
                parts.into_par_iter().enumerate().for_each(|(b, s)| {
                    let range = b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(n);
                    let kept = range.filter(|&f| fate[f] == Fate::Kept);
                    for (k, f) in kept.enumerate() {
                        for j in 0..3 {
                            s[3 * k + j] = 3 * f as u32 + j as u32;
                        }
                    }
                });
            }
            out.fate = fate;
            remove_duplicates(&mut out, &counts, reps.len(), corners);
            return out;
        }
        let mut out = Eliminated {
            face_offsets: vec![0; faces + 1],
            face_indices: vec![0; total],
            source_corner: vec![0; if corners { total } else { 0 }],
            degenerate: counts.iter().map(|c| c[2]).sum(),
            flattened: counts.iter().map(|c| c[3]).sum(),
            ..Eliminated::default()
        };
        // Pass 2: each block writes its faces into its own slices of the outputs.
        {
            let mut jobs = Vec::with_capacity(counts.len());
            let (mut offsets, mut indices) =
                (&mut out.face_offsets[1..], &mut out.face_indices[..]);
            let mut sources = &mut out.source_corner[..];
            let mut base = 0u32;
            for (b, c) in counts.iter().enumerate() {
                let (o, rest) = std::mem::take(&mut offsets).split_at_mut(c[0] as usize);
                offsets = rest;
                let (i, rest) = std::mem::take(&mut indices).split_at_mut(c[1] as usize);
                indices = rest;
                let k = if corners { c[1] as usize } else { 0 };
                let (s, rest) = std::mem::take(&mut sources).split_at_mut(k);
                sources = rest;
                jobs.push((b, base, o, i, s));
                base += c[1] as u32;
            }
            let fate = &fate;
            jobs.into_par_iter()
                .for_each(|(b, base, offsets, indices, sources)| {
                    let range = b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(n);
                    write_faces(
                        mesh, cluster_of, fate, range, base, offsets, indices, sources,
                    );
                });
        }
        out.fate = fate;
        remove_duplicates(&mut out, &counts, reps.len(), corners);
        out
    }
}

/// Finds the duplicates among `out`'s faces ([`find_duplicates`]; `counts`: the kept faces
/// of each block of input faces), turns their fates and squeezes them out in place.
fn remove_duplicates(out: &mut Eliminated, counts: &[[u64; 4]], clusters: usize, corners: bool) {
    let faces = out.face_offsets.len() - 1;
    let duplicate = find_duplicates(out, clusters);
    out.duplicates = duplicate.len() as u64;
    if duplicate.is_empty() {
        return;
    }
    // The input faces of the duplicates change fate (parallel over the blocks of input
    // faces: each knows from the counts how many kept faces come before it).
    let firsts: Vec<u64> = counts
        .iter()
        .scan(0u64, |before, c| {
            let first = *before;
            *before += c[0];
            Some(first)
        })
        .collect();
    out.fate
        .par_chunks_mut(blocks::BLOCK)
        .zip(firsts)
        .for_each(|(fates, first)| {
            let from = duplicate.partition_point(|&d| u64::from(d) < first);
            let mut next = duplicate[from..].iter().peekable();
            let kept = fates.iter_mut().filter(|f| **f == Fate::Kept);
            for (i, f) in kept.enumerate() {
                if next.peek().is_none() {
                    break;
                }
                if next
                    .next_if(|&&d| u64::from(d) == first + i as u64)
                    .is_some()
                {
                    *f = Fate::Duplicate;
                }
            }
        });
    // Squeeze the duplicates out in place, a run of faces between two duplicates at a
    // time (one move each); the write position never passes the read position.
    let (mut corner_w, mut face_w) = (0usize, 0usize);
    let runs = duplicate
        .iter()
        .map(|&d| d as usize)
        .chain(std::iter::once(faces));
    let mut from = 0usize;
    for dup in runs {
        // Faces from..dup survive; their corners move down by (corners dropped so far).
        let (s, e) = (
            out.face_offsets[from] as usize,
            out.face_offsets[dup] as usize,
        );
        let shift = (s - corner_w) as u32;
        out.face_indices.copy_within(s..e, corner_w);
        if corners {
            out.source_corner.copy_within(s..e, corner_w);
        }
        // Offsets from + 1 ..= dup end those faces: shifted down in place, then moved.
        out.face_offsets[from + 1..=dup]
            .iter_mut()
            .for_each(|o| *o -= shift);
        out.face_offsets.copy_within(from + 1..=dup, face_w + 1);
        face_w += dup - from;
        corner_w += e - s;
        from = dup + 1;
    }
    out.face_indices.truncate(corner_w);
    out.source_corner
        .truncate(if corners { corner_w } else { 0 });
    out.face_offsets.truncate(face_w + 1);
}

/// How many clusters the faces that survive elimination use: [`eliminate`]'s output vertex
/// count without building its faces (duplicates use the clusters of the face they repeat).
pub(crate) fn count_used(mesh: &Mesh, cluster_of: &[u32], reps: &[[f32; 3]]) -> usize {
    let used: Vec<AtomicBool> = (0..reps.len()).map(|_| AtomicBool::new(false)).collect();
    // Whether a cluster is used does not depend on which core marks it first.
    blocks::ranges(mesh.face_count()).for_each(|r| {
        let mut ring = Vec::new();
        for f in r {
            let mark = |c: u32| used[c as usize].store(true, Ordering::Relaxed);
            match image(mesh, cluster_of, reps, f, &mut ring) {
                Image::Face(3) => mesh
                    .face(f)
                    .iter()
                    .for_each(|&v| mark(cluster_of[v as usize])),
                // A polygon keeps the clusters of its collapsed ring.
                Image::Face(_) => ring.iter().for_each(|&(c, _)| mark(c)),
                Image::Collapsed { .. } => {}
            }
        }
    });
    used.into_iter()
        .filter(|u| u.load(Ordering::Relaxed))
        .count()
}

/// A face's image under the clustering.
enum Image {
    /// An output face with this many corners.
    Face(usize),
    /// A collapsed face; `distinct`: it has 3 distinct clusters (or a ring of 3 or more)
    /// whose representatives are collinear.
    Collapsed { distinct: bool },
}

/// The image of face `f`; `ring` is scratch for polygons.
fn image(
    mesh: &Mesh,
    cluster_of: &[u32],
    reps: &[[f32; 3]],
    f: usize,
    ring: &mut Vec<(u32, u32)>,
) -> Image {
    let (s, e) = (mesh.face_offsets[f], mesh.face_offsets[f + 1]);
    if e - s == 3 {
        // Triangles, the common case: no ring to collapse, only three ids to compare.
        let v = [0, 1, 2].map(|k| cluster_of[mesh.face_indices[s as usize + k] as usize]);
        let distinct = v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
        if !distinct || zero_area_triangle(v, reps) {
            return Image::Collapsed { distinct };
        }
        return Image::Face(3);
    }
    polygon_ring(mesh, cluster_of, s..e, ring);
    if ring.len() < 3 || zero_area(ring, reps) {
        return Image::Collapsed {
            distinct: ring.len() >= 3,
        };
    }
    Image::Face(ring.len())
}

/// The collapsed ring of (cluster, input corner) of the polygon whose corners are `corners`.
fn polygon_ring(
    mesh: &Mesh,
    cluster_of: &[u32],
    corners: std::ops::Range<u32>,
    ring: &mut Vec<(u32, u32)>,
) {
    ring.clear();
    for corner in corners {
        let c = cluster_of[mesh.face_indices[corner as usize] as usize];
        debug_assert_ne!(c, UNUSED);
        ring.push((c, corner));
    }
    collapse_ring(ring);
}

/// Writes the kept faces of `range` (by `fate`) into a block's slices of the outputs: their
/// offsets (shifted by `base`, the corners before the block), cluster ids and, when `sources`
/// is not empty, input corners.
#[allow(clippy::too_many_arguments)]
fn write_faces(
    mesh: &Mesh,
    cluster_of: &[u32],
    fate: &[Fate],
    range: std::ops::Range<usize>,
    base: u32,
    offsets: &mut [u32],
    indices: &mut [u32],
    sources: &mut [u32],
) {
    let corners = !sources.is_empty();
    let (mut face, mut at) = (0usize, 0usize);
    if let Some(triangles) = mesh.triangles() {
        // All triangles: the kept ones' ids, without reading the offsets.
        for f in range.filter(|&f| fate[f] == Fate::Kept) {
            let t = triangles[f];
            for k in 0..3 {
                indices[at + k] = cluster_of[t[k] as usize];
                if corners {
                    sources[at + k] = 3 * f as u32 + k as u32;
                }
            }
            at += 3;
            offsets[face] = base + at as u32;
            face += 1;
        }
        return;
    }
    let mut ring = Vec::new();
    for f in range {
        if fate[f] != Fate::Kept {
            continue;
        }
        let (s, e) = (mesh.face_offsets[f], mesh.face_offsets[f + 1]);
        if e - s == 3 {
            for k in 0..3 {
                indices[at + k] = cluster_of[mesh.face_indices[s as usize + k] as usize];
                if corners {
                    sources[at + k] = s + k as u32;
                }
            }
            at += 3;
        } else {
            polygon_ring(mesh, cluster_of, s..e, &mut ring);
            for (k, &(c, corner)) in ring.iter().enumerate() {
                indices[at + k] = c;
                if corners {
                    sources[at + k] = corner;
                }
            }
            at += ring.len();
        }
        offsets[face] = base + at as u32;
        face += 1;
    }
}

/// The output faces that repeat an earlier one (same cluster cycle up to rotation and
/// reversal), sorted.
///
/// Duplicates share their smallest cluster, so faces are bucketed by it and only faces within
/// a bucket are compared; a bucket is the fan of faces around one output vertex, a handful of
/// faces, sorted by a key of their other clusters (equal keys are duplicates). The bucketing is a
/// two-level counting sort that every core takes part in: faces are first spread, in face
/// order, over [`DUPLICATE_RANGES`] ranges of clusters (a count and a scatter pass over blocks
/// of faces), then each range — a few thousand faces, in cache — is bucketed and compared on
/// its own. Within a bucket faces stay in increasing order, so the first of equal faces is
/// the one kept, whatever the thread count.
fn find_duplicates(faces: &Eliminated, clusters: usize) -> Vec<u32> {
    let n = faces.face_offsets.len() - 1;
    let face = |f: usize| {
        &faces.face_indices[faces.face_offsets[f] as usize..faces.face_offsets[f + 1] as usize]
    };
    // Every face a triangle: faces are read as triples (no offsets).
    let all_triangles = faces.face_indices.len() == 3 * n;
    let triangle = |f: usize| -> [u32; 3] {
        let t = &faces.face_indices[3 * f..3 * f + 3];
        [t[0], t[1], t[2]]
    };
    let smallest = |f: usize| {
        if all_triangles {
            let t = triangle(f);
            t[0].min(t[1]).min(t[2]) as usize
        } else {
            *face(f).iter().min().expect("faces have corners") as usize
        }
    };
    let width = clusters.div_ceil(DUPLICATE_RANGES).max(1);
    let ranges = clusters.div_ceil(width);
    // Count and scatter (parallel over blocks of faces): each block's faces of each range go
    // to a place fixed by the counts (range by range, block by block).
    let counts: Vec<Vec<u32>> = blocks::map(n, |r| {
        let mut c = vec![0u32; ranges];
        r.for_each(|f| c[smallest(f) / width] += 1);
        c
    });
    let mut range_start = Vec::with_capacity(ranges + 1);
    let mut next = vec![vec![0u32; ranges]; counts.len()];
    let mut total = 0u32;
    for k in 0..ranges {
        range_start.push(total as usize);
        for (b, c) in counts.iter().enumerate() {
            next[b][k] = total;
            total += c[k];
        }
    }
    range_start.push(total as usize);
    drop(counts);
    let mut by_range = vec![0u32; n];
    let writes = DisjointWrites::new(&mut by_range);
    blocks::ranges(n).zip(next).for_each(|(r, mut next)| {
        for f in r {
            let k = smallest(f) / width;
            writes.write(next[k] as usize, f as u32);
            next[k] += 1;
        }
    });
    // Each range on its own (parallel over ranges): bucket by smallest cluster, compare.
    let marked: Vec<Vec<u32>> = (0..ranges)
        .into_par_iter()
        .map(|k| {
            let list = &by_range[range_start[k]..range_start[k + 1]];
            let base = k * width;
            let mut start = vec![0u32; width + 1];
            list.iter()
                .for_each(|&f| start[smallest(f as usize) - base + 1] += 1);
            for c in 1..=width {
                start[c] += start[c - 1];
            }
            let mut fill = start.clone();
            let mut bucketed = vec![0u32; list.len()];
            for &f in list {
                let c = smallest(f as usize) - base;
                bucketed[fill[c] as usize] = f;
                fill[c] += 1;
            }
            let mut marked = Vec::new();
            let mut keys: Vec<(u64, u32)> = Vec::new();
            for c in 0..width {
                let bucket = &bucketed[start[c] as usize..start[c + 1] as usize];
                if bucket.len() < 2 {
                    continue;
                }
                if all_triangles {
                    // The bucket's cluster is every face's smallest: the other two, sorted,
                    // tell its faces apart.
                    keys.clear();
                    keys.extend(bucket.iter().map(|&f| {
                        let [a, b, c] = triangle(f as usize);
                        let (lo, hi) = (a.max(b).min(c).max(a.min(b)), a.max(b).max(c));
                        ((u64::from(lo) << 32) | u64::from(hi), f)
                    }));
                    // Sorted by key, then face: the first of equal faces comes first.
                    keys.sort_unstable();
                    for w in keys.windows(2) {
                        if w[0].0 == w[1].0 {
                            marked.push(w[1].1);
                        }
                    }
                } else {
                    mark_polygon_duplicates(bucket, face, &mut marked);
                }
            }
            marked
        })
        .collect();
    let mut dup: Vec<u32> = marked.into_iter().flatten().collect();
    dup.sort_unstable();
    dup
}

/// Ranges of clusters the duplicate search first spreads faces over: fixed (not the thread
/// count), enough for every core and for each range's buckets to stay in cache.
const DUPLICATE_RANGES: usize = 256;

/// Marks the faces of `bucket` (increasing face order, same smallest cluster) that repeat an
/// earlier one, comparing canonical cluster cycles.
fn mark_polygon_duplicates<'a>(
    bucket: &[u32],
    face: impl Fn(usize) -> &'a [u32],
    marked: &mut Vec<u32>,
) {
    let canonical = |f: u32| -> Vec<u32> {
        let fc = face(f as usize);
        if fc.len() == 3 {
            let mut k = [fc[0], fc[1], fc[2]];
            k.sort_unstable();
            k.to_vec()
        } else {
            let ring: Vec<(u32, u32)> = fc.iter().map(|&c| (c, 0)).collect();
            canonical_polygon(&ring)
        }
    };
    // Faces of different sizes never repeat each other: the length goes first in the key.
    let mut keyed: Vec<((usize, Vec<u32>), u32)> = bucket
        .iter()
        .map(|&f| ((face(f as usize).len(), canonical(f)), f))
        .collect();
    keyed.sort_unstable();
    for w in keyed.windows(2) {
        if w[0].0 == w[1].0 {
            marked.push(w[1].1);
        }
    }
}

/// Removes zero-length edges (equal neighbours, cyclically) and zero-angle corners (`a b a`)
/// until neither is left.
fn collapse_ring(ring: &mut Vec<(u32, u32)>) {
    loop {
        let before = ring.len();
        ring.dedup_by_key(|r| r.0);
        while ring.len() > 1 && ring[0].0 == ring[ring.len() - 1].0 {
            ring.pop();
        }
        let n = ring.len();
        if n >= 3
            && let Some(i) = (0..n).find(|&i| ring[i].0 == ring[(i + 2) % n].0)
        {
            {
                // Corner i+1 is a spike: drop it and the repeated vertex after it.
                let (a, b) = ((i + 1) % n, (i + 2) % n);
                let (hi, lo) = if a > b { (a, b) } else { (b, a) };
                ring.remove(hi);
                ring.remove(lo);
            }
        }
        if ring.len() == before {
            return;
        }
    }
}

/// Whether the triangle over the cluster positions has exactly zero area.
fn zero_area_triangle(v: [u32; 3], reps: &[[f32; 3]]) -> bool {
    let [a, b, c] = v.map(|i| area_vector::f64_point(reps[i as usize]));
    area_vector::triangle(a, b, c) == glam::DVec3::ZERO
}

/// Whether the polygon over the cluster positions has exactly zero area.
fn zero_area(ring: &[(u32, u32)], reps: &[[f32; 3]]) -> bool {
    let corner = |i: usize| area_vector::f64_point(reps[ring[i].0 as usize]);
    area_vector::polygon(ring.len(), corner) == glam::DVec3::ZERO
}

/// The polygon's cluster sequence, rotated to start at its smallest id and read in the
/// direction whose second element is smaller: equal for rotations and reversals.
fn canonical_polygon(ring: &[(u32, u32)]) -> Vec<u32> {
    let n = ring.len();
    let start = (0..n).min_by_key(|&i| ring[i].0).unwrap_or(0);
    let fwd = ring[(start + 1) % n].0;
    let back = ring[(start + n - 1) % n].0;
    if fwd <= back {
        (0..n).map(|k| ring[(start + k) % n].0).collect()
    } else {
        (0..n).map(|k| ring[(start + n - k) % n].0).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(ids: &[u32]) -> Vec<(u32, u32)> {
        ids.iter()
            .enumerate()
            .map(|(i, &c)| (c, i as u32))
            .collect()
    }

    #[test]
    fn collapses_edges_and_spikes() {
        let mut r = ring(&[1, 1, 2, 3, 1]);
        collapse_ring(&mut r);
        assert_eq!(r.iter().map(|x| x.0).collect::<Vec<_>>(), vec![1, 2, 3]);
        let mut r = ring(&[1, 2, 1, 3, 4]);
        collapse_ring(&mut r);
        assert_eq!(r.iter().map(|x| x.0).collect::<Vec<_>>(), vec![1, 3, 4]);
        let mut r = ring(&[5, 6, 5]);
        collapse_ring(&mut r);
        assert!(r.len() < 3);
    }

    #[test]
    fn duplicates_and_reversed_duplicates_are_removed() {
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[2, 1, 0]); // reversed duplicate
        m.push_face(&[1, 2, 0]); // rotated duplicate
        m.push_face(&[0, 1, 3, 2]);
        m.push_face(&[1, 0, 2, 3]); // reversed + rotated quad
        m.push_face(&[0, 0, 1]); // collapsed
        let ids: Vec<u32> = (0..4).collect();
        let e = eliminate(&m, &ids, &m.positions, true);
        assert_eq!(e.source_faces().collect::<Vec<_>>(), vec![0, 3]);
        assert_eq!((e.duplicates, e.degenerate), (3, 1));
        assert_eq!(e.collapsed().collect::<Vec<_>>(), vec![5]);
        assert_eq!(count_used(&m, &ids, &m.positions), 4);
    }

    /// Many duplicates across several blocks, triangles alone and mixed with quads: the
    /// parallel bucketing, fate update and run-wise squeeze match a plain first-seen filter.
    #[test]
    fn duplicates_across_blocks_match_a_first_seen_filter() {
        for quads in [false, true] {
            let mut state = 12345u64;
            let mut next = |n: u64| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 33) % n) as u32
            };
            let positions: Vec<[f32; 3]> = (0..40)
                .map(|_| [next(1000) as f32, next(1000) as f32, next(1000) as f32])
                .collect();
            let mut m = Mesh {
                positions,
                ..Mesh::default()
            };
            for f in 0..3 * blocks::BLOCK + 100 {
                let corners = if quads && f % 3 == 0 { 4 } else { 3 };
                let face: Vec<u32> = (0..corners).map(|_| next(40)).collect();
                m.push_face(&face);
            }
            let ids: Vec<u32> = (0..40).collect();
            let e = eliminate(&m, &ids, &m.positions, true);
            // The reference: each face's collapsed ring, kept when its canonical cycle is new.
            let (mut seen, mut faces, mut sources) =
                (std::collections::HashSet::new(), vec![], vec![]);
            let mut fate = vec![];
            let mut ring = Vec::new();
            for f in 0..m.face_count() {
                let (s, end) = (m.face_offsets[f], m.face_offsets[f + 1]);
                polygon_ring(&m, &ids, s..end, &mut ring);
                if ring.len() < 3 || zero_area(&ring, &m.positions) {
                    fate.push(Fate::Collapsed);
                } else if seen.insert((ring.len(), canonical_polygon(&ring))) {
                    fate.push(Fate::Kept);
                    faces.push(ring.iter().map(|r| r.0).collect::<Vec<_>>());
                    sources.extend(ring.iter().map(|r| r.1));
                } else {
                    fate.push(Fate::Duplicate);
                }
            }
            assert!(fate.iter().filter(|f| **f == Fate::Duplicate).count() > 1000);
            assert_eq!(e.fate, fate, "quads: {quads}");
            let got: Vec<Vec<u32>> = (0..e.face_offsets.len() - 1)
                .map(|f| {
                    e.face_indices[e.face_offsets[f] as usize..e.face_offsets[f + 1] as usize]
                        .to_vec()
                })
                .collect();
            assert_eq!(got, faces, "quads: {quads}");
            assert_eq!(e.source_corner, sources, "quads: {quads}");
        }
    }

    #[test]
    fn collinear_faces_have_zero_area() {
        let reps = [[0.0f32, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(zero_area(&ring(&[0, 1, 2]), &reps));
    }
}
