//! Tests of `polygon_twist.rs`: analytic cases and dense sampling of both triangulations.

use super::*;

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// The positions rounded to f32, as a mesh holds them.
fn rounded(c: &[DVec3]) -> Vec<DVec3> {
    c.iter().map(|p| p.as_vec3().as_dvec3()).collect()
}

/// Points of triangle `t` on a barycentric grid of `n` steps per side.
fn samples(t: [DVec3; 3], n: usize, out: &mut Vec<DVec3>) {
    for i in 0..=n {
        for j in 0..=n - i {
            let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
            out.push(t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * w);
        }
    }
}

fn distance_to(p: DVec3, surface: &[[DVec3; 3]]) -> f64 {
    surface
        .iter()
        .map(|&t| p.distance(closest_on_triangle(p, t)))
        .fold(f64::INFINITY, f64::min)
}

/// The Hausdorff distance between two triangulations from `n`-step samples of each (a lower
/// bound of the true one, within `spacing` of it).
fn sampled_hausdorff(a: &[[DVec3; 3]], b: &[[DVec3; 3]], n: usize) -> f64 {
    let mut worst = 0f64;
    for (from, to) in [(a, b), (b, a)] {
        let mut pts = Vec::new();
        for &t in from {
            samples(t, n, &mut pts);
        }
        for p in pts {
            worst = worst.max(distance_to(p, to));
        }
    }
    worst
}

fn fan(c: &[DVec3]) -> Vec<[DVec3; 3]> {
    (1..c.len() - 1).map(|k| [c[0], c[k], c[k + 1]]).collect()
}

/// A small deterministic generator (xorshift) of values in [-1, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

#[test]
fn triangles_have_no_twist() {
    assert_eq!(
        polygon_twist(&[v(0.0, 0.0, 0.0), v(1.0, 0.0, 3.0), v(0.0, 1.0, 7.0)]),
        0.0
    );
}

#[test]
fn planar_quads_have_no_twist() {
    let square = [
        v(0.0, 0.0, 2.0),
        v(1.0, 0.0, 2.0),
        v(1.0, 1.0, 2.0),
        v(0.0, 1.0, 2.0),
    ];
    assert_eq!(polygon_twist(&square), 0.0);
    // A tilted plane, far from the origin, rounded to f32 as a mesh stores it: the rounding
    // is not a twist.
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for _ in 0..200 {
        let (e1, e2) = (
            v(rng.next(), rng.next(), rng.next()),
            v(rng.next(), rng.next(), rng.next()),
        );
        let o = v(100.0, -250.0, 40.0);
        let q: Vec<DVec3> = [(0.0, 0.0), (1.0, 0.1), (0.9, 1.2), (-0.1, 0.8)]
            .iter()
            .map(|&(s, t)| o + e1 * s + e2 * t)
            .collect();
        assert_eq!(polygon_twist(&rounded(&q)), 0.0, "{q:?}");
    }
}

#[test]
fn a_symmetric_skew_quad_matches_its_closed_form() {
    // Corners alternately h above and below the unit square: by symmetry the peak is at the
    // diagonals' midpoints, 2h above the other split, whose triangles slope by 2h per unit:
    // the distance to their plane is 2h / √(1 + 8h²).
    for h in [1e-4, 0.01, 0.1, 0.5] {
        let q = [
            v(0.0, 0.0, h),
            v(1.0, 0.0, -h),
            v(1.0, 1.0, h),
            v(0.0, 1.0, -h),
        ];
        let exact = 2.0 * h / (1.0 + 8.0 * h * h).sqrt();
        let got = polygon_twist(&q);
        assert!(got >= exact * (1.0 - 1e-12), "h {h}: {got} < {exact}");
        assert!(got <= exact * (1.0 + 2e-6), "h {h}: {got} vs {exact}");
    }
}

