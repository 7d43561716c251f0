//! Where each cluster's vertices merge to (Belblidia & Perrin, section 2, "fusion des
//! sommets"): the weighted barycentre or the heaviest vertex, as in the paper, or — beyond it —
//! the quadric minimiser of the cluster's face planes (Lindstrom 2000).

use crate::adaptive_partition::LeafView;
use crate::area_vector;
use crate::blocks;
use crate::cluster_stats::{self, Stats};
use crate::options::Representative;
use crate::partition::Members;
use crate::quadric::Quadric;
use rayon::prelude::*;
use tessd_mesh::Mesh;

/// Clusters whose quadrics are summed at once (80 bytes each, so 0.65 MB): the quadric
/// representatives are placed chunk by chunk (a chunk per core at a time), and no quadric is
/// held for every cluster.
const CHUNK: usize = 1 << 13;

/// Where the clusters' vertices, hence their statistics, come from.
#[derive(Clone, Copy)]
pub(crate) enum Source<'a> {
    /// The grid's clusters: each one's vertices, with the positions and weights.
    Members(&'a Members, &'a [[f32; 3]], &'a [f32]),
    /// Each cluster's vertices, as a range of an adaptive partition's vertex order: the
    /// statistics are summed cluster by cluster as it is placed (`cluster_stats::of_points`).
    Leaves(LeafView<'a>),
}

impl Source<'_> {
    /// The statistics of cluster `c` (`scratch` is reused between calls).
    fn stats(&self, c: usize, scratch: &mut Vec<u64>) -> Stats {
        match self {
            Source::Members(m, positions, weights) => {
                cluster_stats::of_members(m.of(c), positions, weights)
            }
            Source::Leaves(view) => cluster_stats::of_points(view.points(c), scratch),
        }
    }
}

/// The position of each of the `n` clusters of `cluster_of`, from their statistics (`source`).
///
/// With [`Representative::Quadric`] the minimiser is kept only when it stays inside the
/// cluster's box of vertices (grown by a quarter of its diagonal) and, when `tolerance` is set
/// (quality goal, whose `source` is [`Source::Leaves`]), only when every vertex of the cluster
/// stays within `tolerance` of it; otherwise the cluster falls back to its weighted barycentre,
/// which the quality partition already guarantees. Every cluster is solved on its own, so the
/// sweep runs on every core.
pub(crate) fn place(
    mesh: &Mesh,
    cluster_of: &[u32],
    n: usize,
    source: Source,
    rep: Representative,
    tolerance: Option<f64>,
) -> Vec<[f32; 3]> {
    debug_assert!(tolerance.is_none() || matches!(source, Source::Leaves(_)));
    let mut reps = vec![[0f32; 3]; n];
    match rep {
        Representative::Barycenter | Representative::Heaviest => {
            let heaviest = rep == Representative::Heaviest;
            each_cluster(&mut reps, 0, |c, out, scratch| {
                let s = source.stats(c, scratch);
                *out = if heaviest {
                    mesh.positions[s.heaviest as usize]
                } else {
                    s.barycentre().map(|x| x as f32)
                };
            });
        }
        Representative::Quadric => {
            let touched = chunks_touched(mesh, cluster_of, n);
            // Chunks are independent (their own clusters, their own partial sums): several
            // at once, since one chunk's clusters meet only the few blocks of faces around them.
            reps.par_chunks_mut(CHUNK).enumerate().for_each(|(k, out)| {
                let first = k * CHUNK;
                let quadrics = chunk_quadrics(mesh, cluster_of, &touched, k, out.len());
                each_cluster(out, first, |c, out, scratch| {
                    let s = source.stats(c, scratch);
                    let x0 = s.barycentre();
                    *out = quadric_point(&quadrics[c - first], &s, x0);
                    if let (Some(tol), Source::Leaves(view)) = (tolerance, source)
                        && view.points(c).iter().any(|q| dist(*out, q.p) > tol)
                    {
                        *out = x0.map(|x| x as f32);
                    }
                });
            });
        }
    }
    reps
}

/// Calls `f(cluster, its representative, scratch)` for each of `reps` (clusters `first..`), in
/// fixed blocks on every core.
fn each_cluster(
    reps: &mut [[f32; 3]],
    first: usize,
    f: impl Fn(usize, &mut [f32; 3], &mut Vec<u64>) + Sync,
) {
    reps.par_chunks_mut(blocks::BLOCK)
        .enumerate()
        .for_each(|(b, chunk)| {
            let mut scratch = Vec::new();
            for (i, out) in chunk.iter_mut().enumerate() {
                f(first + b * blocks::BLOCK + i, out, &mut scratch);
            }
        });
}

