//! Comparisons whose answers are known in closed form.

use tessd_compare::{CompareError, CompareOptions, SampleCount, SurfaceIndex, compare, one_sided};
use tessd_mesh::Mesh;

fn mesh(positions: Vec<[f32; 3]>, faces: &[&[u32]]) -> Mesh {
    let mut m = Mesh {
        positions,
        ..Mesh::default()
    };
    for f in faces {
        m.push_face(f);
    }
    m
}

/// The square `[lo, hi]²` at height `z`, as one quad.
fn square(lo: f32, hi: f32, z: f32) -> Mesh {
    mesh(
        vec![[lo, lo, z], [hi, lo, z], [hi, hi, z], [lo, hi, z]],
        &[&[0, 1, 2, 3]],
    )
}

/// The cube `[-s/2, s/2]³` as six quads.
fn cube(s: f32) -> Mesh {
    let h = s / 2.0;
    let p = (0..8)
        .map(|i| {
            [
                if i & 1 != 0 { h } else { -h },
                if i & 2 != 0 { h } else { -h },
                if i & 4 != 0 { h } else { -h },
            ]
        })
        .collect();
    mesh(
        p,
        &[
            &[0, 2, 3, 1],
            &[4, 5, 7, 6],
            &[0, 1, 5, 4],
            &[2, 6, 7, 3],
            &[0, 4, 6, 2],
            &[1, 3, 7, 5],
        ],
    )
}

/// An icosphere of radius 1: the icosahedron with each triangle split into 4, `level` times,
/// new vertices pushed onto the sphere.
fn icosphere(level: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let norm = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    for v in &mut p {
        *v = norm(*v);
    }
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut nf = Vec::with_capacity(f.len() * 4);
        let mut m = |a: u32, b: u32, p: &mut Vec<[f64; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (x, y) = (p[a as usize], p[b as usize]);
                p.push(norm([x[0] + y[0], x[1] + y[1], x[2] + y[2]]));
                (p.len() - 1) as u32
            })
        };
        for [a, b, c] in f {
            let (ab, bc, ca) = (m(a, b, &mut p), m(b, c, &mut p), m(c, a, &mut p));
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    let mut out = Mesh {
        positions: p
            .iter()
            .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32])
            .collect(),
        ..Mesh::default()
    };
    for t in &f {
        out.push_face(t);
    }
    out
}

