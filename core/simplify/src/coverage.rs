//! Is every input face's image on the output? (Beyond the paper: what `--max-error` promises
//! is a distance between the two *surfaces*, and paper 004 bounds only how far a vertex moves.)
//!
//! Clustering moves each input vertex `v` to its cluster's representative `r(v)` and maps an
//! input triangle `(a, b, c)` affinely onto `(r(a), r(b), r(c))`: a point with barycentric
//! coordinates `(α, β, γ)` moves by at most `α|a − r(a)| + β|b − r(b)| + γ|c − r(c)|`, so by at
//! most the largest displacement `D` of the triangle's corners. Hence:
//!
//! - **output → input ≤ D**: every output face is the image of an input face;
//! - **input → output ≤ D** for an input face *whose image lies on the output*. A kept face is
//!   on it by construction (a duplicate has the very corners of the face that was kept). A face
//!   that collapsed has a segment or a point as image, which lies on the output only when that
//!   segment is an output edge, or that point an output vertex.
//!
//! This module finds the collapsed faces whose image is not on the output (*gaps*: a spike or
//! fin thinner than a cell whose faces all folded, a cluster whose every face collapsed) and
//! the clusters of their uncovered segments and points, which the quality goal splits
//! (`lib.rs`). The image of a collapsed face is read from its corner clusters: the segments
//! between consecutive distinct clusters around the face, or the single point when all its
//! corners share one cluster. (For the rare face with three distinct clusters whose
//! representatives are collinear, that asks for all three sides, more than the longest one the
//! image is; it only refines a little more.)

use crate::elimination::Eliminated;
use crate::partition::UNUSED;
use tessd_mesh::Mesh;

/// The collapsed input faces whose image is not on the output.
#[derive(Debug, Default)]
pub(crate) struct Gaps {
    /// Those faces, in input order.
    pub faces: Vec<u32>,
    /// The clusters of their uncovered segments and points, sorted, each once.
    pub clusters: Vec<u32>,
    /// How many of their image segments are no output edge.
    pub segments: u64,
    /// How many of their image points are no output vertex.
    pub points: u64,
}

impl Gaps {
    /// Whether every input face's image lies on the output.
    pub(crate) fn is_empty(&self) -> bool {
        self.clusters.is_empty()
    }
}

/// A piece of a collapsed face's image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Piece {
    /// Every corner went to this cluster.
    Point(u32),
    /// Two consecutive corners went to these distinct clusters.
    Segment(u32, u32),
}

/// Calls `f` with each piece of the image of input face `face` (its corner indices) under
/// `cluster_of`, read as a collapsed face's: the single point, or the segment between each
/// pair of consecutive corners in distinct clusters (in a polygon, a segment may come twice).
pub(crate) fn collapsed_image(face: &[u32], cluster_of: &[u32], mut f: impl FnMut(Piece)) {
    let n = face.len();
    let cluster = |i: usize| cluster_of[face[i] as usize];
    if n == 3 {
        return triangle_image([0, 1, 2].map(cluster), f);
    }
    let mut any = false;
    let mut prev = cluster(n - 1);
    for i in 0..n {
        let c = cluster(i);
        if c != prev {
            f(Piece::Segment(prev, c));
            any = true;
        }
        prev = c;
    }
    if !any {
        f(Piece::Point(prev));
    }
}

/// [`collapsed_image`] of a triangle over clusters `[a, b, c]`, the common case: a segment
/// that two of its sides share comes once, its smaller cluster first.
fn triangle_image([a, b, c]: [u32; 3], mut f: impl FnMut(Piece)) {
    let segment = |x: u32, y: u32| Piece::Segment(x.min(y), x.max(y));
    match (a == b, b == c, c == a) {
        (true, true, _) => f(Piece::Point(a)),
        (true, false, _) => f(segment(b, c)),
        (false, true, _) | (false, false, true) => f(segment(a, b)),
        (false, false, false) => {
            f(segment(a, b));
            f(segment(b, c));
            f(segment(c, a));
        }
    }
}