#[test]
fn quad_twist_is_the_sampled_distance_between_the_two_splits() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let n = 120;
    let mut off_midpoint = 0;
    for case in 0..40 {
        // Convex-ish quads with random heights, and a few arbitrary ones.
        let q: Vec<DVec3> = if case < 30 {
            let lift = 0.4 * rng.next();
            [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                .iter()
                .map(|&(x, y)| {
                    v(
                        x + 0.3 * rng.next(),
                        y + 0.3 * rng.next(),
                        lift * rng.next(),
                    )
                })
                .collect()
        } else {
            (0..4)
                .map(|_| v(rng.next(), rng.next(), rng.next()))
                .collect()
        };
        let a = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
        let b = [[q[0], q[1], q[3]], [q[1], q[2], q[3]]];
        let sampled = sampled_hausdorff(&a, &b, n);
        let twist = polygon_twist(&q);
        // Sampling finds a lower bound, within a sample spacing (times the longest side) of
        // the true distance; the twist is an upper bound tight to 1e-6.
        let side = (0..4)
            .map(|i| q[i].distance(q[(i + 1) % 4]))
            .chain([q[0].distance(q[2]), q[1].distance(q[3])])
            .fold(0.0, f64::max);
        assert!(
            sampled <= twist * (1.0 + 1e-9) + 1e-12,
            "case {case}: sampled {sampled} above the twist {twist}"
        );
        assert!(
            twist - sampled <= side / n as f64,
            "case {case}: twist {twist} far above sampled {sampled}"
        );
        // The distance from one diagonal's midpoint to the other split is not the answer in
        // general (only for symmetric quads).
        let mid = 0.5 * (q[0] + q[2]);
        let mid2 = 0.5 * (q[1] + q[3]);
        let at_midpoints = distance_to(mid, &b).max(distance_to(mid2, &a));
        if twist > at_midpoints * (1.0 + 1e-3) {
            off_midpoint += 1;
        }
    }
    assert!(
        off_midpoint > 10,
        "{off_midpoint} of 40 peaked off the midpoints"
    );
}

#[test]
fn a_planar_arrowhead_quad_is_twisted() {
    // Planar but concave at v3: the split along v1v3 is the quad; the fan along v0v2 also
    // covers the triangle v0v2v3 outside it, whose point (2, 0) is 1/√4.25 from the quad (from
    // its edges v0v3 and v3v2).
    let q = [
        v(0.0, 0.0, 0.0),
        v(2.0, -1.0, 0.0),
        v(4.0, 0.0, 0.0),
        v(2.0, -0.5, 0.0),
    ];
    let a = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
    let b = [[q[0], q[1], q[3]], [q[1], q[2], q[3]]];
    let sampled = sampled_hausdorff(&a, &b, 200);
    let twist = polygon_twist(&q);
    assert!((sampled - 4.25f64.sqrt().recip()).abs() < 1e-9, "{sampled}");
    assert!(sampled <= twist * (1.0 + 1e-9) && twist - sampled <= 4.0 / 200.0);
}

#[test]
fn planar_polygons_have_no_twist() {
    // A convex hexagon, and a concave one that is star-shaped from its first corner.
    let hexagon: Vec<DVec3> = (0..6)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 6.0;
            v(3.0 + a.cos(), 1.0 + a.sin(), 0.5 * a.cos() + 0.25 * a.sin())
        })
        .collect();
    assert_eq!(polygon_twist(&rounded(&hexagon)), 0.0);
    let star = [
        v(0.0, 0.0, 1.0),
        v(4.0, 0.0, 1.0),
        v(2.5, 1.0, 1.0),
        v(4.0, 2.0, 1.0),
        v(0.0, 2.0, 1.0),
    ];
    assert_eq!(polygon_twist(&star), 0.0);
}

#[test]
fn the_polygon_bound_holds_for_every_triangulation() {
    // Pentagons and hexagons with random heights: the bound must be at least the sampled
    // distance between the fan and the fan from every other corner (triangulations that
    // do not overlap seen from above, as the polygons are convex there).
    let mut rng = Rng(0x1234_5678_9abc_def1);
    for case in 0..20 {
        let n = 5 + case % 2;
        let c: Vec<DVec3> = (0..n)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / n as f64;
                v(a.cos(), a.sin(), 0.2 * rng.next())
            })
            .collect();
        let bound = polygon_twist(&c);
        assert!(bound > 0.0 && bound < 0.5, "case {case}: {bound}");
        for k in 1..n {
            let mut rotated = c.clone();
            rotated.rotate_left(k);
            let d = sampled_hausdorff(&fan(&c), &fan(&rotated), 60);
            assert!(d <= bound, "case {case}, fan from {k}: {d} > {bound}");
        }
    }
}

#[test]
fn a_folded_fan_gets_the_corner_bound() {
    // Not star-shaped from v0: the fan folds; the bound falls back to the corners' spacing,
    // and still holds against ear clipping's triangulation.
    let c = [
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(1.0, 3.0, 0.0),
        v(0.5, 0.5, 0.0),
        v(0.0, 3.0, 0.0),
    ];
    let bound = polygon_twist(&c);
    let ears = [[c[0], c[1], c[3]], [c[1], c[2], c[3]], [c[0], c[3], c[4]]];
    let d = sampled_hausdorff(&fan(&c), &ears, 100);
    assert!(d > 0.0 && d <= bound, "{d} vs {bound}");
}

