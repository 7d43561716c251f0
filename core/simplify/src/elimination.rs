//! Elimination (Belblidia & Perrin, section 2, "élimination"): after every vertex moved to its
//! cluster, remove what collapsed — zero-length edges, zero-angle corners, zero-area faces and
//! duplicate faces (also reversed ones, as stacked CAD solids produce) — so that the
//! simplification actually lowers the complexity.

use crate::area_vector;
use crate::blocks;
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
}

impl Fates {
    /// Faces with 3 distinct clusters whose representatives are collinear.
    pub(crate) fn flattened(&self) -> u64 {
        self.counts.iter().map(|c| c[3]).sum()
    }
}

/// Decides the fate of every face of `mesh` under `cluster_of` and `reps` (collapsed or kept;
/// duplicates are found later).
pub(crate) fn fates(mesh: &Mesh, cluster_of: &[u32], reps: &[[f32; 3]]) -> Fates {
    let mut fate = vec![Fate::Kept; mesh.face_count()];
    // Pass 1: fates, and per block (kept faces, kept corners, degenerate, flattened).
    let counts: Vec<[u64; 4]> = fate
        .par_chunks_mut(blocks::BLOCK)
        .enumerate()
        .map(|(b, fates)| {
            let mut c = [0u64; 4];
            let mut ring = Vec::new();
            for (i, slot) in fates.iter_mut().enumerate() {
                let f = b * blocks::BLOCK + i;
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
    Fates { fate, counts }
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
        let Fates { fate, counts } = self;
        let n = mesh.face_count();
        let faces: usize = counts.iter().map(|c| c[0] as usize).sum();
        let total: usize = counts.iter().map(|c| c[1] as usize).sum();
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
        let duplicate = find_duplicates(&out, reps.len());
        out.duplicates = duplicate.len() as u64;
        if duplicate.is_empty() {
            return out;
        }
        // The input faces of the duplicates change fate.
        let mut next = duplicate.iter().peekable();
        let kept = out.fate.iter_mut().filter(|f| **f == Fate::Kept);
        for (i, f) in kept.enumerate() {
            if next.next_if(|&&d| d as usize == i).is_some() {
                *f = Fate::Duplicate;
            }
        }
        // Squeeze the duplicates out in place: the write position never passes the read position.
        let mut next = duplicate.iter().peekable();
        let (mut corner_w, mut face_w) = (0usize, 0usize);
        for f in 0..faces {
            // Offsets f and f + 1 are still the originals here: writes go to `face_w` ≤ f, or to
            // f + 1 with its own value when nothing was dropped yet.
            let (s, e) = (
                out.face_offsets[f] as usize,
                out.face_offsets[f + 1] as usize,
            );
            if next.next_if(|&&d| d as usize == f).is_some() {
                continue;
            }
            out.face_indices.copy_within(s..e, corner_w);
            if corners {
                out.source_corner.copy_within(s..e, corner_w);
            }
            corner_w += e - s;
            face_w += 1;
            out.face_offsets[face_w] = corner_w as u32;
        }
        out.face_indices.truncate(corner_w);
        out.source_corner
            .truncate(if corners { corner_w } else { 0 });
        out.face_offsets.truncate(face_w + 1);
        out
    }
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
/// Duplicates share their smallest cluster, so faces are bucketed by it (a counting sort: two
/// linear passes, one array of bucket starts) and only faces within a bucket are compared; a
/// bucket is the fan of faces around one output vertex, a handful of faces, and the few large
/// ones are sorted instead of compared pairwise.
fn find_duplicates(faces: &Eliminated, clusters: usize) -> Vec<u32> {
    let n = faces.face_offsets.len() - 1;
    let face = |f: usize| {
        &faces.face_indices[faces.face_offsets[f] as usize..faces.face_offsets[f + 1] as usize]
    };
    let smallest = |f: usize| *face(f).iter().min().expect("faces have corners") as usize;
    // Bucket ends, then (filling each bucket from its end, faces in decreasing order) starts.
    let mut start = vec![0u32; clusters + 1];
    for f in 0..n {
        start[smallest(f)] += 1;
    }
    for c in 1..=clusters {
        start[c] += start[c - 1];
    }
    let mut bucketed = vec![0u32; n];
    for f in (0..n).rev() {
        let c = smallest(f);
        start[c] -= 1;
        bucketed[start[c] as usize] = f as u32;
    }
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
    // Buckets are disjoint: blocks of clusters mark their own faces on every core, each
    // bucket exactly as one thread would.
    let marked = blocks::map(clusters, |r| {
        let mut marked: Vec<u32> = Vec::new();
        let mut local: Vec<bool> = Vec::new();
        for c in r {
            let bucket = &bucketed[start[c] as usize..start[c + 1] as usize];
            if bucket.len() < 2 {
                continue;
            }
            // Faces were bucketed in increasing order, so the first of equal faces comes first.
            if bucket.len() <= 32 {
                let sorted3 = |f: u32| {
                    let fc = face(f as usize);
                    let mut k = [fc[0], fc[1], fc[2]];
                    k.sort_unstable();
                    k
                };
                local.clear();
                local.resize(bucket.len(), false);
                for (i, &a) in bucket.iter().enumerate() {
                    let len = face(a as usize).len();
                    if local[i] {
                        continue;
                    }
                    let same = |b: u32| match len {
                        3 => sorted3(a) == sorted3(b),
                        _ => canonical(a) == canonical(b),
                    };
                    for (j, &b) in bucket.iter().enumerate().skip(i + 1) {
                        if !local[j] && face(b as usize).len() == len && same(b) {
                            local[j] = true;
                            marked.push(b);
                        }
                    }
                }
            } else {
                let mut keyed: Vec<(Vec<u32>, u32)> =
                    bucket.iter().map(|&f| (canonical(f), f)).collect();
                keyed.sort_unstable();
                for w in keyed.windows(2) {
                    if w[0].0 == w[1].0 {
                        marked.push(w[1].1);
                    }
                }
            }
        }
        marked
    });
    let mut dup: Vec<u32> = marked.into_iter().flatten().collect();
    dup.sort_unstable();
    dup
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

    #[test]
    fn collinear_faces_have_zero_area() {
        let reps = [[0.0f32, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(zero_area(&ring(&[0, 1, 2]), &reps));
    }
}