/// What the output covers: its vertices, and its edges as adjacency lists over clusters (an
/// edge `{a, b}` listed under the smaller id; interior edges twice), in compressed rows: two
/// linear passes over the output's faces, no hashing.
struct Covered {
    used: Vec<bool>,
    start: Vec<u32>,
    other: Vec<u32>,
}

impl Covered {
    /// The output whose faces `each_face(f)` calls `f` with (twice: once to count, once to
    /// fill each list from its end, so the row starts are the only index array).
    fn new(clusters: usize, mut each_face: impl FnMut(&mut dyn FnMut(&[u32]))) -> Self {
        let mut used = vec![false; clusters];
        let mut start = vec![0u32; clusters + 1];
        each_face(&mut |face| {
            let mut prev = face[face.len() - 1];
            for &c in face {
                used[c as usize] = true;
                start[prev.min(c) as usize] += 1;
                prev = c;
            }
        });
        for c in 1..=clusters {
            start[c] += start[c - 1];
        }
        let mut other = vec![0u32; start[clusters] as usize];
        each_face(&mut |face| {
            let mut prev = face[face.len() - 1];
            for &c in face {
                let lo = prev.min(c) as usize;
                start[lo] -= 1;
                other[start[lo] as usize] = prev.max(c);
                prev = c;
            }
        });
        Covered { used, start, other }
    }

    /// Whether `piece` lies on the output: a vertex of it, or an edge of it.
    fn covers(&self, piece: Piece) -> bool {
        match piece {
            Piece::Point(c) => self.used[c as usize],
            Piece::Segment(a, b) => {
                let (lo, hi) = (a.min(b) as usize, a.max(b));
                self.other[self.start[lo] as usize..self.start[lo + 1] as usize].contains(&hi)
            }
        }
    }
}

impl Gaps {
    /// Records an uncovered piece (the clusters are marked in `involved`).
    fn add(&mut self, piece: Piece, involved: &mut [bool]) {
        match piece {
            Piece::Point(c) => {
                self.points += 1;
                involved[c as usize] = true;
            }
            Piece::Segment(a, b) => {
                self.segments += 1;
                involved[a as usize] = true;
                involved[b as usize] = true;
            }
        }
    }

    /// Lists the `involved` clusters.
    fn finish(mut self, involved: &[bool]) -> Gaps {
        self.clusters = (0..involved.len() as u32)
            .filter(|&c| involved[c as usize])
            .collect();
        self
    }
}

/// The same check from `cluster_of` alone, before representatives are placed, for a mesh of
/// triangles: a face counts as kept when its three clusters differ. That is what elimination
/// keeps, except a face whose three representatives happen to be collinear (it reports those,
/// and then [`find_gaps`] checks the real output). Cheaper than placing and eliminating, so
/// the coverage rounds of the quality goal run on it; `faces` is left empty.
///
/// `moved`: after a round, only faces with a vertex in a cell that was split (`moved[v]`) are
/// read. The others' pieces were covered before, by a kept face with those two clusters, and
/// that face stays kept: a split gives its third cluster a new id, never one of those two.
///
/// The kept faces are read twice and the collapsed ones once more rather than copied (two bits
/// a face say which is which): neither the kept faces nor the collapsed ones' pieces are held.
/// Issue 33 (point 4) proposed one face pass putting the collapsed faces' segments into a
/// deduplicated u64 set checked against the kept faces' edges; measured on a 1 M-triangle
/// torus at 5 % of its vertices (one thread), where 9 faces in 10 collapse, sorting their
/// pieces cost more than indexing the kept edges (24.3 against 16.2 ms), and writing the
/// pieces down in the first pass instead of reading the collapsed faces again saved 2 % for
/// up to 8 bytes a face of memory: this index of the kept edges (the smaller side) stays.
pub(crate) fn gaps_by_clusters(
    mesh: &Mesh,
    cluster_of: &[u32],
    clusters: usize,
    moved: Option<&[bool]>,
) -> Gaps {
    let faces = mesh.face_indices.len() / 3;
    let (mut kept, mut collapsed) = (Bits::new(faces), Bits::new(faces));
    let read = |f: usize| {
        let t = &mesh.face_indices[3 * f..3 * f + 3];
        [0, 1, 2].map(|k| cluster_of[t[k] as usize])
    };
    let mut first = true;
    let covered = Covered::new(clusters, |each| {
        if std::mem::take(&mut first) {
            // The first reading sorts the faces.
            for f in 0..faces {
                let t = &mesh.face_indices[3 * f..3 * f + 3];
                if moved.is_some_and(|m| !t.iter().any(|&v| m[v as usize])) {
                    continue;
                }
                let t = read(f);
                if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
                    kept.set(f);
                    each(&t);
                } else {
                    collapsed.set(f);
                }
            }
        } else {
            kept.ones().for_each(|f| each(&read(f)));
        }
    });
    let mut gaps = Gaps::default();
    let mut involved = vec![false; clusters];
    // Neighbouring faces, neighbours in the mesh's order too, collapse alike: a piece that
    // repeats the one before is checked once.
    let mut last = None;
    for f in collapsed.ones() {
        triangle_image(read(f), |p| {
            if last != Some(p) {
                last = Some(p);
                if !covered.covers(p) {
                    gaps.add(p, &mut involved);
                }
            }
        });
    }
    gaps.finish(&involved)
}

