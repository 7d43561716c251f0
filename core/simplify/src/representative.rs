//! Where each cluster's vertices merge to (Belblidia & Perrin, section 2, "fusion des
//! sommets"): the weighted barycentre or the heaviest vertex, as in the paper, or — beyond it —
//! the quadric minimiser of the cluster's face planes (Lindstrom 2000).

use crate::area_vector;
use crate::blocks;
use crate::cell_table::CellTable;
use crate::cluster_stats::{self, Stats};
use crate::options::Representative;
use crate::partition::{Partition, UNUSED};
use crate::quadric::Quadric;
use rayon::prelude::*;
use tessd_mesh::Mesh;

/// The position of every cluster, from its statistics (`stats`, when the partition gathered
/// them while it binned; else gathered here).
///
/// With [`Representative::Quadric`] the minimiser is kept only when it stays inside the
/// cluster's box of vertices (grown by a quarter of its diagonal) and, when `tolerance` is set
/// (quality goal), only when every vertex of the cluster stays within `tolerance` of it;
/// otherwise the cluster falls back to its weighted barycentre, which the quality partition
/// already guarantees. Every cluster is solved on its own, so the sweep runs on every core.
pub(crate) fn place(
    mesh: &Mesh,
    weights: &[f32],
    partition: &Partition,
    stats: Option<&[Stats]>,
    rep: Representative,
    tolerance: Option<f64>,
) -> Vec<[f32; 3]> {
    let n = partition.clusters;
    let cluster_of = &partition.cluster_of;
    let gathered;
    let stats = match stats {
        Some(s) => s,
        None => {
            gathered = cluster_stats::gather(&mesh.positions, weights, cluster_of, n);
            &gathered[..]
        }
    };
    debug_assert_eq!(stats.len(), n);
    match rep {
        Representative::Barycenter => stats
            .par_iter()
            .map(|s| s.barycentre().map(|x| x as f32))
            .collect(),
        Representative::Heaviest => stats
            .par_iter()
            .map(|s| mesh.positions[s.heaviest as usize])
            .collect(),
        Representative::Quadric => {
            let quadrics = cluster_quadrics(mesh, cluster_of, n);
            let mut reps: Vec<[f32; 3]> = quadrics
                .par_iter()
                .zip(stats)
                .map(|(q, s)| {
                    let x0 = s.barycentre();
                    let x = q.minimizer(x0);
                    let (lo, hi) = (s.lo, s.hi);
                    let diag = (0..3)
                        .map(|k| f64::from(hi[k] - lo[k]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    let margin = 0.25 * diag;
                    let inside = (0..3).all(|k| {
                        x[k] >= f64::from(lo[k]) - margin && x[k] <= f64::from(hi[k]) + margin
                    });
                    if inside && x.iter().all(|v| v.is_finite()) {
                        x
                    } else {
                        x0
                    }
                    .map(|v| v as f32)
                })
                .collect();
            if let Some(tol) = tolerance {
                let mut worst = vec![0f64; n];
                for (&c, p) in cluster_of.iter().zip(&mesh.positions) {
                    if c != UNUSED {
                        let d = dist(reps[c as usize], *p);
                        worst[c as usize] = worst[c as usize].max(d);
                    }
                }
                for c in 0..n {
                    if worst[c] > tol {
                        reps[c] = stats[c].barycentre().map(|x| x as f32);
                    }
                }
            }
            reps
        }
    }
}

/// Sums, per cluster, the area-weighted plane quadrics of the faces touching it (each face once
/// per distinct cluster among its corners): Lindstrom 2000, section 3.2, where each triangle's
/// quadric goes to the cells of its vertices. Fixed blocks of faces sum into partial quadrics of
/// their own, added into the clusters in block order ([`crate::blocks`]).
fn cluster_quadrics(mesh: &Mesh, cluster_of: &[u32], n: usize) -> Vec<Quadric> {
    let partials = blocks::map(mesh.face_count(), |r| {
        let mut table = CellTable::with_capacity((r.len() / 4).max(64));
        let (mut keys, mut q) = (Vec::new(), Vec::<Quadric>::new());
        let mut seen: Vec<u32> = Vec::with_capacity(8);
        for f in r {
            let face = mesh.face(f);
            let (normal, area, centroid) = plane_of(mesh, face);
            if area <= 0.0 {
                continue;
            }
            let d = -(normal[0] * centroid[0] + normal[1] * centroid[1] + normal[2] * centroid[2]);
            let fq = Quadric::plane(normal, d, area);
            seen.clear();
            for &v in face {
                let c = cluster_of[v as usize];
                if !seen.contains(&c) {
                    seen.push(c);
                    let id = table.id(u64::from(c)) as usize;
                    if id == q.len() {
                        keys.push(c);
                        q.push(Quadric::default());
                    }
                    q[id].add(&fq);
                }
            }
        }
        (keys, q)
    });
    let mut q = vec![Quadric::default(); n];
    for (keys, partial) in &partials {
        for (&c, p) in keys.iter().zip(partial) {
            q[c as usize].add(p);
        }
    }
    q
}

/// Unit normal, area and a point of the plane of a face (the first corner of a triangle, the
/// centroid of a polygon).
fn plane_of(mesh: &Mesh, face: &[u32]) -> ([f64; 3], f64, [f64; 3]) {
    let p = |i: usize| mesh.positions[face[i] as usize].map(f64::from);
    let (n, at) = match face.len() {
        3 => (area_vector::triangle(p(0), p(1), p(2)), p(0)),
        m => {
            let mut c = [0f64; 3];
            for i in 0..m {
                let q = p(i);
                (0..3).for_each(|k| c[k] += q[k]);
            }
            let c = c.map(|x| x / m as f64);
            (area_vector::polygon(m, p), c)
        }
    };
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len == 0.0 {
        return ([0.0; 3], 0.0, at);
    }
    (n.map(|x| x / len), 0.5 * len, at)
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (f64::from(a[k]) - f64::from(b[k])).powi(2))
        .sum::<f64>()
        .sqrt()
}