/// Smallest distance from the origin to the plane of a face of a (convex) mesh.
fn min_plane_distance(m: &Mesh) -> f64 {
    m.faces()
        .map(|f| {
            let p = |i: usize| {
                let v = m.positions[f[i] as usize];
                [v[0] as f64, v[1] as f64, v[2] as f64]
            };
            let (a, b, c) = (p(0), p(1), p(2));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            ((n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / l).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

fn opts(n: u64) -> CompareOptions {
    CompareOptions::default().with_samples(n)
}

#[test]
fn parallel_squares_at_distance_d() {
    let d = 0.375;
    let c = compare(&square(0.0, 1.0, 0.0), &square(0.0, 1.0, d), &opts(20_000)).unwrap();
    for dist in [&c.a_to_b, &c.b_to_a] {
        assert!(close(dist.max, d as f64, 1e-12), "{dist:?}");
        assert!(close(dist.mean, d as f64, 1e-12));
        assert!(close(dist.rms, d as f64, 1e-12));
        assert_eq!(dist.samples, 20_000 + 4);
        assert!(close(dist.area, 1.0, 1e-12));
    }
    assert!(close(c.hausdorff, d as f64, 1e-12));
    assert!(close(c.rms, d as f64, 1e-12));
    assert!(close(c.mean, d as f64, 1e-12));
    assert!(close(
        c.bbox_diagonal,
        (2.0 + d as f64 * d as f64).sqrt(),
        1e-7
    ));
    assert!(close(
        c.hausdorff_relative(),
        c.hausdorff / c.bbox_diagonal,
        1e-15
    ));
}

#[test]
fn cube_against_scaled_cube() {
    // Inner cube of side 1, outer of side s, same centre. Inner → outer: every point of a face
    // is (s - 1)/2 from the parallel outer face and farther from the others. Outer → inner: a
    // point q of the outer surface is at sqrt(Σ max(|q_i| - 1/2, 0)²) from the inner cube,
    // largest at the corners: √3 (s - 1)/2.
    let s = 1.5f32;
    let h = (s as f64 - 1.0) / 2.0;
    let o = opts(400_000).with_vertices(false);
    let c = compare(&cube(1.0), &cube(s), &o).unwrap();
    assert!(close(c.a_to_b.max, h, 1e-12), "{:?}", c.a_to_b);
    assert!(close(c.a_to_b.mean, h, 1e-12));
    assert!(close(c.a_to_b.rms, h, 1e-12));
    // Face samples come within a few 1e-3 of the corner; vertex samples hit it exactly.
    let corner = 3f64.sqrt() * h;
    assert!(c.b_to_a.max <= corner + 1e-12 && c.b_to_a.max > 0.99 * corner);
    let with_vertices = compare(&cube(1.0), &cube(s), &opts(1000)).unwrap();
    assert!(close(with_vertices.hausdorff, corner, 1e-12));
    assert_eq!(with_vertices.b_to_a.argmax_point.map(f64::abs), [0.75; 3]);
    assert_eq!(with_vertices.b_to_a.argmax_closest.map(f64::abs), [0.5; 3]);
    // Outer → inner over one face (all six alike), with t = max(|y| - 1/2, 0) for y uniform
    // on [-s/2, s/2]: E[t²] = 2 h³ / (3 s), so RMS² = h² + 2 E[t²] = h² + 4 h³ / (3 s).
    let s64 = s as f64;
    let rms = (h * h + 4.0 * h.powi(3) / (3.0 * s64)).sqrt();
    assert!(close(c.b_to_a.rms, rms, 1e-3), "{} vs {rms}", c.b_to_a.rms);
    // The mean by midpoint quadrature of the same integrand.
    let n = 1000;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let y = -s64 / 2.0 + s64 * (i as f64 + 0.5) / n as f64;
            let z = -s64 / 2.0 + s64 * (j as f64 + 0.5) / n as f64;
            let (ty, tz) = ((y.abs() - 0.5).max(0.0), (z.abs() - 0.5).max(0.0));
            sum += (h * h + ty * ty + tz * tz).sqrt();
        }
    }
    let mean = sum / (n * n) as f64;
    assert!(
        close(c.b_to_a.mean, mean, 1e-3),
        "{} vs {mean}",
        c.b_to_a.mean
    );
    // Symmetric RMS: pooled over both directions' samples (equal counts here).
    let pooled = ((c.a_to_b.rms.powi(2) + c.b_to_a.rms.powi(2)) / 2.0).sqrt();
    assert!(close(c.rms, pooled, 1e-12));
    assert_eq!(c.hausdorff, c.b_to_a.max);
}

#[test]
fn mesh_against_itself_is_zero() {
    let m = icosphere(3);
    let c = compare(&m, &m, &opts(50_000)).unwrap();
    assert!(c.hausdorff < 1e-12, "{c:?}");
    assert!(c.rms < 1e-12);
    // A quad and its two triangles are the same surface.
    let quad = square(0.0, 1.0, 0.0);
    let tris = mesh(quad.positions.clone(), &[&[0, 1, 2], &[0, 2, 3]]);
    assert!(compare(&quad, &tris, &opts(10_000)).unwrap().hausdorff < 1e-12);
}

#[test]
fn coarse_sphere_against_fine_sphere_is_within_the_chordal_bound() {
    // Both polyhedra are convex, inscribed in the unit sphere and contain the ball of radius
    // r = their smallest face-plane distance. Along any ray from the centre each surface lies
    // in [r, 1], so the distance between them is at most 1 - min(r_coarse, r_fine). The
    // deepest point of the coarse mesh (at r_coarse, the foot of that face's perpendicular) is
    // at least r_fine - r_coarse from the fine surface, which gives a lower bound.
    let coarse = icosphere(1);
    let fine = icosphere(5); // 20 480 triangles: exercises the parallel BVH build
    let (rc, rf) = (min_plane_distance(&coarse), min_plane_distance(&fine));
    let c = compare(&coarse, &fine, &opts(200_000)).unwrap();
    let upper = 1.0 - rc.min(rf) + 1e-6;
    assert!(c.hausdorff <= upper, "{} > {upper}", c.hausdorff);
    assert!(
        c.a_to_b.max >= 0.95 * (rf - rc),
        "{} vs {}",
        c.a_to_b.max,
        rf - rc
    );
    assert!(c.b_to_a.max <= upper && c.b_to_a.max > 0.0);
    assert!(c.rms < c.hausdorff && c.rms > 0.0);
    // A finer coarse mesh is closer.
    let c2 = compare(&icosphere(2), &fine, &opts(200_000)).unwrap();
    assert!(c2.hausdorff < c.hausdorff && c2.rms < c.rms);
}

#[test]
fn triangle_against_translated_triangle() {
    // T = (0,0,0) (1,0,0) (0,1,0); T' = T + (δ, 0, d). A point (x, y, 0) of T is at
    // sqrt(d² + max(δ - x, 0)²) from T' (its in-plane closest point is (max(x, δ), y)).
    let (delta, d) = (0.25f64, 0.5f64);
    let t = mesh(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[&[0, 1, 2]],
    );
    let moved = mesh(
        t.positions
            .iter()
            .map(|p| [p[0] + delta as f32, p[1], p[2] + d as f32])
            .collect(),
        &[&[0, 1, 2]],
    );
    let c = compare(&t, &moved, &opts(400_000).with_vertices(false)).unwrap();
    // x has density 2(1 - x) on T: E[max(δ - x, 0)²] = (2/3)(1 - δ)δ³ + δ⁴/2.
    let e2 = 2.0 / 3.0 * (1.0 - delta) * delta.powi(3) + delta.powi(4) / 2.0;
    let rms = (d * d + e2).sqrt();
    assert!(close(c.a_to_b.rms, rms, 1e-3), "{} vs {rms}", c.a_to_b.rms);
    let n = 200_000;
    let mut mean = (1.0 - delta).powi(2) * d; // P(x ≥ δ) = (1 - δ)²
    for i in 0..n {
        let x = delta * (i as f64 + 0.5) / n as f64;
        mean += (d * d + (delta - x).powi(2)).sqrt() * 2.0 * (1.0 - x) * delta / n as f64;
    }
    assert!(
        close(c.a_to_b.mean, mean, 1e-3),
        "{} vs {mean}",
        c.a_to_b.mean
    );
    // Both maxima sit at corners: (0,0,0) → (δ,0,d) and (1+δ,0,d) → (1,0,0).
    let h = (d * d + delta * delta).sqrt();
    let cv = compare(&t, &moved, &opts(1000)).unwrap();
    assert!(close(cv.a_to_b.max, h, 1e-7) && close(cv.b_to_a.max, h, 1e-7));
    assert!(close(cv.hausdorff, h, 1e-7));
}

#[test]
fn one_sided_is_asymmetric() {
    // A small square inside a big one, same plane: small → big is 0, big → small is the
    // corner-to-corner distance 0.25 √2.
    let small = square(0.25, 0.75, 0.0);
    let big = square(0.0, 1.0, 0.0);
    let o = opts(50_000);
    let s2b = one_sided(&small, &big, &o).unwrap();
    let b2s = one_sided(&big, &small, &o).unwrap();
    assert!(s2b.max < 1e-12 && s2b.rms < 1e-12, "{s2b:?}");
    assert!(close(b2s.max, 0.25 * 2f64.sqrt(), 1e-12), "{b2s:?}");
    assert!(b2s.rms > 0.1);
    let c = compare(&small, &big, &o).unwrap();
    assert_eq!((c.a_to_b, c.b_to_a), (s2b, b2s));
}

#[test]
fn deterministic_across_runs_and_thread_counts() {
    let a = icosphere(3);
    let b = icosphere(1);
    let o = opts(100_000).with_seed(42).with_edges(true);
    let first = compare(&a, &b, &o).unwrap();
    assert_eq!(first, compare(&a, &b, &o).unwrap());
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert_eq!(first, pool.install(|| compare(&a, &b, &o).unwrap()));
    }
    // Another seed moves the samples (but hardly the estimate).
    let other = compare(&a, &b, &o.clone().with_seed(43)).unwrap();
    assert_ne!(first.a_to_b.mean, other.a_to_b.mean);
    assert!(close(first.a_to_b.mean, other.a_to_b.mean, 1e-2));
}

#[test]
fn sample_counts() {
    let sq = square(0.0, 1.0, 0.0);
    let d = |o: &CompareOptions| one_sided(&sq, &sq, o).unwrap().samples;
    let base = CompareOptions::default();
    assert_eq!(base.samples, SampleCount::Auto);
    assert!(base.include_vertices && !base.include_edges);
    // Auto: at least 1 M face samples, plus the 4 vertices.
    assert_eq!(d(&base), 1_000_000 + 4);
    assert_eq!(d(&base.clone().with_samples(10).with_vertices(false)), 10);
    assert_eq!(d(&base.clone().with_samples_per_area(2500.0)), 2504);
    // Edges: √2500 = 50 per unit length over the 4 polygon edges (no fan diagonal).
    let with_edges = base.clone().with_samples_per_area(2500.0).with_edges(true);
    assert_eq!(d(&with_edges), 2504 + 200);
    // Only vertices.
    assert_eq!(d(&base.clone().with_samples(0)), 4);
}

#[test]
fn surface_index_queries() {
    let idx = SurfaceIndex::new(&cube(2.0)).unwrap();
    assert_eq!(idx.triangle_count(), 12);
    assert!(close(idx.area(), 24.0, 1e-12));
    let c = idx.closest_point([3.0, 0.5, -0.25]);
    assert_eq!(c.point, [1.0, 0.5, -0.25]);
    assert_eq!(c.distance, 2.0);
    assert_eq!(
        idx.distances(&[[0.0, 0.0, 0.0], [2.0, 2.0, 1.0], [1.0, 1.0, 1.0]]),
        vec![1.0, 2f64.sqrt(), 0.0]
    );
    let from = cube(1.0);
    let d = idx.distance_from(&from, &opts(1000)).unwrap();
    assert_eq!(d, one_sided(&from, &cube(2.0), &opts(1000)).unwrap());
}

#[test]
fn errors_name_the_mesh() {
    let good = square(0.0, 1.0, 0.0);
    let empty = Mesh {
        positions: vec![[0.0; 3]; 3],
        ..Mesh::default()
    };
    let e = compare(&good, &empty, &opts(10)).unwrap_err();
    assert!(matches!(e, CompareError::EmptyMesh { which: "b" }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "mesh b has no faces; a surface distance needs a surface"
    );
    let e = one_sided(&empty, &good, &opts(10)).unwrap_err();
    assert!(matches!(e, CompareError::EmptyMesh { which: "from" }));

    let flat = mesh(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        &[&[0, 1, 2], &[0, 0, 1]],
    );
    let e = compare(&flat, &good, &opts(10)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "mesh a has 2 faces but all of them have zero area"
    );
    assert!(matches!(
        SurfaceIndex::new(&flat),
        Err(CompareError::DegenerateMesh {
            which: "to",
            faces: 2
        })
    ));

    let mut bad = good.clone();
    bad.positions[1][0] = f32::NAN;
    let e = compare(&good, &bad, &opts(10)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "mesh b is invalid: vertex 1 has a non-finite coordinate x = NaN"
    );
    assert!(std::error::Error::source(&e).is_some());

    let e = one_sided(&good, &good, &opts(0).with_vertices(false)).unwrap_err();
    assert!(matches!(e, CompareError::InvalidOptions(_)));
    let e = one_sided(
        &good,
        &good,
        &CompareOptions::default().with_samples_per_area(f64::NAN),
    )
    .unwrap_err();
    assert!(e.to_string().contains("sample density NaN"), "{e}");
}

#[test]
fn a_cancel_stops_the_comparison_mid_way() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::{Duration, Instant};
    let (a, b) = (icosphere(5), icosphere(3));
    // Set before: nothing is measured.
    let flag = Arc::new(AtomicBool::new(true));
    let o = opts(1000).with_cancel(flag.clone());
    assert!(matches!(compare(&a, &b, &o), Err(CompareError::Cancelled)));
    assert!(matches!(
        one_sided(&a, &b, &o),
        Err(CompareError::Cancelled)
    ));
    // Set while 50 M samples are being measured (seconds of work): the answer comes within
    // a few milliseconds of work.
    flag.store(false, Ordering::Relaxed);
    let o = opts(50_000_000).with_cancel(flag.clone());
    let setter = {
        let flag = flag.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            flag.store(true, Ordering::Relaxed);
            Instant::now()
        })
    };
    let r = one_sided(&a, &b, &o);
    let answered = Instant::now();
    let set = setter.join().unwrap();
    assert!(matches!(r, Err(CompareError::Cancelled)), "{r:?}");
    let late = answered.saturating_duration_since(set);
    println!("cancelled: answered {late:?} after the flag was set");
    assert!(late < Duration::from_millis(300), "{late:?}");
}
