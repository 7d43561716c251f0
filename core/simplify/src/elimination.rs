//! Elimination (Belblidia & Perrin, section 2, "élimination"): after every vertex moved to its
//! cluster, remove what collapsed — zero-length edges, zero-angle corners, zero-area faces and
//! duplicate faces (also reversed ones, as stacked CAD solids produce) — so that the
//! simplification actually lowers the complexity.

use crate::area_vector;
use crate::blocks;
use crate::partition::UNUSED;
use tessd_mesh::Mesh;

/// Faces over cluster ids, with where each came from.
#[derive(Debug, Default)]
pub(crate) struct Eliminated {
    /// Compressed-row faces, as in [`Mesh`].
    pub face_offsets: Vec<u32>,
    /// Cluster id of each corner.
    pub face_indices: Vec<u32>,
    /// The input face of each output face.
    pub source_face: Vec<u32>,
    /// The input corner (index into the input's `face_indices`) of each output corner.
    pub source_corner: Vec<u32>,
    /// The input faces that collapsed (their image is a segment or a point, see `coverage.rs`).
    pub collapsed: Vec<u32>,
    /// Faces removed because they collapsed (fewer than 3 distinct corners or zero area).
    pub degenerate: u64,
    /// Of those, faces with 3 distinct clusters whose representatives are collinear.
    pub flattened: u64,
    /// Faces removed as duplicates of an earlier face.
    pub duplicates: u64,
}

/// Maps every face of `mesh` through `cluster_of` and removes collapsed and duplicate faces.
/// The first of several duplicates is kept, so the result is deterministic. `corners`: also
/// record each output corner's input corner (needed only to carry face-varying attributes).
///
/// One pass writes the surviving faces straight into the output — in parallel, fixed blocks of
/// faces each writing their own part, joined in block order so faces keep their order
/// ([`crate::blocks`]); duplicates are then found by bucketing faces by their smallest cluster
/// ([`find_duplicates`]) and squeezed out in place.
pub(crate) fn eliminate(
    mesh: &Mesh,
    cluster_of: &[u32],
    reps: &[[f32; 3]],
    corners: bool,
) -> Eliminated {
    let parts = blocks::map(mesh.face_count(), |r| {
        collapse_faces(mesh, cluster_of, reps, r, corners)
    });
    let mut out = join(parts);
    let duplicate = find_duplicates(&out, reps.len());
    out.duplicates = duplicate.iter().filter(|&&d| d).count() as u64;
    if out.duplicates == 0 {
        return out;
    }
    // Squeeze the duplicates out in place: the write position never passes the read position.
    let (mut corner_w, mut face_w) = (0usize, 0usize);
    for (f, &dup) in duplicate.iter().enumerate() {
        // Offsets f and f + 1 are still the originals here: writes go to `face_w` ≤ f, or to
        // f + 1 with its own value when nothing was dropped yet.
        let (s, e) = (
            out.face_offsets[f] as usize,
            out.face_offsets[f + 1] as usize,
        );
        if dup {
            continue;
        }
        out.face_indices.copy_within(s..e, corner_w);
        if corners {
            out.source_corner.copy_within(s..e, corner_w);
        }
        out.source_face[face_w] = out.source_face[f];
        corner_w += e - s;
        face_w += 1;
        out.face_offsets[face_w] = corner_w as u32;
    }
    out.face_indices.truncate(corner_w);
    out.source_corner
        .truncate(if corners { corner_w } else { 0 });
    out.source_face.truncate(face_w);
    out.face_offsets.truncate(face_w + 1);
    out
}

/// The blocks' faces one after the other.
fn join(mut parts: Vec<Eliminated>) -> Eliminated {
    if parts.len() == 1 {
        return parts.pop().expect("one part");
    }
    let faces: usize = parts.iter().map(|p| p.source_face.len()).sum();
    let corners: usize = parts.iter().map(|p| p.face_indices.len()).sum();
    let mut out = Eliminated {
        face_offsets: Vec::with_capacity(faces + 1),
        face_indices: Vec::with_capacity(corners),
        source_face: Vec::with_capacity(faces),
        ..Eliminated::default()
    };
    out.face_offsets.push(0);
    for p in parts {
        let base = out.face_indices.len() as u32;
        out.face_offsets
            .extend(p.face_offsets[1..].iter().map(|&o| o + base));
        out.face_indices.extend_from_slice(&p.face_indices);
        out.source_face.extend_from_slice(&p.source_face);
        out.source_corner.extend_from_slice(&p.source_corner);
        out.collapsed.extend_from_slice(&p.collapsed);
        out.degenerate += p.degenerate;
        out.flattened += p.flattened;
    }
    out
}

