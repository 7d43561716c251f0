//! Elimination (Belblidia & Perrin, section 2, "élimination"): after every vertex moved to its
//! cluster, remove what collapsed — zero-length edges, zero-angle corners, zero-area faces and
//! duplicate faces (also reversed ones, as stacked CAD solids produce) — so that the
//! simplification actually lowers the complexity.

use crate::cell_table::mix;
use crate::partition::UNUSED;
use std::collections::HashSet;
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

/// Maps every face of `mesh` through `cluster_of` and removes collapsed and duplicate faces.
/// The first of several duplicates is kept, so the result is deterministic.
pub(crate) fn eliminate(mesh: &Mesh, cluster_of: &[u32], reps: &[[f32; 3]]) -> Eliminated {
    let mut out = Eliminated {
        face_offsets: Vec::with_capacity(mesh.face_count() / 2 + 1),
        face_indices: Vec::with_capacity(mesh.face_indices.len() / 2),
        ..Eliminated::default()
    };
    out.face_offsets.push(0);
    let mut ring: Vec<(u32, u32)> = Vec::with_capacity(16);
    let mut tris = TriangleSet::with_capacity(1 << 12);
    let mut polys: HashSet<Vec<u32>> = HashSet::new();
    for (f, w) in mesh.face_offsets.windows(2).enumerate() {
        if w[1] - w[0] == 3 {
            // Triangles, the common case: no ring to collapse, only three ids to compare.
            let s = w[0] as usize;
            let v = [0, 1, 2].map(|k| cluster_of[mesh.face_indices[s + k] as usize]);
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || zero_area_triangle(v, reps) {
                out.degenerate += 1;
                continue;
            }
            let mut key = v;
            key.sort_unstable();
            if !tris.insert(key) {
                out.duplicates += 1;
                continue;
            }
            out.face_indices.extend_from_slice(&v);
            out.source_corner.extend([w[0], w[0] + 1, w[0] + 2]);
            out.face_offsets.push(out.face_indices.len() as u32);
            out.source_face.push(f as u32);
            continue;
        }
        ring.clear();
        for corner in w[0]..w[1] {
            let c = cluster_of[mesh.face_indices[corner as usize] as usize];
            debug_assert_ne!(c, UNUSED);
            ring.push((c, corner));
        }
        collapse_ring(&mut ring);
        if ring.len() < 3 || zero_area(&ring, reps) {
            out.degenerate += 1;
            continue;
        }
        let fresh = if ring.len() == 3 {
            let mut key = [ring[0].0, ring[1].0, ring[2].0];
            key.sort_unstable();
            tris.insert(key)
        } else {
            polys.insert(canonical_polygon(&ring))
        };
        if !fresh {
            out.duplicates += 1;
            continue;
        }
        out.face_indices.extend(ring.iter().map(|r| r.0));
        out.source_corner.extend(ring.iter().map(|r| r.1));
        out.face_offsets.push(out.face_indices.len() as u32);
        out.source_face.push(f as u32);
    }
    out
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

/// A set of sorted triangles (open addressing; the first insert of a key wins).
struct TriangleSet {
    slots: Vec<[u32; 3]>,
    mask: usize,
    len: usize,
}

impl TriangleSet {
    fn with_capacity(n: usize) -> TriangleSet {
        let size = (n.max(8) * 2).next_power_of_two();
        TriangleSet {
            slots: vec![[u32::MAX; 3]; size],
            mask: size - 1,
            len: 0,
        }
    }

    /// Inserts `key`; false when it was already there.
    fn insert(&mut self, key: [u32; 3]) -> bool {
        if (self.len + 1) * 2 > self.slots.len() {
            let old = std::mem::take(&mut self.slots);
            *self = TriangleSet::with_capacity(old.len());
            for k in old.into_iter().filter(|k| k[0] != u32::MAX) {
                self.insert(k);
            }
        }
        let h = mix(u64::from(key[0]) << 32 | u64::from(key[1])) ^ mix(u64::from(key[2]));
        let mut slot = h as usize & self.mask;
        loop {
            let s = self.slots[slot];
            if s == key {
                return false;
            }
            if s[0] == u32::MAX {
                self.slots[slot] = key;
                self.len += 1;
                return true;
            }
            slot = (slot + 1) & self.mask;
        }
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
