//! Where each cluster's vertices merge to (Belblidia & Perrin, section 2, "fusion des
//! sommets"): the weighted barycentre or the heaviest vertex, as in the paper, or — beyond it —
//! the quadric minimiser of the cluster's face planes (Lindstrom 2000).

use crate::adaptive_partition::LeafView;
use crate::area_vector;
use crate::blocks;
use crate::cell_table::CellTable;
use crate::cluster_stats::{self, Stats};
use crate::options::Representative;
use crate::partition::Members;
use crate::quadric::Quadric;
use rayon::prelude::*;
use std::ops::Range;
use tessd_mesh::Mesh;

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
            // Every cluster's quadric in one pass over the faces (no rescan per chunk of
            // clusters), then each cluster solved on its own.
            // The adaptive goals hold their points (16 to 24 bytes a vertex) while they
            // place: their chunks are smaller, to stay within the same memory limit.
            let share = match source {
                Source::Members(..) => GRID_SHARE,
                Source::Leaves(_) => ADAPTIVE_SHARE,
            };
            for_each_quadric_chunk(mesh, cluster_of, n, share, |first, quadrics| {
                let out = &mut reps[first..first + quadrics.len()];
                each_cluster(out, first, |c, out, scratch| {
                    let s = source.stats(c, scratch);
                    let x0 = s.barycentre();
                    *out = quadric_point(&quadrics[c - first], [s.lo, s.hi], x0);
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

/// The quadric minimiser of a cluster with quadric `q`, kept when it stays inside the box
/// `lo`–`hi` of the cluster's vertices grown by a quarter of its diagonal; else `x0`, the
/// barycentre.
pub(crate) fn quadric_point(q: &Quadric, [lo, hi]: [[f32; 3]; 2], x0: [f64; 3]) -> [f32; 3] {
    let x = q.minimizer(x0);
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

/// Sums, for each of the `n` clusters of `cluster_of`, the area-weighted plane quadrics of
/// the faces touching it (each face once per distinct cluster among its corners): Lindstrom
/// 2000, section 3.2, where each triangle's quadric goes to the cells of its vertices; calls
/// `f(first cluster, their quadrics)` a chunk of clusters at a time.
///
/// A chunk is `1 / share` as many clusters as the mesh has vertices (at least 32 768): its
/// quadrics (80 bytes each) stay under a fraction of the input's size, so the representatives
/// keep the extra peak memory under twice the input; every call with at most
/// [`ONE_PASS_SHARE`]'s share of clusters is one chunk, and a mesh
/// simplified to more than `1 / share` of its vertices takes one more cheap pass per chunk
/// (faces without a corner in the chunk are skipped on their cluster ids).
///
/// Per chunk, one pass over the faces in fixed blocks ([`crate::blocks`]): each block sums into partial
/// quadrics of its own (a small table from cluster to partial, with a cache of the last
/// clusters met, since consecutive faces mostly hit the same clusters), and the partials are
/// added into the clusters in block order, so a cluster's sum is the same bits on any number
/// of threads. The blocks go in waves (a block per core): while one wave's partials are added
/// in (one core), the next wave sums (the others), and only one wave's partials are held.
pub(crate) fn for_each_quadric_chunk(
    mesh: &Mesh,
    cluster_of: &[u32],
    n: usize,
    share: usize,
    mut f: impl FnMut(usize, &[Quadric]),
) {
    let v = mesh.vertex_count();
    let chunk = if n <= v / ONE_PASS_SHARE {
        n.max(1)
    } else {
        (v / share).max(MIN_CHUNK)
    };
    for first in (0..n).step_by(chunk) {
        let range = first as u32..(first + chunk).min(n) as u32;
        f(
            first,
            &if n <= v / HOLD_SHARE {
                cluster_quadrics::<true>(mesh, cluster_of, range)
            } else {
                cluster_quadrics::<false>(mesh, cluster_of, range)
            },
        );
    }
}

/// A grid's quadric chunk holds a sixth of the vertex count in clusters ([`for_each_quadric_chunk`]).
pub(crate) const GRID_SHARE: usize = 6;

/// An adaptive goal's quadric chunk holds a twelfth: its kd points are alive beside it (the
/// complexity goal at 50 % of a 1 M-triangle torus: extra peak 2.26× the input with a quarter,
/// 65769d72's 1.81×).
const ADAPTIVE_SHARE: usize = 12;

/// Up to `1 / ONE_PASS_SHARE` of the vertex count in clusters, every cluster goes in one
/// chunk, one face pass: the quality goal at 10 % of a 1 M-triangle torus (50 k clusters)
/// took two passes with a twelfth. Its quadrics (≤ 10 bytes a vertex, a twelfth's 6.7 and
/// 3.3 more) stay within the memory limit, since the arrays of 16 bytes a cluster that are
/// alive beside them (leaf starts, representatives) hold 6 bytes a vertex less than at the
/// 50 % target, where the limit is measured.
const ONE_PASS_SHARE: usize = 8;

/// With at most `1 / HOLD_SHARE` of the vertex count in clusters (8 vertices or more a
/// cluster), the face passes hold the sum of a cluster whose faces follow one another in
/// registers (`cluster_quadrics`); with smaller clusters, whose faces are seldom wholly
/// inside, they add in memory: the face pass on a 1 M-triangle torus with kd clusters, one
/// thread, core time (`perf stat -e task-clock`, `representative_speed.rs`) at 1 % / 10 % /
/// 43 % of the vertices: held 11.9 / 20.5 / 48.3 ms, in memory 17.2 / 21.7 / 45.5 ms.
const HOLD_SHARE: usize = 8;

/// Fewest clusters a chunk of [`for_each_quadric_chunk`] takes (fewer in the unit tests, so
/// that they cross chunks).
const MIN_CHUNK: usize = if cfg!(test) { 1 << 10 } else { 1 << 15 };

#[cfg(test)]
#[path = "representative_speed.rs"]
mod speed;

/// The quadrics of the clusters of `range` ([`for_each_quadric_chunk`]); `HOLD`: see
/// [`HOLD_SHARE`].
fn cluster_quadrics<const HOLD: bool>(
    mesh: &Mesh,
    cluster_of: &[u32],
    range: Range<u32>,
) -> Vec<Quadric> {
    let (first, n) = (range.start, range.len());
    let blocks = mesh.face_count().div_ceil(blocks::BLOCK);
    if blocks::single_thread() {
        // One core: the same sums with a table only for the clusters that earlier blocks
        // touched. The first block that touches a cluster sums straight into its total (0 +
        // its faces in order: the same bits as its partial, which the parallel merge adds to
        // 0); a later block sums into a partial of its own, added at the block's end (so in
        // block order).
        let mut sums = OneCore {
            first,
            q: vec![Quadric::default(); n],
            block_of: vec![u32::MAX; n],
            table: CellTable::with_capacity(256),
            keys: vec![],
            part: vec![],
        };
        for b in 0..blocks {
            let r = b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(mesh.face_count());
            let b = b as u32;
            // The cluster of the last faces wholly in one cluster, and its slot's running
            // value, held in registers while faces keep adding to it (the same adds in the
            // same order: the same bits): each add no longer waits for the store of the one
            // before. A face across clusters adds into their slots in memory, and leaves the
            // open one open.
            let mut open = (u32::MAX, Quadric::default());
            each_face_quadric(mesh, cluster_of, &range, r, |c, fq, whole| {
                if HOLD && c == open.0 {
                    open.1.add(fq);
                } else if !(HOLD && whole) {
                    sums.slot(c, b).add(fq);
                } else {
                    if open.0 != u32::MAX {
                        *sums.slot(open.0, b) = open.1;
                    }
                    let mut v = *sums.slot(c, b);
                    v.add(fq);
                    open = (c, v);
                }
            });
            if HOLD && open.0 != u32::MAX {
                *sums.slot(open.0, b) = open.1;
            }
            for (&c, p) in sums.keys.iter().zip(&sums.part) {
                sums.q[(c - first) as usize].add(p);
            }
            if !sums.keys.is_empty() {
                sums.table = CellTable::with_capacity(256);
                (sums.keys, sums.part) = (vec![], vec![]);
            }
        }
        return sums.q;
    }
    let mut q = vec![Quadric::default(); n];
    let merge = |q: &mut Vec<Quadric>, partials: Vec<(Vec<u32>, Vec<Quadric>)>| {
        for (keys, partial) in &partials {
            for (&c, p) in keys.iter().zip(partial) {
                q[(c - first) as usize].add(p);
            }
        }
    };
    let mut pending: Option<Vec<(Vec<u32>, Vec<Quadric>)>> = None;
    // A block per core a wave: the partials held stay a few blocks' worth. (The wave size
    // does not change the sums: they are added in block order whatever it is.)
    let wave_blocks = rayon::current_num_threads().max(2);
    for wave in (0..blocks).step_by(wave_blocks) {
        let sum = || {
            (wave..(wave + wave_blocks).min(blocks))
                .into_par_iter()
                .map(|b| block_quadrics::<HOLD>(mesh, cluster_of, &range, b))
                .collect()
        };
        let previous = pending.take();
        let (partials, ()) = rayon::join(sum, || {
            if let Some(p) = previous {
                merge(&mut q, p);
            }
        });
        pending = Some(partials);
    }
    if let Some(p) = pending {
        merge(&mut q, p);
    }
    q
}

/// The one-core sums of [`cluster_quadrics`]: the totals of a chunk's clusters, the first
/// block that touched each, and the current block's partials of the clusters that an earlier
/// block touched.
struct OneCore {
    first: u32,
    q: Vec<Quadric>,
    block_of: Vec<u32>,
    table: CellTable,
    keys: Vec<u32>,
    part: Vec<Quadric>,
}

impl OneCore {
    /// Where block `b` sums cluster `c`'s faces: its total when `b` is the first block to touch
    /// it, else its partial for `b`.
    fn slot(&mut self, c: u32, b: u32) -> &mut Quadric {
        let i = (c - self.first) as usize;
        let at = &mut self.block_of[i];
        if *at == u32::MAX {
            *at = b;
        }
        if *at == b {
            &mut self.q[i]
        } else {
            let id = self.table.id(u64::from(c)) as usize;
            if id == self.keys.len() {
                self.keys.push(c);
                self.part.push(Quadric::default());
            }
            &mut self.part[id]
        }
    }
}

/// Block `b`'s partial quadrics: the clusters it touches in the order it meets them, and
/// each one's sum over the block's faces in face order.
fn block_quadrics<const HOLD: bool>(
    mesh: &Mesh,
    cluster_of: &[u32],
    range: &Range<u32>,
    b: usize,
) -> (Vec<u32>, Vec<Quadric>) {
    let r = b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(mesh.face_count());
    let mut table = CellTable::with_capacity(1024);
    // The last cluster met at each of a few cache places, and its partial.
    let mut recent = [(u32::MAX, 0u32); 64];
    let (mut keys, mut q) = (Vec::new(), Vec::<Quadric>::new());
    // The cluster of the last face wholly in one, its slot and the slot's running value
    // (see the one-core path of `cluster_quadrics`).
    let mut open = (u32::MAX, 0u32, Quadric::default());
    each_face_quadric(mesh, cluster_of, range, r, |c, fq, whole| {
        if HOLD && c == open.0 {
            open.2.add(fq);
            return;
        }
        let hit = &mut recent[c as usize % recent.len()];
        let slot = if hit.0 == c {
            hit.1
        } else {
            let id = table.id(u64::from(c));
            if id as usize == keys.len() {
                keys.push(c);
                q.push(Quadric::default());
            }
            *hit = (c, id);
            id
        };
        if !(HOLD && whole) {
            q[slot as usize].add(fq);
            return;
        }
        if open.0 != u32::MAX {
            q[open.1 as usize] = open.2;
        }
        let mut sum = q[slot as usize];
        sum.add(fq);
        open = (c, slot, sum);
    });
    if HOLD && open.0 != u32::MAX {
        q[open.1 as usize] = open.2;
    }
    (keys, q)
}

/// Calls `f(cluster, the face's quadric, whole)` for every face of `faces`, in order, once
/// for each distinct cluster of `range` among its corners (Lindstrom's rule: a face's quadric
/// goes to the cells of its vertices, once per cell); faces without a corner in `range`, or of
/// zero area, are passed over. `whole`: every corner of the face is in `cluster` (told for
/// triangles only), so that a caller may hold a run of such faces' sum in registers.
#[inline(always)]
fn each_face_quadric(
    mesh: &Mesh,
    cluster_of: &[u32],
    range: &Range<u32>,
    faces: Range<usize>,
    mut f: impl FnMut(u32, &Quadric, bool),
) {
    if let Some(triangles) = mesh.triangles() {
        each_triangle_quadric(&mesh.positions, &triangles[faces], cluster_of, range, f);
        return;
    }
    let mut seen: Vec<u32> = Vec::with_capacity(8);
    for face in faces.map(|i| mesh.face(i)) {
        if !face
            .iter()
            .any(|&v| range.contains(&cluster_of[v as usize]))
        {
            continue;
        }
        let Some(fq) = face_quadric(mesh, face) else {
            continue;
        };
        seen.clear();
        for &v in face {
            let c = cluster_of[v as usize];
            if range.contains(&c) && !seen.contains(&c) {
                seen.push(c);
                f(c, &fq, false);
            }
        }
    }
}

/// Triangles a batch of [`each_triangle_quadric`] holds.
const BATCH: usize = 16;

/// [`each_face_quadric`] for a mesh of triangles, by batches of [`BATCH`] faces: first the
/// area vectors of a batch's faces with a corner in `range`, then their weights (`0.5 / |N|`,
/// a square root and a division each: with one face at a time their latency chain bound the
/// pass, 25 % of its samples; a batch's roots are independent and issue back to back), then
/// the quadrics, added in face order. The same arithmetic as [`face_quadric`], so the same
/// bits.
#[inline(always)]
fn each_triangle_quadric(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    cluster_of: &[u32],
    range: &Range<u32>,
    mut f: impl FnMut(u32, &Quadric, bool),
) {
    let (first, len) = (range.start, range.end - range.start);
    let inside = |c: u32| c.wrapping_sub(first) < len;
    let mut normal = [[0f64; 3]; BATCH];
    let mut offset = [0f64; BATCH];
    let mut len2 = [0f64; BATCH];
    let mut weight = [0f64; BATCH];
    let mut clusters = [[0u32; 3]; BATCH];
    for batch in triangles.chunks(BATCH) {
        let mut k = 0;
        for t in batch {
            let c = t.map(|v| cluster_of[v as usize]);
            if !(inside(c[0]) || inside(c[1]) || inside(c[2])) {
                continue;
            }
            let p = t.map(|v| area_vector::f64_point(positions[v as usize]));
            let n = area_vector::triangle(p[0], p[1], p[2]);
            normal[k] = n.to_array();
            offset[k] = -n.dot(p[0]);
            len2[k] = n.length_squared();
            clusters[k] = c;
            k += 1;
        }
        // The faces kept, rounded up to pairs (the compiler pairs the roots); none when the
        // batch has no face in `range`, as most batches of a later chunk's pass.
        let m = k.next_multiple_of(2);
        for (w, l) in weight[..m].iter_mut().zip(&len2[..m]) {
            *w = 0.5 / l.sqrt();
        }
        for i in 0..k {
            if len2[i] == 0.0 {
                continue;
            }
            let q = Quadric::plane(normal[i], offset[i], weight[i]);
            let [a, b, c] = clusters[i];
            let whole = a == b && a == c;
            if inside(a) {
                f(a, &q, whole);
            }
            if b != a && inside(b) {
                f(b, &q, false);
            }
            if c != a && c != b && inside(c) {
                f(c, &q, false);
            }
        }
    }
}

/// The area-weighted quadric of a face's plane; `None` for a face of zero area.
///
/// From the unnormalised area vector `N` (twice the area times the unit normal) and a point
/// `p` of the plane: `area · (n·x + d)² = (N·x − N·p)² · ½ / |N|`, so one square root and one
/// division a face, not a division per component of the normal (the latency chain that bound
/// the quadric pass; a few ulps from normalising first).
#[inline(always)] // Into the face loops: the next faces' loads overlap this one's root.
fn face_quadric(mesh: &Mesh, face: &[u32]) -> Option<Quadric> {
    if let &[a, b, c] = face {
        return triangle_quadric([a, b, c].map(|v| mesh.positions[v as usize]));
    }
    let (n, at) = area_vector_of(mesh, face);
    plane_quadric(n, at)
}

/// The area-weighted quadric of the triangle `p` ([`face_quadric`]; `None` for zero area):
/// the bits the batched walk of [`each_triangle_quadric`] gives, for the grid's own face pass.
/// A pass that calls it face after face waits on its root and division: computing a few
/// faces' area vectors before their weights, as [`each_triangle_quadric`] does, hides them.
#[inline(always)]
pub(crate) fn triangle_quadric(p: [[f32; 3]; 3]) -> Option<Quadric> {
    let p = p.map(area_vector::f64_point);
    plane_quadric(area_vector::triangle(p[0], p[1], p[2]), p[0])
}

/// The quadric of the plane with area vector `n` through `at`, weighted by its area.
#[inline(always)]
fn plane_quadric(n: glam::DVec3, at: glam::DVec3) -> Option<Quadric> {
    let len2 = n.length_squared();
    if len2 == 0.0 {
        return None;
    }
    let d = -n.dot(at);
    Some(Quadric::plane(n.to_array(), d, 0.5 / len2.sqrt()))
}

/// Area vector (twice the area along the normal, Newell's) and a point of the plane (the
/// centroid) of a polygon.
#[inline(always)]
fn area_vector_of(mesh: &Mesh, face: &[u32]) -> (glam::DVec3, glam::DVec3) {
    let p = |i: usize| area_vector::f64_point(mesh.positions[face[i] as usize]);
    let m = face.len();
    let c = (0..m).map(p).fold(glam::DVec3::ZERO, |c, q| c + q);
    (area_vector::polygon(m, p), c / m as f64)
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (f64::from(a[k]) - f64::from(b[k])).powi(2))
        .sum::<f64>()
        .sqrt()
}
