//! Loop subdivision against OpenSubdiv's own regression outputs (`shared/data/subdiv`, Hbr
//! baselines: one step of ours on level k must give level k + 1 within 1e-6 of the bounding
//! box, order-independently) and against the scheme's analytic properties.

use tessd_mesh::{Crease, Mesh};
use tessd_subdiv::{
    Boundary, Refiner, Scheme, StencilTable, SubdivError, SubdivOptions, subdivide,
};

mod common;
use common::{
    both_sided, bumps_f32, creased, dist32, edge_uses, grid_f32, icosahedron, octahedron,
    one_sided, read, size,
};

fn options(levels: u32, boundary: Boundary) -> SubdivOptions {
    common::options(Scheme::Loop, levels, boundary)
}

#[test]
fn loop_icosahedron_matches_opensubdiv() {
    for k in 0..2 {
        let cage = read(&format!("loop_icosahedron_level{k}.obj"));
        let want = read(&format!("loop_icosahedron_level{}.obj", k + 1));
        let got = subdivide(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
        assert_eq!(
            got.positions.len(),
            want.positions.len(),
            "level {k}: vertices"
        );
        assert_eq!(got.face_count(), want.face_count(), "level {k}: faces");
        assert!(got.faces().all(|f| f.len() == 3));
        let (d, s) = (both_sided(&got.positions, &want.positions), size(&want));
        println!(
            "loop_icosahedron level {k} -> {}: max distance {d:.3e} of size {s}",
            k + 1
        );
        assert!(d <= 1e-6 * s, "level {k}: off by {d}");
    }
}

/// Our level-1 table with every smooth vertex row reweighted by Warren's simplified
/// `β = 3/(8n)` (centre 5/8), the classic wrong β.
fn warren(table: &StencilTable, cage_vertices: usize) -> StencilTable {
    let mut t = table.clone();
    let first = t.len() - cage_vertices;
    for v in 0..cage_vertices {
        let r = first + v;
        let (s, e) = (t.offsets[r] as usize, t.offsets[r + 1] as usize);
        let n = (e - s - 1) as f32;
        for k in s..e {
            t.weights[k] = if t.sources[k] as usize == v {
                0.625
            } else {
                3.0 / (8.0 * n)
            };
        }
    }
    t
}

#[test]
fn wrong_beta_and_catmull_clark_fail_the_same_comparison() {
    // Negative controls: the comparison above must see a wrong β or a wrong scheme.
    let cage = read("loop_icosahedron_level0.obj");
    let want = read("loop_icosahedron_level1.obj");
    let tol = 1e-6 * size(&want);
    let refiner = Refiner::new(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
    let table = warren(&refiner.tables[0], cage.positions.len());
    let flat = StencilTable::apply_chain(&[table], cage.positions.as_flattened(), 3);
    let wrong: Vec<[f32; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let d = both_sided(&wrong, &want.positions);
    println!("Warren's beta: max distance {d:.3e} (tolerance {tol:.3e})");
    assert!(d > 100.0 * tol, "Warren's β passes: {d}");

    let cc = subdivide(&cage, &SubdivOptions::default()).unwrap();
    let d = one_sided(&want.positions, &cc.positions);
    println!("Catmull-Clark: max distance {d:.3e}");
    assert_ne!(cc.positions.len(), want.positions.len());
    assert!(d > 100.0 * tol, "Catmull–Clark passes: {d}");
}

fn radius(p: [f32; 3]) -> f64 {
    dist32(p, [0.0; 3])
}

#[test]
fn regular_solids_refine_symmetrically() {
    for (name, cage, valence) in [
        ("octahedron", octahedron(), 4),
        ("icosahedron", icosahedron(), 5),
    ] {
        assert!(cage.faces().all(|f| f.len() == 3));
        let ne = edge_uses(&cage).len();
        assert_eq!(ne, cage.positions.len() * valence / 2, "{name}");
        let out = subdivide(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
        let (edges, verts) = out.positions.split_at(ne);
        for (what, group) in [("edge points", edges), ("vertex points", verts)] {
            let r: Vec<f64> = group.iter().map(|&p| radius(p)).collect();
            let (lo, hi) = r
                .iter()
                .fold((f64::MAX, 0.0f64), |(l, h), &x| (l.min(x), h.max(x)));
            assert!(hi - lo < 1e-6, "{name} {what}: radii {lo}..{hi}");
        }
        // The vertex point is (1 − nβ) v (the neighbours' sum is parallel to v with norm
        // n cos θ); the edge point is 3/4 of the midpoint plus 1/4 of the far corners' mean.
        let n = valence as f64;
        let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n).cos();
        let beta = (0.625 - c * c) / n;
        let v0 = cage.positions[0];
        let nb: Vec<[f32; 3]> = cage
            .positions
            .iter()
            .copied()
            .filter(|&q| {
                (dist32(q, v0) - dist32(cage.positions[0], nearest_other(&cage, 0))).abs() < 1e-4
            })
            .collect();
        assert_eq!(nb.len(), valence);
        let mut want = [0.0f64; 3];
        for k in 0..3 {
            want[k] = (1.0 - n * beta) * f64::from(v0[k])
                + beta * nb.iter().map(|q| f64::from(q[k])).sum::<f64>();
        }
        let want = (want[0].powi(2) + want[1].powi(2) + want[2].powi(2)).sqrt();
        assert!(
            (radius(verts[0]) - want).abs() < 1e-6,
            "{name}: vertex radius"
        );
    }
}

fn nearest_other(m: &Mesh, v: usize) -> [f32; 3] {
    let p = m.positions[v];
    *m.positions
        .iter()
        .filter(|&&q| q != p)
        .min_by(|&&a, &&b| dist32(a, p).total_cmp(&dist32(b, p)))
        .unwrap()
}

#[test]
fn every_row_sums_to_one() {
    let g = creased(
        grid_f32(6, bumps_f32),
        &[(7, 8, 0.4), (8, 9, 1.5), (14, 15, 10.0), (8, 15, 2.0)],
    );
    for cage in [g, icosahedron(), octahedron()] {
        for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
            let r = Refiner::new(&cage, &options(3, boundary)).unwrap();
            for t in &r.tables {
                for i in 0..t.len() {
                    let s: f32 = t.row(i).map(|(_, w)| w).sum();
                    assert!((s - 1.0).abs() < 1e-6, "row {i}: {s}");
                }
            }
        }
    }
}

#[test]
fn planar_mesh_stays_planar() {
    // The plane z = 0.3 x − 0.7 y + 0.2, with creases of every kind.
    let plane = |x: f32, y: f32| 0.3 * x - 0.7 * y + 0.2;
    let cage = creased(
        grid_f32(5, plane),
        &[(6, 7, 0.5), (7, 8, 10.0), (12, 7, 1.3)],
    );
    for boundary in [Boundary::EdgeOnly, Boundary::EdgeAndCorner] {
        let out = subdivide(&cage, &options(3, boundary)).unwrap();
        let worst = out
            .positions
            .iter()
            .map(|p| (p[2] - plane(p[0], p[1])).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-6, "off the plane by {worst}");
    }
}

/// The boundary vertices of `m`, each once.
fn boundary_points(m: &Mesh) -> Vec<[f32; 3]> {
    let mut vs: Vec<u32> = edge_uses(m)
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .flat_map(|((a, b), _)| [a, b])
        .collect();
    vs.sort_unstable();
    vs.dedup();
    vs.into_iter().map(|v| m.positions[v as usize]).collect()
}

#[test]
fn boundary_is_the_cubic_bspline_of_the_boundary_polygon() {
    let n = 6u32;
    let cage = grid_f32(n, bumps_f32);
    // The boundary polygon, going round.
    let mut ring: Vec<u32> = (0..n).collect();
    ring.extend((1..n).map(|j| n - 1 + n * j));
    ring.extend((0..n - 1).rev().map(|i| i + n * (n - 1)));
    ring.extend((1..n - 1).rev().map(|j| n * j));
    let p = |k: usize| cage.positions[ring[k % ring.len()] as usize];
    let mut want = Vec::new();
    for k in 0..ring.len() {
        let (a, v, b) = (p(k + ring.len() - 1), p(k), p(k + 1));
        want.push(std::array::from_fn(|i| (a[i] + 6.0 * v[i] + b[i]) / 8.0));
        want.push(std::array::from_fn(|i| (v[i] + b[i]) / 2.0));
    }
    let out = subdivide(&cage, &options(1, Boundary::EdgeOnly)).unwrap();
    let got = boundary_points(&out);
    assert_eq!(got.len(), want.len());
    let d = both_sided(&got, &want);
    assert!(d < 1e-6, "boundary off the B-spline by {d}");
}

/// The grid with row `j = 3` (y = 0.5) flat at z = 0 and creased with sharpness `s`.
fn creased_grid(s: f32) -> Mesh {
    let n = 7u32;
    let mut m = grid_f32(n, |x, y| {
        if (y - 0.5).abs() < 1e-6 {
            0.0
        } else {
            bumps_f32(x, y) + 0.3
        }
    });
    m.creases = (0..n - 1)
        .map(|i| Crease {
            a: i + 3 * n,
            b: i + 1 + 3 * n,
            value: s,
        })
        .collect();
    m
}

#[test]
fn sharp_crease_stays_on_its_straight_line() {
    let out = subdivide(&creased_grid(10.0), &options(3, Boundary::EdgeOnly)).unwrap();
    assert_eq!(out.creases.len(), 6 * 8);
    for c in &out.creases {
        assert_eq!(c.value, 10.0);
        for v in [c.a, c.b] {
            let p = out.positions[v as usize];
            assert!(
                (p[1] - 0.5).abs() < 1e-6 && p[2].abs() < 1e-6,
                "{p:?} left the crease"
            );
        }
    }
    // Without the crease the same vertices leave the line (the control).
    let mut smooth = creased_grid(10.0);
    smooth.creases.clear();
    let free = subdivide(&smooth, &options(3, Boundary::EdgeOnly)).unwrap();
    let off = out
        .creases
        .iter()
        .map(|c| free.positions[c.a as usize][2].abs())
        .fold(0.0f32, f32::max);
    assert!(
        off > 1e-2,
        "the smooth surface stays on the line too: {off}"
    );
}

#[test]
fn semi_sharp_creases_blend_between_smooth_and_sharp() {
    let level = |s: f32, levels: u32| {
        subdivide(&creased_grid(s), &options(levels, Boundary::EdgeOnly))
            .unwrap()
            .positions
    };
    let (smooth, half, one, sharp) = (level(0.0, 1), level(0.5, 1), level(1.0, 1), level(10.0, 1));
    let mut moved = 0.0f64;
    for i in 0..smooth.len() {
        // s = 1 is fully sharp for one level; s = 0.5 is halfway to it from smooth.
        assert!(dist32(one[i], sharp[i]) < 1e-6, "vertex {i}");
        let mid: [f32; 3] = std::array::from_fn(|k| 0.5 * (smooth[i][k] + one[i][k]));
        assert!(
            dist32(half[i], mid) < 1e-6,
            "vertex {i}: {:?} vs {mid:?}",
            half[i]
        );
        moved = moved.max(dist32(smooth[i], one[i]));
    }
    assert!(moved > 1e-2, "the crease changes nothing: {moved}");
    // One more level: s = 1 has run out, infinity has not.
    let (one2, sharp2) = (level(1.0, 2), level(10.0, 2));
    assert!(one2.iter().zip(&sharp2).any(|(&a, &b)| dist32(a, b) > 1e-3));
}

#[test]
fn refining_twice_equals_two_levels_with_fractional_creases() {
    let cage = creased_grid(1.7);
    let once = subdivide(&cage, &options(1, Boundary::EdgeAndCorner)).unwrap();
    assert!(once.creases.iter().all(|c| (c.value - 0.7).abs() < 1e-6));
    let twice = subdivide(&once, &options(1, Boundary::EdgeAndCorner)).unwrap();
    let two = subdivide(&cage, &options(2, Boundary::EdgeAndCorner)).unwrap();
    assert_eq!(twice.face_indices, two.face_indices);
    let d = twice
        .positions
        .iter()
        .zip(&two.positions)
        .map(|(&a, &b)| dist32(a, b))
        .fold(0.0, f64::max);
    assert!(d < 1e-6, "{d}");
}

#[test]
fn edge_and_corner_keeps_corners_fixed() {
    let n = 5u32;
    let cage = grid_f32(n, bumps_f32);
    // (n − 1, 0) and (0, n − 1) have one face; (0, 0) and (n − 1, n − 1) two.
    let single = [n - 1, n * (n - 1)].map(|v| cage.positions[v as usize]);
    let double = [0, n * n - 1].map(|v| cage.positions[v as usize]);
    let found = |out: &Mesh, p: [f32; 3]| out.positions.iter().any(|&q| dist32(p, q) < 1e-7);
    let corners = subdivide(&cage, &options(3, Boundary::EdgeAndCorner)).unwrap();
    let edges = subdivide(&cage, &options(3, Boundary::EdgeOnly)).unwrap();
    for p in single {
        assert!(found(&corners, p), "corner {p:?} moved");
        assert!(!found(&edges, p), "edge-only kept {p:?}");
    }
    for p in double {
        assert!(!found(&corners, p), "two-face boundary vertex {p:?} kept");
    }
}

#[test]
fn non_triangle_cages_are_refused() {
    let mut cage = grid_f32(3, bumps_f32);
    cage.push_face(&[0, 1, 4, 3]);
    for scheme in [Scheme::Loop, Scheme::Butterfly] {
        let o = SubdivOptions {
            scheme,
            ..SubdivOptions::default()
        };
        assert!(matches!(
            subdivide(&cage, &o),
            Err(SubdivError::NotTriangles {
                face: 8,
                corners: 4,
                ..
            })
        ));
    }
}