/// Maps the faces in `range` to clusters and drops those that collapse (no duplicate check).
fn collapse_faces(
    mesh: &Mesh,
    cluster_of: &[u32],
    reps: &[[f32; 3]],
    range: std::ops::Range<usize>,
    corners: bool,
) -> Eliminated {
    let mut out = Eliminated {
        face_offsets: Vec::with_capacity(range.len() + 1),
        face_indices: Vec::with_capacity(
            (mesh.face_offsets[range.end] - mesh.face_offsets[range.start]) as usize,
        ),
        source_face: Vec::with_capacity(range.len()),
        ..Eliminated::default()
    };
    out.face_offsets.push(0);
    let mut ring: Vec<(u32, u32)> = Vec::with_capacity(16);
    for f in range {
        let (s, e) = (mesh.face_offsets[f], mesh.face_offsets[f + 1]);
        if e - s == 3 {
            // Triangles, the common case: no ring to collapse, only three ids to compare.
            let v = [0, 1, 2].map(|k| cluster_of[mesh.face_indices[s as usize + k] as usize]);
            let distinct = v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
            if !distinct || zero_area_triangle(v, reps) {
                out.degenerate += 1;
                out.flattened += u64::from(distinct);
                out.collapsed.push(f as u32);
                continue;
            }
            out.face_indices.extend_from_slice(&v);
            if corners {
                out.source_corner.extend([s, s + 1, s + 2]);
            }
        } else {
            ring.clear();
            for corner in s..e {
                let c = cluster_of[mesh.face_indices[corner as usize] as usize];
                debug_assert_ne!(c, UNUSED);
                ring.push((c, corner));
            }
            collapse_ring(&mut ring);
            if ring.len() < 3 || zero_area(&ring, reps) {
                out.degenerate += 1;
                out.flattened += u64::from(ring.len() >= 3);
                out.collapsed.push(f as u32);
                continue;
            }
            out.face_indices.extend(ring.iter().map(|r| r.0));
            if corners {
                out.source_corner.extend(ring.iter().map(|r| r.1));
            }
        }
        out.face_offsets.push(out.face_indices.len() as u32);
        out.source_face.push(f as u32);
    }
    out
}

/// Marks every face that repeats an earlier one (same cluster cycle up to rotation and
/// reversal).
///
/// Duplicates share their smallest cluster, so faces are bucketed by it (a counting sort: two
/// linear passes) and only faces within a bucket are compared; a bucket is the fan of faces
/// around one output vertex, a handful of faces, and the few large ones are sorted instead of
/// compared pairwise.
fn find_duplicates(faces: &Eliminated, clusters: usize) -> Vec<bool> {
    let n = faces.face_offsets.len() - 1;
    let face = |f: usize| {
        &faces.face_indices[faces.face_offsets[f] as usize..faces.face_offsets[f + 1] as usize]
    };
    let smallest = |f: usize| *face(f).iter().min().expect("faces have corners") as usize;
    let mut start = vec![0u32; clusters + 1];
    for f in 0..n {
        start[smallest(f) + 1] += 1;
    }
    for c in 0..clusters {
        start[c + 1] += start[c];
    }
    let mut bucketed = vec![0u32; n];
    let mut cursor = start.clone();
    for f in 0..n {
        let c = smallest(f);
        bucketed[cursor[c] as usize] = f as u32;
        cursor[c] += 1;
    }
    drop(cursor);
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
    let mut dup = vec![false; n];
    for f in marked.into_iter().flatten() {
        dup[f as usize] = true;
    }
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
    let [a, b, c] = v.map(|i| reps[i as usize].map(f64::from));
    area_vector::triangle(a, b, c) == [0.0; 3]
}

/// Whether the polygon over the cluster positions has exactly zero area.
fn zero_area(ring: &[(u32, u32)], reps: &[[f32; 3]]) -> bool {
    area_vector::polygon(ring.len(), |i| reps[ring[i].0 as usize].map(f64::from)) == [0.0; 3]
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
        assert_eq!(e.source_face, vec![0, 3]);
        assert_eq!((e.duplicates, e.degenerate), (3, 1));
        assert_eq!(e.collapsed, vec![5]);
    }

    #[test]
    fn collinear_faces_have_zero_area() {
        let reps = [[0.0f32, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(zero_area(&ring(&[0, 1, 2]), &reps));
    }
}
