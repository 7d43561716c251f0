//! The quadric face pass against its definition, bit for bit ([`reference_quadrics`]), and
//! its timing: `cargo test --release -p tessd-simplify --lib quadric_pass_speed -- --ignored
//! --nocapture` (`QUADRIC_SPEED_ONLY=1`: the pass alone, untimed, for `perf stat`).

use super::*;
use crate::grid_tests::torus;
use std::collections::BTreeMap;
use std::time::Instant;

/// Milliseconds since the first call.
fn wall_ms() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
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

/// The batched walk gives the definition's bits, on 1 and 2 threads, across chunks and with
/// its sums held in registers.
#[test]
fn batched_walk_keeps_the_bits() {
    let mesh = torus(200, 150);
    // Clusters of 2 and 9 vertices cross chunks; of 30, the faces' sums are held in registers
    // (`HOLD_SHARE`). 60 k faces are 4 blocks: later blocks sum into partials.
    for leaf in [2usize, 9, 30] {
        let (cluster_of, n) = kd_clusters(&mesh.positions, leaf);
        let expected = reference_quadrics(&mesh, &cluster_of, 0..n as u32);
        let held = n <= mesh.vertex_count() / HOLD_SHARE;
        assert_eq!(held, leaf == 30, "{n} clusters");
        for threads in [1usize, 2] {
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
    let mesh = torus(1000, 500);
    let v = mesh.vertex_count();
    // QUADRIC_SPEED_LEAF=14 times one partition only.
    let leaves: Vec<usize> = match std::env::var("QUADRIC_SPEED_LEAF") {
        Ok(l) => vec![l.parse().unwrap()],
        Err(_) => vec![3, 14, 140],
    };
    let only = std::env::var("QUADRIC_SPEED_ONLY").is_ok();
    for leaf in leaves {
        let (cluster_of, n) = kd_clusters(&mesh.positions, leaf);
        for threads in [1usize, 2].into_iter().take(if only { 1 } else { 2 }) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                // 15 passes: untimed for `perf stat -e task-clock` (which a shared machine
                // does not blur), else wall times, the least (the run that was not
                // interrupted) and the median.
                let mut times = vec![];
                for _ in 0..15 {
                    let t = wall_ms();
                    for_each_quadric_chunk(&mesh, &cluster_of, n, ADAPTIVE_SHARE, |_, q| {
                        assert!(!q.is_empty())
                    });
                    times.push(wall_ms() - t);
                }
                if !only {
                    let least = times.iter().cloned().fold(f64::MAX, f64::min);
                    println!(
                        "clusters {n} ({:.1} % of vertices), {threads} thr: {least:.1} ms \
                         (least), median {:.1}",
                        100.0 * n as f64 / v as f64,
                        median(times),
                    );
                }
            });
        }
    }
}

/// What the face pass must give, to the bit, written as plainly as it reads: each block's
/// faces, in order, sum into a partial per cluster of `range` they touch (a face's quadric once
/// per distinct cluster among its corners, Lindstrom's rule; a zero-area face adds nothing),
/// and every cluster adds its partials in block order.
fn reference_quadrics(mesh: &Mesh, cluster_of: &[u32], range: Range<u32>) -> Vec<Quadric> {
    let mut total = vec![Quadric::default(); range.len()];
    for b in 0..mesh.face_count().div_ceil(blocks::BLOCK) {
        let mut partial: BTreeMap<u32, Quadric> = BTreeMap::new();
        for i in b * blocks::BLOCK..((b + 1) * blocks::BLOCK).min(mesh.face_count()) {
            let face = mesh.face(i);
            let Some(fq) = face_quadric(mesh, face) else {
                continue;
            };
            let mut clusters: Vec<u32> = face
                .iter()
                .map(|&v| cluster_of[v as usize])
                .filter(|c| range.contains(c))
                .collect();
            clusters.sort_unstable();
            clusters.dedup();
            for c in clusters {
                partial.entry(c).or_default().add(&fq);
            }
        }
        for (c, p) in partial {
            total[(c - range.start) as usize].add(&p);
        }
    }
    total
}
