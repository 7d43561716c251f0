//! The modified Butterfly scheme against its analytic properties: interpolation, cubic
//! reproduction on regular grids (8-point interior rule, 4-point boundary and crease rule),
//! Zorin's extraordinary stencils, affine invariance.

use std::collections::HashMap;
use tessd_mesh::Mesh;
use tessd_subdiv::butterfly::extraordinary_weights;
use tessd_subdiv::{Boundary, Refiner, Scheme, SubdivOptions, subdivide};

mod common;
use common::{bumps, creased, edge_uses, edges, grid, icosahedron};

fn options(levels: u32, boundary: Boundary) -> SubdivOptions {
    common::options(Scheme::Butterfly, levels, boundary)
}

fn cubic(x: f64, y: f64) -> f64 {
    0.3 + 0.5 * x - 0.8 * y + 0.7 * x * x - 0.4 * x * y + 0.6 * y * y + 0.9 * x * x * x
        - 1.1 * x * x * y
        + 0.5 * x * y * y
        - 0.7 * y * y * y
}

fn quartic(x: f64, y: f64) -> f64 {
    5.0 * (x.powi(4) + y.powi(4))
}

/// A bipyramid: ring `0..k` on the unit circle (valence 4), apexes `k` (top) and `k + 1`
/// (bottom) of valence `k`.
fn bipyramid(k: u32) -> Mesh {
    let mut m = Mesh::default();
    for i in 0..k {
        let t = 2.0 * std::f32::consts::PI * i as f32 / k as f32;
        m.positions.push([t.cos(), t.sin(), 0.0]);
    }
    m.positions.extend([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]);
    for i in 0..k {
        let j = (i + 1) % k;
        m.push_face(&[i, j, k]);
        m.push_face(&[j, i, k + 1]);
    }
    m
}

#[test]
fn old_vertices_are_interpolated_through_three_levels() {
    let creased_grid = creased(
        grid(6, bumps),
        &[(7, 8, 0.5), (8, 9, 1.5), (9, 10, 10.0), (8, 14, 10.0)],
    );
    for cage in [icosahedron(), bipyramid(7), bipyramid(3), creased_grid] {
        for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
            let out = subdivide(&cage, &options(3, boundary)).unwrap();
            assert_eq!(out.face_count(), 64 * cage.face_count());
            for &p in &cage.positions {
                assert!(out.positions.contains(&p), "cage vertex {p:?} moved");
            }
        }
    }
}

#[test]
fn regular_grid_reproduces_cubics_in_the_interior() {
    let n = 11u32;
    let last = n - 1;
    let interior = |v: u32| (1..last).contains(&(v % n)) && (1..last).contains(&(v / n));
    let check = |z: fn(f64, f64) -> f64| -> (f64, usize) {
        let cage = grid(n, z);
        let out = subdivide(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
        let mut worst = 0.0f64;
        let mut count = 0;
        for (e, &[a, b]) in edges(&cage).iter().enumerate() {
            let p = out.positions[e];
            let (pa, pb) = (cage.positions[a as usize], cage.positions[b as usize]);
            if interior(a) && interior(b) {
                count += 1;
                for k in 0..2 {
                    assert!((p[k] - 0.5 * (pa[k] + pb[k])).abs() < 1e-6);
                }
                let want = z(f64::from(p[0]), f64::from(p[1]));
                worst = worst.max((f64::from(p[2]) - want).abs());
            }
        }
        (worst, count)
    };
    let (err, count) = check(cubic);
    println!("cubic: {count} interior edge points, max error {err:.3e}");
    assert_eq!(count, 2 * 8 * 9 + 8 * 8);
    assert!(err < 1e-5, "cubic not reproduced: {err}");
    // The control: a quartic is not reproduced, so the comparison can see an error.
    let (err, _) = check(quartic);
    println!("quartic: max error {err:.3e}");
    assert!(err > 1e-4, "quartic reproduced too: {err}");
}

#[test]
fn edge_points_near_the_border_stay_on_the_lattice() {
    // The ghost wings reproduce linear data: in xy every interior edge point is a midpoint.
    let cage = grid(7, bumps);
    let out = subdivide(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
    let uses = edge_uses(&cage);
    for (e, &[a, b]) in edges(&cage).iter().enumerate() {
        if uses[&(a, b)] == 2 {
            let (pa, pb, p) = (
                cage.positions[a as usize],
                cage.positions[b as usize],
                out.positions[e],
            );
            for k in 0..2 {
                assert!(
                    (p[k] - 0.5 * (pa[k] + pb[k])).abs() < 1e-6,
                    "edge {a}-{b}: {p:?}"
                );
            }
        }
    }
}

#[test]
fn four_point_rule_reproduces_cubics_along_a_straight_boundary() {
    let n = 11u32;
    let cage = grid(n, cubic);
    for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
        let out = subdivide(&cage, &options(1, boundary)).unwrap();
        let mut count = 0;
        for (e, &[a, b]) in edges(&cage).iter().enumerate() {
            // Edges of the row y = 0 whose 4-point stencil stays on that row.
            if b < n && a >= 1 && b <= n - 2 {
                let p = out.positions[e];
                assert!(p[1].abs() < 1e-7, "left the boundary line: {p:?}");
                let want = cubic(f64::from(p[0]), 0.0);
                assert!(
                    (f64::from(p[2]) - want).abs() < 1e-5,
                    "edge {a}-{b}: {p:?} vs {want}"
                );
                count += 1;
            }
        }
        assert_eq!(count, n as usize - 3);
    }
}

#[test]
fn four_point_rule_follows_a_sharp_crease_and_keeps_the_sides_apart() {
    let n = 9u32;
    let m = 4; // the crease row, y = 0.5
    let along = |x: f64| 0.4 - 0.3 * x + 1.2 * x * x - 0.8 * x * x * x;
    let cage = |lower: f64| {
        let z = move |x: f64, y: f64| {
            if (y - 0.5).abs() < 1e-9 {
                along(x)
            } else if y < 0.5 {
                lower * bumps(x, y)
            } else {
                bumps(x, y) + 0.3
            }
        };
        let s: Vec<(u32, u32, f32)> = (0..n - 1)
            .map(|i| (i + m * n, i + 1 + m * n, 10.0))
            .collect();
        creased(grid(n, z), &s)
    };
    let (c1, c2) = (cage(1.0), cage(-2.0));
    let (o1, o2) = (
        subdivide(&c1, &options(1, Boundary::EdgeOnly)).unwrap(),
        subdivide(&c2, &options(1, Boundary::EdgeOnly)).unwrap(),
    );
    let mut on_crease = 0;
    for (e, &[a, b]) in edges(&c1).iter().enumerate() {
        let (ra, rb) = (a / n, b / n);
        if ra == m && rb == m && a % n >= 1 && b % n <= n - 2 {
            let p = o1.positions[e];
            assert!((p[1] - 0.5).abs() < 1e-6);
            assert!(
                (f64::from(p[2]) - along(f64::from(p[0]))).abs() < 1e-5,
                "{p:?}"
            );
            on_crease += 1;
        }
        // Points of the upper side (and the crease) never read the lower side.
        if ra >= m && rb >= m {
            assert_eq!(o1.positions[e], o2.positions[e], "edge {a}-{b}");
        }
    }
    assert_eq!(on_crease, n as usize - 3);
}

#[test]
fn planar_mesh_stays_planar() {
    let plane = |x: f64, y: f64| 0.3 * x - 0.7 * y + 0.2;
    let cage = creased(grid(6, plane), &[(7, 8, 0.5), (8, 9, 10.0), (8, 14, 1.5)]);
    for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
        let out = subdivide(&cage, &options(3, boundary)).unwrap();
        let worst = out
            .positions
            .iter()
            .map(|p| (f64::from(p[2]) - plane(f64::from(p[0]), f64::from(p[1]))).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "off the plane by {worst}");
    }
}

