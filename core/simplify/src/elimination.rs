//! Elimination (Belblidia & Perrin, section 2, "élimination"): after every vertex moved to its
//! cluster, remove what collapsed — zero-length edges, zero-angle corners, zero-area faces and
//! duplicate faces (also reversed ones, as stacked CAD solids produce) — so that the
//! simplification actually lowers the complexity.

use crate::cell_table::mix;
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
    /// Faces removed because they collapsed (fewer than 3 distinct corners or zero area).
    pub degenerate: u64,
    /// Faces removed as duplicates of an earlier face.
    pub duplicates: u64,
}

/// Faces per parallel chunk of the first phase.
const CHUNK: usize = 1 << 16;

/// Maps every face of `mesh` through `cluster_of` and removes collapsed and duplicate faces.
/// The first of several duplicates is kept, so the result is deterministic.
///
/// Two phases: faces are mapped and collapsed in parallel chunks (concatenated in order), then
/// duplicates are found by sorting the survivors' canonical-key hashes (sequential memory
/// traffic, unlike a hash set of millions of faces) and comparing equal-hash runs exactly.
pub(crate) fn eliminate(mesh: &Mesh, cluster_of: &[u32], reps: &[[f32; 3]]) -> Eliminated {
    use rayon::prelude::*;
    let faces = mesh.face_count();
    let chunks: Vec<Eliminated> = (0..faces.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            collapse_faces(
                mesh,
                cluster_of,
                reps,
                c * CHUNK..((c + 1) * CHUNK).min(faces),
            )
        })
        .collect();
    let mut all = Eliminated::default();
    all.face_offsets.push(0);
    for c in chunks {
        let base = all.face_indices.len() as u32;
        all.face_indices.extend_from_slice(&c.face_indices);
        all.source_corner.extend_from_slice(&c.source_corner);
        all.source_face.extend_from_slice(&c.source_face);
        all.face_offsets
            .extend(c.face_offsets[1..].iter().map(|o| o + base));
        all.degenerate += c.degenerate;
    }
    let duplicate = find_duplicates(&all);
    if duplicate.iter().all(|d| !d) {
        return all;
    }
    let mut out = Eliminated {
        degenerate: all.degenerate,
        ..Eliminated::default()
    };
    out.face_offsets.push(0);
    for (f, w) in all.face_offsets.windows(2).enumerate() {
        if duplicate[f] {
            out.duplicates += 1;
            continue;
        }
        let r = w[0] as usize..w[1] as usize;
        out.face_indices
            .extend_from_slice(&all.face_indices[r.clone()]);
        out.source_corner.extend_from_slice(&all.source_corner[r]);
        out.face_offsets.push(out.face_indices.len() as u32);
        out.source_face.push(all.source_face[f]);
    }
    out
}

/// Maps the faces in `range` to clusters and drops those that collapse (no duplicate check).
fn collapse_faces(
    mesh: &Mesh,
    cluster_of: &[u32],
    reps: &[[f32; 3]],
    range: std::ops::Range<usize>,
) -> Eliminated {
    let mut out = Eliminated::default();
    out.face_offsets.push(0);
    let mut ring: Vec<(u32, u32)> = Vec::with_capacity(16);
    for f in range {
        let (s, e) = (mesh.face_offsets[f], mesh.face_offsets[f + 1]);
        if e - s == 3 {
            // Triangles, the common case: no ring to collapse, only three ids to compare.
            let v = [0, 1, 2].map(|k| cluster_of[mesh.face_indices[s as usize + k] as usize]);
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || zero_area_triangle(v, reps) {
                out.degenerate += 1;
                continue;
            }
            out.face_indices.extend_from_slice(&v);
            out.source_corner.extend([s, s + 1, s + 2]);
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
                continue;
            }
            out.face_indices.extend(ring.iter().map(|r| r.0));
            out.source_corner.extend(ring.iter().map(|r| r.1));
        }
        out.face_offsets.push(out.face_indices.len() as u32);
        out.source_face.push(f as u32);
    }
    out
}

/// Marks every face that repeats an earlier one (same cluster cycle up to rotation and
/// reversal).
fn find_duplicates(faces: &Eliminated) -> Vec<bool> {
    use rayon::prelude::*;
    let n = faces.face_offsets.len() - 1;
    let face = |f: usize| {
        &faces.face_indices[faces.face_offsets[f] as usize..faces.face_offsets[f + 1] as usize]
    };
    let canonical = |f: usize| -> Vec<u32> {
        let ring: Vec<(u32, u32)> = face(f).iter().map(|&c| (c, 0)).collect();
        if ring.len() == 3 {
            let mut k = [ring[0].0, ring[1].0, ring[2].0];
            k.sort_unstable();
            k.to_vec()
        } else {
            canonical_polygon(&ring)
        }
    };
    let mut keys: Vec<(u64, u32)> = (0..n)
        .into_par_iter()
        .map(|f| {
            let fc = face(f);
            let h = if fc.len() == 3 {
                let mut k = [fc[0], fc[1], fc[2]];
                k.sort_unstable();
                mix(u64::from(k[0]) << 32 | u64::from(k[1])) ^ mix(u64::from(k[2]) ^ 0x9e37_79b9)
            } else {
                canonical(f)
                    .iter()
                    .fold(0xcbf2_9ce4_8422_2325u64, |h, &c| mix(h ^ u64::from(c)))
            };
            (h, f as u32)
        })
        .collect();
    keys.par_sort_unstable();
    let mut dup = vec![false; n];
    let mut i = 0;
    while i < keys.len() {
        let j = i + keys[i..].iter().take_while(|k| k.0 == keys[i].0).count();
        if j - i == 1 {
            i = j;
            continue;
        }
        // Within a run of equal hashes (in face order), a face is a duplicate if an earlier
        // face of the run has the same canonical cycle.
        for a in i..j {
            if dup[keys[a].1 as usize] {
                continue;
            }
            let ca = canonical(keys[a].1 as usize);
            for b in a + 1..j {
                if !dup[keys[b].1 as usize] && canonical(keys[b].1 as usize) == ca {
                    dup[keys[b].1 as usize] = true;
                }
            }
        }
        i = j;
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
    let (u, w) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    let n = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
    n == [0.0; 3]
}

/// Whether the polygon over the cluster positions has exactly zero area.
fn zero_area(ring: &[(u32, u32)], reps: &[[f32; 3]]) -> bool {
    let mut n = [0f64; 3];
    for i in 0..ring.len() {
        let p = reps[ring[i].0 as usize].map(f64::from);
        let q = reps[ring[(i + 1) % ring.len()].0 as usize].map(f64::from);
        n[0] += (p[1] - q[1]) * (p[2] + q[2]);
        n[1] += (p[2] - q[2]) * (p[0] + q[0]);
        n[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    n == [0.0; 3]
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
        let e = eliminate(&m, &ids, &m.positions);
        assert_eq!(e.source_face, vec![0, 3]);
        assert_eq!((e.duplicates, e.degenerate), (3, 1));
    }

    #[test]
    fn collinear_faces_have_zero_area() {
        let reps = [[0.0f32, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(zero_area(&ring(&[0, 1, 2]), &reps));
    }
}