#[test]
fn a_mesh_summary_counts_polygons_above_a_limit() {
    let h = 0.1;
    let mut m = Mesh {
        positions: vec![
            [0.0, 0.0, h],
            [1.0, 0.0, -h],
            [1.0, 1.0, h],
            [0.0, 1.0, -h],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
        ]
        .into_iter()
        .map(|p: [f64; 3]| p.map(|x| x as f32))
        .collect(),
        ..Mesh::default()
    };
    m.push_face(&[0, 1, 2, 3]);
    m.push_face(&[1, 4, 5, 2]); // twisted too: 1 and 2 are at ∓h, 4 and 5 at 0
    m.push_face(&[4, 5, 2]);
    let t = Twists::of(&m);
    let first = polygon_twist(&rounded(&[
        v(0.0, 0.0, h),
        v(1.0, 0.0, -h),
        v(1.0, 1.0, h),
        v(0.0, 1.0, -h),
    ]));
    assert_eq!(t.max(), first);
    assert_eq!(t.count_above(0.0), 2);
    assert_eq!(t.count_above(first), 0);
    let second = polygon_twist(&rounded(&[
        v(1.0, 0.0, -h),
        v(2.0, 0.0, 0.0),
        v(2.0, 1.0, 0.0),
        v(1.0, 1.0, h),
    ]));
    assert!(second > 0.0 && second < first, "{second} {first}");
    assert_eq!(t.count_above(second), 1);
    assert_eq!(Twists::of(&Mesh::default()).max(), 0.0);
}

#[test]
fn the_note_names_the_fan_and_the_excess() {
    let mut r = Report {
        tolerance: Some(0.5),
        polygon_twist: Some(0.66),
        twisted_polygons: 1234,
        ..Report::default()
    };
    let note = r.twist_note().unwrap();
    assert!(note.contains("fan triangulation"), "{note}");
    assert!(note.contains("1234 polygons are twisted"), "{note}");
    assert!(note.contains("up to 0.660 (1.32× the tolerance)"), "{note}");
    r.twisted_polygons = 0;
    assert_eq!(r.twist_note(), None);
    let r = Report {
        surface_error: Some(2.0),
        polygon_twist: Some(3.0),
        twisted_polygons: 1,
        ..Report::default()
    };
    assert!(
        r.twist_note()
            .unwrap()
            .contains("1 polygon is twisted by more than the surface error, by up to 3.00 (1.50×")
    );
}

/// A `n` × `n` grid of quads over the unit square, corners alternately `h` up and down;
/// `triangles`: each quad split in two.
fn zigzag_grid(n: u32, h: f32, triangles: bool) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let z = if (i + j) % 2 == 0 { h } else { -h };
            m.positions
                .push([i as f32 / n as f32, j as f32 / n as f32, z]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            let q = [v, v + 1, v + n + 2, v + n + 1];
            if triangles {
                m.push_face(&[q[0], q[1], q[2]]);
                m.push_face(&[q[0], q[2], q[3]]);
            } else {
                m.push_face(&q);
            }
        }
    }
    m
}

#[test]
fn measuring_costs_little_next_to_simplifying() {
    use crate::{Count, Method, SimplifyOptions, simplify};
    use std::time::Instant;
    // 180² = 32 400 quads, as the held-out model; 708² × 2 ≈ 1.0 M triangles.
    // Start rayon's pool before timing anything.
    Twists::of(&zigzag_grid(8, 0.1, false));
    for (name, mesh) in [
        ("32k quads", zigzag_grid(180, 0.004, false)),
        ("1M triangles", zigzag_grid(708, 0.001, true)),
    ] {
        let start = Instant::now();
        let twists = Twists::of(&mesh);
        let measured = start.elapsed();
        let start = Instant::now();
        let options = SimplifyOptions::new(Method::Complexity(Count::Relative(0.2)));
        let out = simplify(&mesh, &options, &mut |_, _| true).unwrap();
        let simplified = start.elapsed();
        let start = Instant::now();
        let quality = SimplifyOptions::new(Method::Quality(crate::Length::Relative(0.01)));
        simplify(&mesh, &quality, &mut |_, _| true).unwrap();
        let bounded = start.elapsed();
        eprintln!(
            "{name}: twists measured in {:.2} ms; simplified (twists included) in {:.1} ms \
             (complexity 20 %), {:.1} ms (quality 1 %); largest twist {}",
            measured.as_secs_f64() * 1e3,
            simplified.as_secs_f64() * 1e3,
            bounded.as_secs_f64() * 1e3,
            twists.max()
        );
        if mesh.face(0).len() == 3 {
            assert_eq!(twists.max(), 0.0);
            assert_eq!(out.report.polygon_twist, Some(0.0));
        } else {
            // 2h / √(1 + 8h²/s²) for corners ±h on squares of side s.
            let (h, s) = (0.004f64, 1.0 / 180.0);
            let exact = 2.0 * h / (1.0 + 8.0 * h * h / (s * s)).sqrt();
            assert!(
                (twists.max() - exact).abs() < 1e-3 * exact,
                "{}",
                twists.max()
            );
            assert_eq!(twists.count_above(0.0), 180 * 180);
            assert_eq!(out.report.polygon_twist, Some(twists.max()));
        }
    }
}
