//! Fan triangulation, the deterministic random generator, and stratified area- and
//! length-weighted sample placement.

use crate::geom::{V3, triangle_area, v64};
use rayon::prelude::*;
use tessd_mesh::Mesh;

/// SplitMix64 (Steele, Lea & Flood 2014): tiny, fast, passes BigCrush, and trivially seeded per
/// stream, which is what deterministic parallel sampling needs.
#[derive(Clone, Debug)]
pub(crate) struct Rng(u64);

#[inline(always)]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// The generator for stream `stream` of seed `seed` (streams are independent).
    pub(crate) fn new(seed: u64, stream: u64) -> Rng {
        Rng(mix64(
            seed ^ mix64(stream.wrapping_add(0x9E37_79B9_7F4A_7C15)),
        ))
    }

    #[inline(always)]
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.0)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    #[inline(always)]
    pub(crate) fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// The fan triangles of a mesh's faces with non-zero area, in face order, and their areas.
pub(crate) struct Triangles {
    pub tris: Vec<[u32; 3]>,
    pub areas: Vec<f64>,
}

/// Faces per parallel work item of [`triangulate`].
const FACE_CHUNK: usize = 1 << 15;

/// Fan-triangulates every face (`v0, vi, vi+1`) and drops triangles of zero (or non-finite)
/// area. Runs in parallel over chunks of faces; the output order is the face order.
pub(crate) fn triangulate(mesh: &Mesh) -> Triangles {
    let pos = &mesh.positions;
    let nf = mesh.face_count();
    let parts: Vec<Triangles> = (0..nf.div_ceil(FACE_CHUNK))
        .into_par_iter()
        .map(|c| {
            let (f0, f1) = (c * FACE_CHUNK, ((c + 1) * FACE_CHUNK).min(nf));
            let corners = (mesh.face_offsets[f1] - mesh.face_offsets[f0]) as usize;
            let cap = corners.saturating_sub(2 * (f1 - f0));
            let mut out = Triangles {
                tris: Vec::with_capacity(cap),
                areas: Vec::with_capacity(cap),
            };
            for f in f0..f1 {
                let f = mesh.face(f);
                for i in 1..f.len().saturating_sub(1) {
                    let t = [f[0], f[i], f[i + 1]];
                    let area = triangle_area(
                        v64(pos[t[0] as usize]),
                        v64(pos[t[1] as usize]),
                        v64(pos[t[2] as usize]),
                    );
                    if area > 0.0 && area.is_finite() {
                        out.tris.push(t);
                        out.areas.push(area);
                    }
                }
            }
            out
        })
        .collect();
    if parts.len() == 1 {
        return parts.into_iter().next().unwrap();
    }
    let n = parts.iter().map(|p| p.tris.len()).sum();
    let mut all = Triangles {
        tris: Vec::with_capacity(n),
        areas: Vec::with_capacity(n),
    };
    for p in parts {
        all.tris.extend_from_slice(&p.tris);
        all.areas.extend_from_slice(&p.areas);
    }
    all
}

/// Spreads the low 21 bits of `v` to every third bit.
#[inline(always)]
fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// The indices `0..n` ordered along a Z-order (Morton) curve through the points `point(i)`
/// (quantised to 21 bits per axis in their bounding box; ties by index, so the order is
/// unique). Samples taken in this order are spatially coherent whatever the element order of
/// the input, which keeps the closest-point queries' seeds good and their memory accesses
/// local.
pub(crate) fn morton_order(n: usize, point: impl Fn(usize) -> V3 + Sync) -> Vec<u32> {
    let (lo, hi) = (0..n)
        .into_par_iter()
        .fold(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(mut lo, mut hi), i| {
                let p = point(i);
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
                (lo, hi)
            },
        )
        .reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |a, b| {
                (
                    [a.0[0].min(b.0[0]), a.0[1].min(b.0[1]), a.0[2].min(b.0[2])],
                    [a.1[0].max(b.1[0]), a.1[1].max(b.1[1]), a.1[2].max(b.1[2])],
                )
            },
        );
    let extent = (0..3).fold(0.0f64, |e, k| e.max(hi[k] - lo[k]));
    let scale = if extent > 0.0 {
        ((1u64 << 21) - 1) as f64 / extent
    } else {
        0.0
    };
    let mut keys: Vec<(u64, u32)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let p = point(i);
            let q = |k: usize| ((p[k] - lo[k]) * scale) as u64; // saturating, NaN-free
            (
                spread3(q(0)) | (spread3(q(1)) << 1) | (spread3(q(2)) << 2),
                i as u32,
            )
        })
        .collect();
    keys.par_sort_unstable();
    keys.into_par_iter().map(|(_, i)| i).collect()
}

/// Inclusive running sums with a leading 0: `cum[i]..cum[i + 1]` is element `i`'s share.
pub(crate) fn cumulative(weights: &[f64]) -> Vec<f64> {
    let mut cum = Vec::with_capacity(weights.len() + 1);
    let mut s = 0.0;
    cum.push(0.0);
    for &w in weights {
        s += w;
        cum.push(s);
    }
    cum
}

/// Indices of the vertices used by at least one face, ascending.
pub(crate) fn referenced_vertices(mesh: &Mesh) -> Vec<u32> {
    let mut used = vec![false; mesh.positions.len()];
    for &v in &mesh.face_indices {
        used[v as usize] = true;
    }
    used.iter()
        .enumerate()
        .filter_map(|(i, &u)| u.then_some(i as u32))
        .collect()
}