#[test]
fn extraordinary_stencils_sum_to_one() {
    for k in 3..=12 {
        let s: f64 = extraordinary_weights(k).iter().sum();
        assert!((0.75 + s - 1.0).abs() < 1e-12, "k = {k}: 3/4 + {s}");
        let r = Refiner::new(&bipyramid(k as u32), &options(2, Boundary::EdgeOnly)).unwrap();
        for t in &r.tables {
            for i in 0..t.len() {
                let s: f32 = t.row(i).map(|(_, w)| w).sum();
                assert!((s - 1.0).abs() < 1e-6, "k = {k}, row {i}: {s}");
            }
        }
    }
}

/// Zorin's published weights, written out again here.
fn zorin(k: usize, j: usize) -> f64 {
    match k {
        3 => [5.0 / 12.0, -1.0 / 12.0, -1.0 / 12.0][j],
        4 => [3.0 / 8.0, 0.0, -1.0 / 8.0, 0.0][j],
        _ => {
            let t = 2.0 * std::f64::consts::PI * j as f64 / k as f64;
            (0.25 + t.cos() + 0.5 * (2.0 * t).cos()) / k as f64
        }
    }
}

#[test]
fn bipyramid_apex_edges_use_zorins_stencils() {
    for k in 3..=12u32 {
        let cage = bipyramid(k);
        let (top, bottom) = (k, k + 1);
        let e = edges(&cage).iter().position(|&x| x == [0, top]).unwrap();
        let r = Refiner::new(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
        let got: HashMap<u32, f64> = r.tables[0].row(e).map(|(v, w)| (v, f64::from(w))).collect();
        // Ring vertex 0 (valence 4), going round from the top: top, 1, bottom, k − 1.
        let mut want: HashMap<u32, f64> = HashMap::new();
        let both = k != 6;
        let share = if both { 0.5 } else { 1.0 };
        for (j, v) in [top, 1, bottom, k - 1].into_iter().enumerate() {
            *want.entry(v).or_default() += share * zorin(4, j);
        }
        *want.entry(0).or_default() += share * 0.75;
        if both {
            // The apex (valence k), going round from ring vertex 0.
            *want.entry(top).or_default() += 0.5 * 0.75;
            for j in 0..k as usize {
                *want.entry(j as u32).or_default() += 0.5 * zorin(k as usize, j);
            }
        }
        want.retain(|_, w| *w != 0.0);
        let keys = |m: &HashMap<u32, f64>| {
            let mut k: Vec<u32> = m.keys().copied().collect();
            k.sort_unstable();
            k
        };
        assert_eq!(keys(&got), keys(&want), "k = {k}");
        for (v, w) in &want {
            assert!(
                (got[v] - w).abs() < 1e-6,
                "k = {k}, vertex {v}: {} vs {w}",
                got[v]
            );
        }
    }
}
