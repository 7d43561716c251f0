//! Timing of the quadric face pass against the previous version (kept below as `old`), in one
//! process, interleaved: `cargo test --release -p tessd-simplify --lib quadric_pass_speed --
//! --ignored --nocapture`. Also checks that both give the same bits.

use super::*;
use std::time::Instant;

/// Milliseconds since the first call.
fn wall_ms() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

/// A closed bumpy torus of about `triangles` triangles, rows of vertices in order (the
/// benchmark's generated input, `bench/simplify/src/generate.rs`).
fn bumpy_torus(triangles: u64) -> Mesh {
    let nv = ((triangles as f64 / 5.0).sqrt().round() as u32).max(3);
    let nu = ((triangles as f64 / (2.0 * f64::from(nv))).round() as u32).max(3);
    let tau = std::f64::consts::TAU;
    let edge = tau * 0.4 / f64::from(nv);
    let mut m = Mesh::default();
    for i in 0..nu {
        let u = tau * f64::from(i) / f64::from(nu);
        for j in 0..nv {
            let v = tau * f64::from(j) / f64::from(nv);
            let bumps =
                0.10 * (6.0 * u).sin() * (4.0 * v).cos() + 0.04 * (17.0 * u + 9.0 * v).sin();
            let h = (u64::from(i) << 32 | u64::from(j)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let noise = 0.1 * edge * ((h >> 11) as f64 / (1u64 << 52) as f64 - 1.0);
            let r = 0.4 * (1.0 + bumps) + noise;
            let ring = 1.0 + r * v.cos();
            m.positions.push([
                (ring * u.cos()) as f32,
                (ring * u.sin()) as f32,
                (r * v.sin()) as f32,
            ]);
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let (i1, j1) = ((i + 1) % nu, (j + 1) % nv);
            let (a, b, c, d) = (i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1);
            m.push_face(&[a, b, c]);
            m.push_face(&[a, c, d]);
        }
    }
    m
}

/// Clusters of at most `leaf` vertices by median cuts across the largest side, numbered in
/// leaf order (the adaptive goals' kd order).
fn kd_clusters(positions: &[[f32; 3]], leaf: usize) -> (Vec<u32>, usize) {
    fn split(p: &[[f32; 3]], ids: &mut [u32], leaf: usize, out: &mut [u32], next: &mut u32) {
        if ids.len() <= leaf {
            for &i in ids.iter() {
                out[i as usize] = *next;
            }
            *next += 1;
            return;
        }
        let axis = (0..3)
            .max_by(|&a, &b| {
                let ext = |k: usize| {
                    let (lo, hi) = ids.iter().fold((f32::MAX, f32::MIN), |(l, h), &i| {
                        (l.min(p[i as usize][k]), h.max(p[i as usize][k]))
                    });
                    hi - lo
                };
                ext(a).total_cmp(&ext(b))
            })
            .unwrap();
        // 40 % / 60 %: leaf counts between the powers of two a median gives.
        let mid = ids.len() * 2 / 5;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            p[a as usize][axis].total_cmp(&p[b as usize][axis])
        });
        let (l, r) = ids.split_at_mut(mid);
        split(p, l, leaf, out, next);
        split(p, r, leaf, out, next);
    }
    let mut ids: Vec<u32> = (0..positions.len() as u32).collect();
    let mut out = vec![0; positions.len()];
    let mut next = 0;
    split(positions, &mut ids, leaf, &mut out, &mut next);
    (out, next as usize)
}

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// The batched walk gives the previous version's bits, on 1 and 2 threads, across chunks and
/// with its sums held in registers.
#[test]
fn batched_walk_keeps_the_bits() {
    let mesh = bumpy_torus(60_000);
    // Clusters of 2 and 9 vertices cross chunks; of 30, the faces' sums are held in registers
    // (`HOLD_SHARE`). 60 k faces are 4 blocks: later blocks sum into partials.
    for leaf in [2usize, 9, 30] {
        let (cluster_of, n) = kd_clusters(&mesh.positions, leaf);
        let expected = old::cluster_quadrics(&mesh, &cluster_of, 0..n as u32);
        let held = n <= mesh.vertex_count() / HOLD_SHARE;
        assert_eq!(held, leaf == 30, "{n} clusters");
        let only = std::env::var("QUADRIC_SPEED_ONLY").is_ok();
        for threads in [1usize, 2].into_iter().take(if only { 1 } else { 2 }) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut got = vec![];
            pool.install(|| {
                for_each_quadric_chunk(&mesh, &cluster_of, n, ADAPTIVE_SHARE, |first, q| {
                    assert_eq!(first, got.len());
                    got.extend_from_slice(q)
                })
            });
            assert!(got == expected, "leaf {leaf}, {threads} threads");
        }
    }
}