/// The distinct polygon edges (fan diagonals excluded) of non-zero length, sorted, and their
/// lengths.
pub(crate) fn polygon_edges(mesh: &Mesh) -> (Vec<[u32; 2]>, Vec<f64>) {
    let mut edges: Vec<[u32; 2]> = mesh
        .face_offsets
        .par_windows(2)
        .flat_map_iter(|w| {
            let f = &mesh.face_indices[w[0] as usize..w[1] as usize];
            (0..f.len()).map(move |i| {
                let (a, b) = (f[i], f[(i + 1) % f.len()]);
                [a.min(b), a.max(b)]
            })
        })
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    let pos = &mesh.positions;
    let pairs: Vec<([u32; 2], f64)> = edges
        .par_iter()
        .filter_map(|e| {
            let l = v64(pos[e[0] as usize]).distance(v64(pos[e[1] as usize]));
            (l > 0.0 && l.is_finite()).then_some((*e, l))
        })
        .collect();
    pairs.into_iter().unzip()
}

/// Stratified placement of `total` samples along a cumulative weight array: sample `k` falls
/// at `(k + u_k) / total` of the total weight (one jittered sample per stratum), so every
/// element gets its share of samples to within one, with far less variance than independent
/// Monte Carlo draws. Calls `emit(element, fraction_within_element, rng)` for samples
/// `start..end` in order; the element walk is linear after one binary search.
pub(crate) fn stratified(
    cum: &[f64],
    total: u64,
    start: u64,
    end: u64,
    rng: &mut Rng,
    mut emit: impl FnMut(usize, f64, &mut Rng),
) {
    let n = cum.len() - 1;
    let w = cum[n];
    let step = w / total as f64;
    let t0 = start as f64 * step;
    let mut j = cum
        .partition_point(|&c| c <= t0)
        .saturating_sub(1)
        .min(n - 1);
    for k in start..end {
        let t = (k as f64 + rng.f64()) * step;
        while j + 1 < n && cum[j + 1] <= t {
            j += 1;
        }
        let len = cum[j + 1] - cum[j];
        let f = if len > 0.0 {
            ((t - cum[j]) / len).clamp(0.0, 1.0)
        } else {
            rng.f64()
        };
        emit(j, f, rng);
    }
}

/// A uniformly distributed point of triangle `abc` from two uniforms in `[0, 1]` (Osada et al.
/// 2002: `(1 - √r1) a + √r1 (1 - r2) b + √r1 r2 c`).
#[inline(always)]
pub(crate) fn point_in_triangle(a: V3, b: V3, c: V3, r1: f64, r2: f64) -> V3 {
    let s = r1.sqrt();
    a * (1.0 - s) + (b * (s * (1.0 - r2)) + c * (s * r2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_uniform_and_streams_differ() {
        let mut r = Rng::new(1, 0);
        let n = 100_000;
        let mean: f64 = (0..n).map(|_| r.f64()).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.01);
        assert_ne!(Rng::new(1, 0).next_u64(), Rng::new(1, 1).next_u64());
        assert_ne!(Rng::new(1, 0).next_u64(), Rng::new(2, 0).next_u64());
    }

    #[test]
    fn stratified_counts_follow_weights() {
        let cum = cumulative(&[1.0, 0.0, 3.0, 6.0]);
        let mut counts = [0usize; 4];
        let mut rng = Rng::new(5, 0);
        // Two halves give the same elements as one pass would.
        stratified(&cum, 1000, 0, 400, &mut rng, |j, f, _| {
            assert!((0.0..=1.0).contains(&f));
            counts[j] += 1;
        });
        stratified(&cum, 1000, 400, 1000, &mut rng, |j, _, _| counts[j] += 1);
        assert_eq!(counts.iter().sum::<usize>(), 1000);
        assert_eq!(counts[1], 0);
        for (c, want) in counts.iter().zip([100, 0, 300, 600]) {
            assert!((*c as i64 - want).abs() <= 1, "{counts:?}");
        }
    }

    #[test]
    fn morton_order_follows_the_curve() {
        // A 4 × 4 grid in the plane, given in a scrambled order.
        let pts: Vec<V3> = (0..16)
            .map(|i| V3::new(((i * 7) % 4) as f64, ((i * 7) / 4 % 4) as f64, 0.0))
            .collect();
        let order = morton_order(pts.len(), |i| pts[i]);
        let xy: Vec<(f64, f64)> = order
            .iter()
            .map(|&i| (pts[i as usize][0], pts[i as usize][1]))
            .collect();
        assert_eq!(&xy[..4], &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..16).collect::<Vec<u32>>());
        assert_eq!(spread3(0b111), 0b1001001);
        assert_eq!(morton_order(0, |_| V3::ZERO), Vec::<u32>::new());
    }

    #[test]
    fn fan_triangulation_skips_degenerate() {
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [2.0, 0.0, 0.0],
            ],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2, 3]);
        m.push_face(&[0, 1, 4]); // collinear
        let t = triangulate(&m);
        assert_eq!(t.tris, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(t.areas, vec![0.5, 0.5]);
        let (e, l) = polygon_edges(&m);
        assert_eq!(e, vec![[0, 1], [0, 3], [0, 4], [1, 2], [1, 4], [2, 3]]);
        assert_eq!(l, vec![1.0, 1.0, 2.0, 1.0, 1.0, 1.0]);
        assert_eq!(referenced_vertices(&m), vec![0, 1, 2, 3, 4]);
    }
}