/// The quadric minimiser of a cluster with quadric `q` and statistics `s`, kept when it stays
/// inside the cluster's box of vertices grown by a quarter of its diagonal; else `x0`, the
/// barycentre.
fn quadric_point(q: &Quadric, s: &Stats, x0: [f64; 3]) -> [f32; 3] {
    let x = q.minimizer(x0);
    let (lo, hi) = (s.lo, s.hi);
    let diag = (0..3)
        .map(|k| f64::from(hi[k] - lo[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    let margin = 0.25 * diag;
    let inside =
        (0..3).all(|k| x[k] >= f64::from(lo[k]) - margin && x[k] <= f64::from(hi[k]) + margin);
    if inside && x.iter().all(|v| v.is_finite()) {
        x
    } else {
        x0
    }
    .map(|v| v as f32)
}

/// For each fixed block of faces, the chunks of [`CHUNK`] clusters its faces touch (a bit set
/// of `n.div_ceil(CHUNK)` bits), so that summing a chunk's quadrics visits only those blocks.
fn chunks_touched(mesh: &Mesh, cluster_of: &[u32], n: usize) -> Vec<Vec<u64>> {
    let words = n.div_ceil(CHUNK).div_ceil(64);
    if n <= CHUNK {
        // One chunk: every block touches it.
        return vec![vec![1]; mesh.face_count().div_ceil(blocks::BLOCK)];
    }
    blocks::map(mesh.face_count(), |r| {
        let mut bits = vec![0u64; words];
        let corners = mesh.face_offsets[r.start] as usize..mesh.face_offsets[r.end] as usize;
        for &v in &mesh.face_indices[corners] {
            let k = cluster_of[v as usize] as usize / CHUNK;
            bits[k / 64] |= 1 << (k % 64);
        }
        bits
    })
}

/// Sums, for the `len` clusters of chunk `k`, the area-weighted plane quadrics of the faces
/// touching them (each face once per distinct cluster among its corners): Lindstrom 2000,
/// section 3.2, where each triangle's quadric goes to the cells of its vertices. Fixed blocks
/// of faces sum into partial quadrics of their own, added into the clusters in block order
/// ([`crate::blocks`]); a cluster's sum is the same whichever chunk it is in, since it is made
/// of the same partials in the same order.
fn chunk_quadrics(
    mesh: &Mesh,
    cluster_of: &[u32],
    touched: &[Vec<u64>],
    k: usize,
    len: usize,
) -> Vec<Quadric> {
    let first = (k * CHUNK) as u32;
    let last = first + len as u32;
    let blocks: Vec<usize> = (0..touched.len())
        .filter(|&b| touched[b][k / 64] >> (k % 64) & 1 == 1)
        .collect();
    let partials: Vec<(Vec<u32>, Vec<Quadric>)> = blocks
        .par_iter()
        .map(|&b| {
            let r = b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(mesh.face_count());
            // The block's id of each cluster of the chunk, in the order the block meets them.
            let mut local = vec![u32::MAX; len];
            let (mut keys, mut q) = (Vec::new(), Vec::<Quadric>::new());
            let mut seen: Vec<u32> = Vec::with_capacity(8);
            for f in r {
                let face = mesh.face(f);
                let inside = |&v: &u32| (first..last).contains(&cluster_of[v as usize]);
                if !face.iter().any(inside) {
                    continue;
                }
                let (normal, area, centroid) = plane_of(mesh, face);
                if area <= 0.0 {
                    continue;
                }
                let d =
                    -(normal[0] * centroid[0] + normal[1] * centroid[1] + normal[2] * centroid[2]);
                let fq = Quadric::plane(normal, d, area);
                seen.clear();
                for &v in face {
                    let c = cluster_of[v as usize];
                    if !seen.contains(&c) {
                        seen.push(c);
                        if !(first..last).contains(&c) {
                            continue;
                        }
                        let slot = &mut local[(c - first) as usize];
                        if *slot == u32::MAX {
                            *slot = q.len() as u32;
                            keys.push(c);
                            q.push(Quadric::default());
                        }
                        q[*slot as usize].add(&fq);
                    }
                }
            }
            (keys, q)
        })
        .collect();
    let mut q = vec![Quadric::default(); len];
    for (keys, partial) in &partials {
        for (&c, p) in keys.iter().zip(partial) {
            q[(c - first) as usize].add(p);
        }
    }
    q
}

/// Unit normal, area and a point of the plane of a face (the first corner of a triangle, the
/// centroid of a polygon).
fn plane_of(mesh: &Mesh, face: &[u32]) -> ([f64; 3], f64, [f64; 3]) {
    let p = |i: usize| area_vector::f64_point(mesh.positions[face[i] as usize]);
    let (n, at) = match face.len() {
        3 => (area_vector::triangle(p(0), p(1), p(2)), p(0)),
        m => {
            let c = (0..m).map(p).fold(glam::DVec3::ZERO, |c, q| c + q);
            (area_vector::polygon(m, p), c / m as f64)
        }
    };
    let len = n.length();
    if len == 0.0 {
        return ([0.0; 3], 0.0, at.to_array());
    }
    ((n / len).to_array(), 0.5 * len, at.to_array())
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (f64::from(a[k]) - f64::from(b[k])).powi(2))
        .sum::<f64>()
        .sqrt()
}