#[test]
#[ignore = "timing; run with --ignored --nocapture"]
fn quadric_pass_speed() {
    let mesh = bumpy_torus(1_000_000);
    let v = mesh.vertex_count();
    // QUADRIC_SPEED_LEAF=14 times one partition only.
    let leaves: Vec<usize> = match std::env::var("QUADRIC_SPEED_LEAF") {
        Ok(l) => vec![l.parse().unwrap()],
        Err(_) => vec![3, 14, 140],
    };
    for leaf in leaves {
        let (cluster_of, n) = kd_clusters(&mesh.positions, leaf);
        let only = std::env::var("QUADRIC_SPEED_ONLY").is_ok();
        for threads in [1usize, 2].into_iter().take(if only { 1 } else { 2 }) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                // Wall times, interleaved; the least of 15 (this machine is shared: the least
                // is the run that was not interrupted), and the median.
                let (mut t_old, mut t_new) = (vec![], vec![]);
                // QUADRIC_SPEED_ONLY=old|new|none runs one variant (or none: the setup
                // alone), for `perf stat -e cycles:u`, which a shared machine does not blur.
                if let Ok(only) = std::env::var("QUADRIC_SPEED_ONLY") {
                    for _ in 0..15 {
                        match only.as_str() {
                            "old" => {
                                let chunk = (v / ADAPTIVE_SHARE).max(MIN_CHUNK);
                                for first in (0..n).step_by(chunk) {
                                    let r = first as u32..(first + chunk).min(n) as u32;
                                    drop(old::cluster_quadrics(&mesh, &cluster_of, r));
                                }
                            }
                            "new" => for_each_quadric_chunk(
                                &mesh,
                                &cluster_of,
                                n,
                                ADAPTIVE_SHARE,
                                |_, q| assert!(!q.is_empty()),
                            ),
                            _ => {}
                        }
                    }
                    return;
                }
                for _ in 0..15 {
                    let t = wall_ms();
                    let mut a = vec![];
                    for_each_quadric_chunk(&mesh, &cluster_of, n, ADAPTIVE_SHARE, |_, q| {
                        a.extend_from_slice(q)
                    });
                    t_new.push(wall_ms() - t);
                    let t = wall_ms();
                    let mut b = vec![];
                    let chunk = (v / ADAPTIVE_SHARE).max(MIN_CHUNK);
                    for first in (0..n).step_by(chunk) {
                        let r = first as u32..(first + chunk).min(n) as u32;
                        b.extend(old::cluster_quadrics(&mesh, &cluster_of, r));
                    }
                    t_old.push(wall_ms() - t);
                    assert!(a == b, "different quadrics");
                }
                let least = |t: &[f64]| t.iter().cloned().fold(f64::MAX, f64::min);
                let (o, nw) = (least(&t_old), least(&t_new));
                println!(
                    "clusters {n} ({:.1} % of vertices), {threads} thr: old {o:.1} ms, new {nw:.1} ms \
                     (least), new/old {:.3}; medians {:.1} / {:.1}",
                    100.0 * n as f64 / v as f64,
                    nw / o,
                    median(t_old.clone()),
                    median(t_new.clone()),
                );
            });
        }
    }
}

/// The face pass as of 19de70e5.
mod old {
    use super::*;

    /// `Quadric::add` as of 19de70e5 (one f64 at a time; LLVM pairs them from the second).
    fn add_old(q: &mut Quadric, other: &Quadric) {
        for k in 0..6 {
            q.a[k] += other.a[k];
        }
        for k in 0..3 {
            q.b[k] += other.b[k];
        }
        q.c += other.c;
    }