/// A set of face indices, a bit each.
struct Bits {
    words: Vec<u64>,
}

impl Bits {
    fn new(n: usize) -> Bits {
        Bits {
            words: vec![0; n.div_ceil(64)],
        }
    }

    fn set(&mut self, i: usize) {
        self.words[i / 64] |= 1 << (i % 64);
    }

    /// The members, in increasing order.
    fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        self.words.iter().enumerate().flat_map(|(w, &bits)| {
            let mut bits = bits;
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let b = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    64 * w + b
                })
            })
        })
    }
}

/// Marks the vertices of `split` (sorted cluster ids under `cluster_of`, as [`Gaps::clusters`]
/// lists them): those a round of splitting can move.
pub(crate) fn vertices_of(cluster_of: &[u32], split: &[u32], clusters: usize) -> Vec<bool> {
    let mut in_split = vec![false; clusters];
    split.iter().for_each(|&c| in_split[c as usize] = true);
    cluster_of
        .iter()
        .map(|&c| c != UNUSED && in_split[c as usize])
        .collect()
}

/// The collapsed faces of `mesh` (as `kept.collapsed()` lists them) whose image under
/// `cluster_of` is not on the output `kept`, which has `clusters` clusters.
pub(crate) fn find_gaps(
    mesh: &Mesh,
    cluster_of: &[u32],
    kept: &Eliminated,
    clusters: usize,
) -> Gaps {
    let mut gaps = Gaps::default();
    if kept.degenerate == 0 {
        return gaps;
    }
    let covered = Covered::new(clusters, |f| {
        kept.face_offsets
            .windows(2)
            .for_each(|w| f(&kept.face_indices[w[0] as usize..w[1] as usize]))
    });
    let mut involved = vec![false; clusters];
    for f in kept.collapsed() {
        let mut open = false;
        collapsed_image(mesh.face(f as usize), cluster_of, |piece| {
            if !covered.covers(piece) {
                gaps.add(piece, &mut involved);
                open = true;
            }
        });
        if open {
            gaps.faces.push(f);
        }
    }
    gaps.finish(&involved)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elimination::eliminate;

    /// A fan of two triangles around vertex 0 and a spike (0, 3, 4) whose tip vertices 3 and 4
    /// share a cluster with vertex 1.
    fn spike() -> Mesh {
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 0.0, 0.01],
                [1.0, 0.01, 0.0],
            ],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2]);
        m.push_face(&[0, 3, 4]);
        m.push_face(&[3, 4, 1]);
        m
    }

    #[test]
    fn a_segment_on_an_output_edge_is_covered() {
        let m = spike();
        // 3 and 4 join 1's cluster: (0, 3, 4) becomes the segment 0–1, an edge of (0, 1, 2);
        // (3, 4, 1) becomes the point 1, an output vertex.
        let cluster_of = [0, 1, 2, 1, 1];
        let reps = [m.positions[0], m.positions[1], m.positions[2]];
        let kept = eliminate(&m, &cluster_of, &reps, false);
        assert_eq!(kept.collapsed().collect::<Vec<_>>(), vec![1, 2]);
        let gaps = find_gaps(&m, &cluster_of, &kept, 3);
        assert!(gaps.is_empty(), "{gaps:?}");
    }

    #[test]
    fn gaps_by_clusters_matches_the_definition() {
        // A 20 × 20 grid of triangles under coarse and random clusterings (with a round's
        // `moved` filter too): the clusters of the uncovered pieces, found by brute force
        // (every piece of every collapsed face against every edge of every kept face).
        let mut m = Mesh::default();
        for j in 0..21 {
            for i in 0..21 {
                m.positions.push([i as f32, j as f32, 0.0]);
            }
        }
        for j in 0..20u32 {
            for i in 0..20u32 {
                let v = j * 21 + i;
                m.push_face(&[v, v + 1, v + 22]);
                m.push_face(&[v, v + 22, v + 21]);
            }
        }
        let mut x = 99u64;
        let mut rnd = |n: u64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % n) as u32
        };
        let mut with_gaps = 0;
        for trial in 0..40 {
            let clusters = [3, 10, 40, 150][trial % 4];
            let cluster_of: Vec<u32> = (0..441)
                .map(|v| {
                    if trial % 2 == 0 {
                        rnd(clusters as u64)
                    } else {
                        ((v % 21) / 3 + 7 * ((v / 21) / 4)) as u32 % clusters
                    }
                })
                .collect();
            let moved: Option<Vec<bool>> =
                (trial % 3 == 0).then(|| (0..441).map(|_| rnd(3) == 0).collect());
            let read = |f: usize| {
                let t = &m.face_indices[3 * f..3 * f + 3];
                let skip = moved
                    .as_ref()
                    .is_some_and(|mv| !t.iter().any(|&v| mv[v as usize]));
                (!skip).then(|| [0, 1, 2].map(|k| cluster_of[t[k] as usize]))
            };
            let faces = (0..800).filter_map(read).collect::<Vec<_>>();
            let kept: Vec<_> = faces
                .iter()
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
                .collect();
            let mut expected = std::collections::BTreeSet::new();
            for t in faces
                .iter()
                .filter(|t| !(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]))
            {
                triangle_image(*t, |p| match p {
                    Piece::Point(c) => {
                        if !kept.iter().any(|k| k.contains(&c)) {
                            expected.insert(c);
                        }
                    }
                    Piece::Segment(a, b) => {
                        let edge = |k: &[u32; 3]| {
                            (0..3).any(|i| {
                                let (x, y) = (k[i], k[(i + 1) % 3]);
                                (x, y) == (a, b) || (y, x) == (a, b)
                            })
                        };
                        if !kept.iter().any(|k| edge(k)) {
                            expected.insert(a);
                            expected.insert(b);
                        }
                    }
                });
            }
            let gaps = gaps_by_clusters(&m, &cluster_of, clusters as usize, moved.as_deref());
            assert_eq!(
                gaps.clusters,
                expected.into_iter().collect::<Vec<_>>(),
                "trial {trial}"
            );
            with_gaps += usize::from(!gaps.is_empty());
        }
        // Both kinds of outcome are exercised.
        assert!((5..40).contains(&with_gaps), "{with_gaps}");
    }

    #[test]
    fn segments_and_points_off_the_output_are_gaps() {
        let m = spike();
        // 1, 3 and 4 in one cluster and 2 in 0's: every face collapses, nothing is output.
        let cluster_of = [0, 1, 0, 1, 1];
        let reps = [m.positions[0], m.positions[1]];
        let kept = eliminate(&m, &cluster_of, &reps, false);
        assert_eq!(kept.face_indices.len(), 0);
        let gaps = find_gaps(&m, &cluster_of, &kept, 2);
        assert_eq!(gaps.faces, vec![0, 1, 2]);
        assert_eq!(gaps.clusters, vec![0, 1]);
        // (0, 1, 0) and (0, 1, 1): segment 0–1 once each; (1, 1, 1): the point 1.
        assert_eq!((gaps.segments, gaps.points), (2, 1));
    }
}