    /// The quadrics of the clusters of `range` ([`for_each_quadric_chunk`]).
    pub(super) fn cluster_quadrics(
        mesh: &Mesh,
        cluster_of: &[u32],
        range: Range<u32>,
    ) -> Vec<Quadric> {
        let (first, n) = (range.start, range.len());
        let mut q = vec![Quadric::default(); n];
        let blocks = mesh.face_count().div_ceil(blocks::BLOCK);
        if blocks::single_thread() {
            // One core: the same sums with a table only for the clusters that earlier blocks
            // touched. The first block that touches a cluster sums straight into its total (0 +
            // its faces in order: the same bits as its partial, which the parallel merge adds to
            // 0); a later block sums into a partial of its own, added at the block's end (so in
            // block order).
            let mut block_of = vec![u32::MAX; n];
            let (mut table, mut keys, mut part) = (CellTable::with_capacity(256), vec![], vec![]);
            for b in 0..blocks {
                let r = b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(mesh.face_count());
                each_face_quadric(mesh, cluster_of, &range, r, |c, fq| {
                    let at = &mut block_of[(c - first) as usize];
                    if *at == u32::MAX {
                        *at = b as u32;
                    }
                    if *at == b as u32 {
                        add_old(&mut q[(c - first) as usize], fq);
                    } else {
                        let id = table.id(u64::from(c)) as usize;
                        if id == keys.len() {
                            keys.push(c);
                            part.push(Quadric::default());
                        }
                        add_old(&mut part[id], fq);
                    }
                });
                for (&c, p) in keys.iter().zip(&part) {
                    add_old(&mut q[(c - first) as usize], p);
                }
                if !keys.is_empty() {
                    (table, keys, part) = (CellTable::with_capacity(256), vec![], vec![]);
                }
            }
            return q;
        }
        let merge = |q: &mut Vec<Quadric>, partials: Vec<(Vec<u32>, Vec<Quadric>)>| {
            for (keys, partial) in &partials {
                for (&c, p) in keys.iter().zip(partial) {
                    add_old(&mut q[(c - first) as usize], p);
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
                    .map(|b| block_quadrics(mesh, cluster_of, &range, b))
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

    /// Block `b`'s partial quadrics: the clusters it touches in the order it meets them, and
    /// each one's sum over the block's faces in face order.
    fn block_quadrics(
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
        each_face_quadric(mesh, cluster_of, range, r, |c, fq| {
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
            add_old(&mut q[slot as usize], fq);
        });
        (keys, q)
    }

    /// Calls `f(cluster, the face's quadric)` for every face of `faces`, in order, once for each
    /// distinct cluster of `range` among its corners (Lindstrom's rule: a face's quadric goes to
    /// the cells of its vertices, once per cell); faces without a corner in `range`, or of zero
    /// area, are passed over.
    #[inline(always)]
    fn each_face_quadric(
        mesh: &Mesh,
        cluster_of: &[u32],
        range: &Range<u32>,
        faces: Range<usize>,
        mut f: impl FnMut(u32, &Quadric),
    ) {
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
                    f(c, &fq);
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
        let (n, at) = area_vector_of(mesh, face);
        let len2 = n.length_squared();
        if len2 == 0.0 {
            return None;
        }
        let d = -n.dot(at);
        Some(Quadric::plane(n.to_array(), d, 0.5 / len2.sqrt()))
    }

    /// Area vector (twice the area along the normal) and a point of the plane of a face (the
    /// first corner of a triangle, the centroid of a polygon).
    #[inline(always)]
    fn area_vector_of(mesh: &Mesh, face: &[u32]) -> (glam::DVec3, glam::DVec3) {
        let p = |i: usize| area_vector::f64_point(mesh.positions[face[i] as usize]);
        match face.len() {
            3 => (area_vector::triangle(p(0), p(1), p(2)), p(0)),
            m => {
                let c = (0..m).map(p).fold(glam::DVec3::ZERO, |c, q| c + q);
                (area_vector::polygon(m, p), c / m as f64)
            }
        }
    }
}
