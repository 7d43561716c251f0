//! Analytic tests of the trim structure: classification against exact geometry, the
//! approximation's distance to exact curves, Loop–Blinn signs, quadtree invariants, the
//! packed layout, a counted depth-13 failure, and a real exported document.

mod common;

use common::{Rng, exact_inside, line, plane, sampled_loops};
use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};
use tessd_brep::{BSplineCurve, Curve, DVec2, Document, Face, Frame, Loop, Surface, Trim};
use tessd_trim::approximate::{approximate_loops, approximate_trim};
use tessd_trim::classify::classify;
use tessd_trim::implicit::{Implicit, ImplicitKind};
use tessd_trim::quadtree::NONE;
use tessd_trim::trim_source::TrimSource;
use tessd_trim::{MAX_DEPTH, NodeKind, Quadratic, TrimStructure};

fn square() -> Loop {
    let c = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    Loop {
        trims: (0..4).map(|i| line(c[i], c[(i + 1) % 4])).collect(),
    }
}

/// A full circle; clockwise for a hole.
fn circle(center: [f64; 2], radius: f64, clockwise: bool) -> Loop {
    Loop {
        trims: vec![Trim {
            curve: Curve::Circle {
                center: center.into(),
                x_dir: [1.0, 0.0].into(),
                y_dir: if clockwise {
                    [0.0, -1.0].into()
                } else {
                    [0.0, 1.0].into()
                },
                radius,
            },
            range: [0.0, TAU],
            edge: None,
        }],
    }
}

const C1: [f64; 2] = [0.28, 0.5];
const R1: f64 = 0.15;
const C2: [f64; 2] = [0.68, 0.45];
const R2: f64 = 0.22;
const R3: f64 = 0.1;

/// The unit square with a circular hole, and a second hole holding a circular island.
fn holes_face() -> Face {
    Face {
        id: 1,
        reversed: false,
        surface: plane(),
        bounds: [0.0, 1.0, 0.0, 1.0],
        loops: vec![
            square(),
            circle(C1, R1, true),
            circle(C2, R2, true),
            circle(C2, R3, false),
        ],
    }
}

/// The exact answer and the distance to the exact boundary.
fn exact(p: [f64; 2]) -> (bool, f64) {
    let d1 = (p[0] - C1[0]).hypot(p[1] - C1[1]);
    let d2 = (p[0] - C2[0]).hypot(p[1] - C2[1]);
    let inside_square = (0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]);
    let on = inside_square && d1 > R1 && !(R3..=R2).contains(&d2);
    let edge = p[0]
        .abs()
        .min((1.0 - p[0]).abs())
        .min(p[1].abs())
        .min((1.0 - p[1]).abs());
    let dist = edge
        .min((d1 - R1).abs())
        .min((d2 - R2).abs())
        .min((d2 - R3).abs());
    (on, dist)
}

#[test]
fn classification_matches_exact_geometry_within_eps() {
    let eps = 1e-3;
    let face = holes_face();
    let t = TrimStructure::build(&face, eps).unwrap();
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let n = 200_000;
    let (mut wrong, mut worst) = (0usize, 0.0f64);
    for _ in 0..n {
        let p = [rng.next() * 1.1 - 0.05, rng.next() * 1.1 - 0.05];
        let (want, dist) = exact(p);
        if t.classify(p[0], p[1]) != want {
            wrong += 1;
            worst = worst.max(dist);
        }
    }
    eprintln!(
        "holes face: {n} points, {wrong} disagreements, farthest {worst:.2e} from the boundary \
         (eps {eps}, eps_uv {:.2e}); stats {:?}",
        t.tolerance.eps_uv, t.stats
    );
    // The plane is an isometry: the (u, v) distance is the world distance.
    assert!(worst <= eps, "a disagreement {worst} from the boundary");
    assert!(wrong < n / 1000);
    assert_eq!(t.stats.failures, 0);
    assert!(t.stats.k_i.is_some());
}

/// Distance from `p` to the curve `c` over `[t0, t1]`: the nearest of `n` samples, refined by
/// golden-section search in the neighbouring intervals.
fn distance_to_curve(c: &Curve<DVec2>, t0: f64, t1: f64, samples: &[[f64; 2]], p: [f64; 2]) -> f64 {
    let n = samples.len() - 1;
    let d = |q: [f64; 2]| (q[0] - p[0]).hypot(q[1] - p[1]);
    let (best, _) = samples
        .iter()
        .enumerate()
        .map(|(i, &q)| (i, d(q)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    let at = |i: usize| t0 + (t1 - t0) * i as f64 / n as f64;
    let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(n)));
    let g = 0.618_033_988_75;
    for _ in 0..80 {
        let x1 = b - g * (b - a);
        let x2 = a + g * (b - a);
        if d(c.point(x1).to_array()) < d(c.point(x2).to_array()) {
            b = x2;
        } else {
            a = x1;
        }
    }
    d(c.point(0.5 * (a + b)).to_array())
}

/// Both one-sided distances between the approximation and the curve, by dense sampling.
fn hausdorff(trim: &Trim, pieces: &[Quadratic]) -> f64 {
    let [t0, t1] = trim.range;
    let n = 4000;
    let exact: Vec<[f64; 2]> = (0..=n)
        .map(|i| {
            trim.curve
                .point(t0 + (t1 - t0) * i as f64 / n as f64)
                .to_array()
        })
        .collect();
    let mut worst: f64 = 0.0;
    let mut approx = Vec::new();
    for q in pieces {
        for i in 0..=40 {
            let p = q.point(i as f64 / 40.0);
            approx.push(p);
            worst = worst.max(distance_to_curve(&trim.curve, t0, t1, &exact, p));
        }
    }
    for e in exact.iter().step_by(4) {
        let d = approx
            .iter()
            .map(|a| (a[0] - e[0]).hypot(a[1] - e[1]))
            .fold(f64::INFINITY, f64::min);
        // the nearest approximation sample, not the nearest curve point: allow the sampling
        // step of a piece on top.
        let step = pieces
            .iter()
            .map(|q| (q.p[0][0] - q.p[2][0]).hypot(q.p[0][1] - q.p[2][1]) / 40.0)
            .fold(0.0, f64::max);
        worst = worst.max((d - step).max(0.0));
    }
    worst
}

fn check_approximation(name: &str, trim: &Trim, eps: f64) {
    let a = approximate_trim(trim, eps).unwrap();
    let h = hausdorff(trim, &a.pieces);
    let lines = a.pieces.iter().filter(|q| q.line).count();
    eprintln!(
        "{name}: eps {eps:.0e}: {} pieces ({lines} lines), measured {:.2e}, dense {h:.2e}",
        a.pieces.len(),
        a.max_error
    );
    assert!(h <= eps, "{name}: {h} > {eps}");
    for w in a.pieces.windows(2) {
        assert_eq!(w[0].p[2], w[1].p[0], "{name}: pieces are connected");
    }
    let [t0, t1] = trim.range;
    let (s, e) = (trim.curve.point(t0), trim.curve.point(t1));
    assert!((a.pieces[0].p[0][0] - s[0]).hypot(a.pieces[0].p[0][1] - s[1]) < 1e-12);
    let last = a.pieces.last().unwrap().p[2];
    assert!((last[0] - e[0]).hypot(last[1] - e[1]) < 1e-12);
}

fn nurbs_circle(center: [f64; 2], r: f64) -> Curve<DVec2> {
    let w = FRAC_1_SQRT_2;
    let dirs = [
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [-1.0, 1.0],
        [-1.0, 0.0],
        [-1.0, -1.0],
        [0.0, -1.0],
        [1.0, -1.0],
        [1.0, 0.0],
    ];
    Curve::Bspline(BSplineCurve {
        degree: 2,
        poles: dirs
            .iter()
            .map(|d| DVec2::new(center[0] + r * d[0], center[1] + r * d[1]))
            .collect(),
        weights: Some(vec![1.0, w, 1.0, w, 1.0, w, 1.0, w, 1.0]),
        knots: vec![0.0, 1.0, 2.0, 3.0, 4.0],
        mults: vec![3, 2, 2, 2, 3],
        periodic: false,
        cache: Default::default(),
    })
}

#[test]
fn approximations_stay_within_eps() {
    let circle = Trim {
        curve: Curve::Circle {
            center: [0.3, -0.2].into(),
            x_dir: [1.0, 0.0].into(),
            y_dir: [0.0, 1.0].into(),
            radius: 2.0,
        },
        range: [0.3, 0.3 + TAU],
        edge: None,
    };
    let ellipse = Trim {
        curve: Curve::Ellipse {
            center: [1.0, 2.0].into(),
            x_dir: [0.6, 0.8].into(),
            y_dir: [-0.8, 0.6].into(),
            major_radius: 3.0,
            minor_radius: 0.5,
        },
        range: [2.0 * PI, 0.0],
        edge: None,
    };
    let rational = Trim {
        curve: nurbs_circle([0.5, 0.5], 1.5),
        range: [0.0, 4.0],
        edge: None,
    };
    let quintic = Trim {
        curve: Curve::Bspline(BSplineCurve {
            degree: 5,
            poles: vec![
                [0.0, 0.0].into(),
                [1.0, 2.0].into(),
                [2.0, -1.0].into(),
                [3.0, 3.0].into(),
                [4.0, 0.0].into(),
                [5.0, 1.0].into(),
                [6.0, -2.0].into(),
            ],
            weights: Some(vec![1.0, 2.0, 0.5, 1.0, 3.0, 1.0, 1.0]),
            knots: vec![0.0, 0.4, 1.0],
            mults: vec![6, 1, 6],
            periodic: false,
            cache: Default::default(),
        }),
        range: [0.0, 1.0],
        edge: None,
    };
    for eps in [1e-2, 1e-3, 1e-4] {
        check_approximation("circle", &circle, eps);
        check_approximation("ellipse (reversed)", &ellipse, eps);
        check_approximation("rational B-spline circle", &rational, eps);
        check_approximation("rational quintic", &quintic, eps);
    }
    // The NURBS circle is a circle: measure analytically too.
    let a = approximate_trim(&rational, 1e-4).unwrap();
    for q in &a.pieces {
        for i in 0..=100 {
            let p = q.point(i as f64 / 100.0);
            let d = ((p[0] - 0.5).hypot(p[1] - 0.5) - 1.5).abs();
            assert!(d <= 1e-4, "{d}");
        }
    }
}

/// Circles and ellipses are cut into Béziers directly (`approximate_conic`), not fitted: the
/// pieces stay within the fit's half of the tolerance of the curve both ways (a quarter more
/// where flattened), the reported error bounds the true distance, the pieces are connected,
/// start and end on the curve, and there are no more of them than the sampled fit of the same
/// circle (a rational B-spline) makes.
#[test]
fn conics_are_cut_directly_within_eps() {
    let circle = |r: f64, range: [f64; 2], clockwise: bool| Trim {
        curve: Curve::Circle {
            center: [0.3, -0.2].into(),
            x_dir: [FRAC_1_SQRT_2, FRAC_1_SQRT_2].into(),
            y_dir: if clockwise {
                [FRAC_1_SQRT_2, -FRAC_1_SQRT_2].into()
            } else {
                [-FRAC_1_SQRT_2, FRAC_1_SQRT_2].into()
            },
            radius: r,
        },
        range,
        edge: None,
    };
    let ellipse = |a: f64, b: f64, range: [f64; 2]| Trim {
        curve: Curve::Ellipse {
            center: [1.0, 2.0].into(),
            x_dir: [0.6, 0.8].into(),
            y_dir: [-0.8, 0.6].into(),
            major_radius: a,
            minor_radius: b,
        },
        range,
        edge: None,
    };
    let mut trims = Vec::new();
    for r in [2e-3, 0.05, 2.0, 300.0] {
        trims.push(circle(r, [0.0, TAU], false));
        trims.push(circle(r, [TAU, 0.0], true));
        trims.push(circle(r, [0.4, 1.3], false));
        trims.push(circle(r, [5.0, 5.0 - 1e-3], true));
        trims.push(ellipse(r, 0.3 * r, [2.0 * PI, 0.0]));
        trims.push(ellipse(r, r / 40.0, [-0.7, 2.9]));
    }
    for eps in [1e-1, 1e-2, 1e-3, 1e-4] {
        for trim in &trims {
            let a = approximate_trim(trim, eps).unwrap();
            let h = hausdorff(trim, &a.pieces);
            let flattened = a.pieces.iter().any(|q| q.line);
            let share = if flattened { 0.75 } else { 0.5 };
            let name = format!("{:?} over {:?} at {eps:e}", trim.curve, trim.range);
            assert!(h <= share * eps, "{name}: {h:e} > {share} eps");
            assert!(
                a.max_error <= share * eps,
                "{name}: reported {:e}",
                a.max_error
            );
            assert!(
                h <= a.max_error * 1.001 + 1e-12,
                "{name}: {h:e} > {:e}",
                a.max_error
            );
            for w in a.pieces.windows(2) {
                assert_eq!(w[0].p[2], w[1].p[0], "{name}: pieces are connected");
            }
            let [t0, t1] = trim.range;
            assert_eq!(a.pieces[0].p[0], trim.curve.point(t0).to_array(), "{name}");
            assert_eq!(
                a.pieces.last().unwrap().p[2],
                trim.curve.point(t1).to_array(),
                "{name}"
            );
        }
        // The circle as a NURBS goes through sampling, fitting and knot removal.
        let exact = Trim {
            curve: Curve::Circle {
                center: [0.5, 0.5].into(),
                x_dir: [1.0, 0.0].into(),
                y_dir: [0.0, 1.0].into(),
                radius: 1.5,
            },
            range: [0.0, TAU],
            edge: None,
        };
        let rational = Trim {
            curve: nurbs_circle([0.5, 0.5], 1.5),
            range: [0.0, 4.0],
            edge: None,
        };
        let direct = approximate_trim(&exact, eps).unwrap().pieces.len();
        let fitted = approximate_trim(&rational, eps).unwrap().pieces.len();
        assert!(direct <= fitted, "eps {eps:e}: {direct} > {fitted} pieces");
    }
}

#[test]
fn loop_blinn_signs() {
    // Turning right (concave): the face is on the left, above the arch.
    let arch = Quadratic::new([0.0, 0.0], [0.5, 1.0], [1.0, 0.0]);
    let im = Implicit::of(&arch);
    assert_eq!(im.kind, ImplicitKind::Concave);
    assert!(im.classify(0.5, 0.6)); // above the apex (0.5, 0.5)
    assert!(!im.classify(0.5, 0.4)); // under it
    assert!(!im.classify(0.5, -1.0)); // under the chord
    assert!(im.classify(0.2, 0.9)); // above, inside the control triangle's hull region
    // Walked the other way (convex): the face is under the arch.
    let back = Quadratic::new([1.0, 0.0], [0.5, 1.0], [0.0, 0.0]);
    let im = Implicit::of(&back);
    assert_eq!(im.kind, ImplicitKind::Convex);
    assert!(!im.classify(0.5, 0.6));
    assert!(im.classify(0.5, 0.4));
    assert!(im.classify(0.5, -1.0));
    assert!(!im.classify(0.5, 2.0));
    // Points on the curve are on (f = 0).
    let c = back.point(0.3);
    let (x, y) = im.xy(c[0], c[1]);
    assert!((y - x * x).abs() < 1e-6);
    // A segment: left is on.
    let seg = Implicit::of(&Quadratic::segment([0.0, 0.0], [1.0, 0.0]));
    assert_eq!(seg.kind, ImplicitKind::Line);
    assert!(seg.classify(0.5, 0.1) && !seg.classify(0.5, -0.1));
    // Collinear control points classify as their line.
    let flat = Implicit::of(&Quadratic::new([0.0, 0.0], [0.5, 0.0], [1.0, 0.0]));
    assert_eq!(flat.kind, ImplicitKind::Line);
    // Triangles in the convex region classify whole.
    assert_eq!(
        im.classify_triangle(&[[0.4, 0.1], [0.6, 0.1], [0.5, 0.3]]),
        Some(true)
    );
    assert_eq!(
        im.classify_triangle(&[[0.4, 0.1], [0.6, 0.1], [0.5, 0.9]]),
        None
    );
}

fn check_invariants(t: &TrimStructure) {
    let tree = &t.tree;
    let mut failed = 0;
    let mut leaves = 0;
    for (i, n) in tree.nodes.iter().enumerate() {
        let h = n.size();
        let rect = n.clip_rect();
        let crossing: Vec<u32> = (0..tree.curves.len() as u32)
            .filter(|&c| tree.curves[c as usize].clip(rect).is_some())
            .collect();
        if n.kind != NodeKind::Internal {
            leaves += 1;
        }
        match n.kind {
            NodeKind::Internal => {
                let c = n.first_child as usize;
                assert!(c > i && c + 4 <= tree.nodes.len());
                let mean = tree.nodes[c..c + 4].iter().map(|k| k.coverage).sum::<f64>() / 4.0;
                assert!((mean - n.coverage).abs() < 1e-12);
                for k in 0..4 {
                    assert_eq!(tree.nodes[c + k].depth, n.depth + 1);
                }
                assert!(!crossing.is_empty());
            }
            NodeKind::On | NodeKind::Off => {
                assert!(crossing.is_empty(), "node {i}");
                assert_eq!(n.coverage, if n.kind == NodeKind::On { 1.0 } else { 0.0 });
            }
            NodeKind::One => assert_eq!(crossing, vec![n.curves[0]]),
            NodeKind::Two => {
                assert_eq!(crossing.len(), 2);
                assert!(crossing.contains(&n.curves[0]) && crossing.contains(&n.curves[1]));
                assert_ne!(n.line, NONE);
                // The curves' parts in the cell lie on their sides of the line.
                let l = tree.lines[n.line as usize].map(f64::from);
                for (k, &c) in n.curves.iter().enumerate() {
                    let q = &tree.curves[c as usize];
                    let [a, b] = q.clip(rect).unwrap();
                    for j in 0..=50 {
                        let p = q.point(a + (b - a) * j as f64 / 50.0);
                        let side = l[0] * p[0] + l[1] * p[1] + l[2];
                        // the line is stored in f32: allow its rounding
                        let tol = 1e-6 * h + 1e-7;
                        let want = if k == 0 { side >= -tol } else { side <= tol };
                        assert!(
                            want,
                            "node {i}: curve {c} crosses its separating line by {side:e}"
                        );
                    }
                }
            }
            NodeKind::Failed => {
                failed += 1;
                assert_eq!(n.depth, MAX_DEPTH);
                assert!(crossing.len() >= 2);
            }
        }
        assert_eq!(n.covered, n.coverage >= 0.5);
    }
    assert_eq!(failed, tree.failures);
    assert_eq!(leaves, tree.leaves_per_depth.iter().sum::<u32>());
}

#[test]
fn quadtree_invariants() {
    let t = TrimStructure::build(&holes_face(), 1e-3).unwrap();
    check_invariants(&t);
    let t = TrimStructure::build(&tangent_face(), 1e-3).unwrap();
    check_invariants(&t);
}

#[test]
fn packed_layout_round_trips() {
    let t = TrimStructure::build(&holes_face(), 1e-3).unwrap();
    assert_eq!(t.stats.bytes, t.packed.bytes());
    assert_eq!(
        t.packed.bytes(),
        16 + 4 * t.tree.nodes.len() + 24 * t.tree.curves.len() + 20 * t.tree.lines.len()
    );
    for i in 0..t.tree.nodes.len() as u32 {
        assert_eq!(t.tree.node(i), t.packed.node(i));
    }
    let mut rng = Rng(99);
    for k in 0..100_000 {
        let (u, v) = (rng.next() * 1.2 - 0.1, rng.next() * 1.2 - 0.1);
        let fp = if k % 2 == 0 {
            [0.0, 0.0]
        } else {
            [1e-3 * (k % 7) as f64; 2]
        };
        assert_eq!(classify(&t.tree, u, v, fp), classify(&t.packed, u, v, fp));
    }
}

#[test]
fn footprint_stops_early_with_coverage() {
    let t = TrimStructure::build(&holes_face(), 1e-3).unwrap();
    // A footprint as large as the domain answers from the root's coverage bit.
    let c = t.classify_at(0.5, 0.5, [10.0, 10.0]);
    assert_eq!((c.node, c.depth, c.used_curves), (0, 0, false));
    assert_eq!(c.on, t.tree.nodes[0].covered);
    // Coarser footprints never descend deeper.
    let mut rng = Rng(7);
    for _ in 0..10_000 {
        let (u, v) = (rng.next(), rng.next());
        let fine = t.classify_at(u, v, [0.0, 0.0]);
        let coarse = t.classify_at(u, v, [0.05, 0.05]);
        assert!(coarse.depth <= fine.depth);
        assert!(coarse.depth <= 5);
    }
}

/// The unit square with a circular hole touching its bottom edge at (0.5, 0), where the
/// hole's two end pieces meet: three curves share every cell around that point. The patch
/// (bounds) is larger than the square, so the square is a trim of its own and not left to
/// the root's rectangle (`tessd_trim::patch_boundary`).
fn tangent_face() -> Face {
    Face {
        id: 2,
        reversed: false,
        surface: plane(),
        bounds: [-0.25, 1.0, -0.25, 1.0],
        loops: vec![
            square(),
            Loop {
                trims: vec![Trim {
                    curve: Curve::Circle {
                        center: [0.5, 0.25].into(),
                        x_dir: [0.0, -1.0].into(),
                        y_dir: [-1.0, 0.0].into(),
                        radius: 0.25,
                    },
                    range: [0.0, TAU],
                    edge: None,
                }],
            },
        ],
    }
}

#[test]
fn tangent_curves_fail_at_depth_13_and_are_counted() {
    let t = TrimStructure::build(&tangent_face(), 1e-3).unwrap();
    eprintln!("tangent face: {:?}", t.stats);
    assert!(t.stats.failures >= 1);
    assert_eq!(t.stats.max_depth, MAX_DEPTH);
    let failed: Vec<_> = t
        .tree
        .nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Failed)
        .collect();
    assert_eq!(failed.len() as u32, t.stats.failures);
    for n in failed {
        // around the tangent point, normalised
        let d = t.tree.domain;
        let p = [(0.5 - d[0]) / (d[1] - d[0]), (0.0 - d[2]) / (d[3] - d[2])];
        let h = n.size();
        assert!((n.origin[0] - p[0]).abs() <= 2.0 * h && (n.origin[1] - p[1]).abs() <= 2.0 * h);
    }
    // Away from the failure the answers are right.
    assert!(t.classify(0.5, 0.75));
    assert!(!t.classify(0.5, 0.25));
    assert!(t.classify(0.1, 0.1));
}

#[test]
fn faces_without_loops_are_their_bounds() {
    let face = Face {
        id: 3,
        reversed: false,
        surface: plane(),
        bounds: [-2.0, 3.0, 10.0, 11.0],
        loops: vec![],
    };
    let t = TrimStructure::build(&face, 0.01).unwrap();
    assert!(t.classify(0.0, 10.5));
    assert!(t.classify(-2.0, 10.0) && t.classify(3.0, 11.0));
    assert!(!t.classify(3.5, 10.5) && !t.classify(0.0, 11.001));
    // The whole patch is on: one "on" root, nothing to walk (patch_boundary).
    assert_eq!(t.tree.nodes.len(), 1);
    assert_eq!(t.tree.nodes[0].kind, NodeKind::On);
    assert_eq!(t.stats.k_i, Some(0));
    assert!(TrimStructure::build(&face, 0.0).is_err());
    assert!(TrimStructure::build(&face, f64::NAN).is_err());
}

/// A rectangle bounded by four lines inside a larger patch makes a shallow tree; its level
/// k_i lies below the deepest leaf, where the triangles still subdivide the leaves (section 6).
#[test]
fn a_shallow_tree_finds_its_triangle_level() {
    let (a, b, c, d) = ([0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]);
    let face = Face {
        id: 4,
        reversed: false,
        surface: plane(),
        bounds: [-1.0, 4.0, -1.0, 3.0],
        loops: vec![Loop {
            trims: vec![line(a, b), line(b, c), line(c, d), line(d, a)],
        }],
    };
    let t = TrimStructure::build(&face, 0.01).unwrap();
    let k = t.stats.k_i.expect("the 40 % level of a rectangle");
    assert!(
        t.tree.classifiable[k as usize] >= 0.4,
        "{:?}",
        t.tree.classifiable
    );
    assert!(t.tree.classifiable[..k as usize].iter().all(|&f| f < 0.4));
}

#[test]
fn bottle_document_builds_at_both_tolerances() {
    let text = include_str!("data/bottle.json");
    let doc = Document::from_json(text).unwrap();
    doc.validate().unwrap();
    for eps in [0.1, 0.01] {
        let (mut quads, mut nodes, mut bytes, mut failures, mut failed_faces) = (0, 0, 0, 0, 0);
        let mut time = std::time::Duration::ZERO;
        let (mut points, mut disagreements) = (0, 0);
        for face in &doc.faces {
            let t = TrimStructure::build(face, eps).unwrap();
            quads += t.stats.quadratics;
            nodes += t.stats.nodes;
            bytes += t.stats.bytes;
            failures += t.stats.failures;
            failed_faces += usize::from(t.stats.failures > 0);
            time += t.stats.build_time;
            // The face is not empty: some of its domain classifies on.
            assert!(t.tree.nodes[0].coverage > 0.0, "face {}", face.id);
            let (n, wrong) = compare_with_polygons(face, &t);
            points += n;
            disagreements += wrong;
            if wrong > 0 {
                eprintln!(
                    "face {} ({}): {wrong} disagreements, {} loops",
                    face.id,
                    face.surface.type_name(),
                    face.loops.len()
                );
            }
        }
        eprintln!(
            "bottle at {eps} mm: {} faces, {quads} quadratics, {nodes} nodes, {bytes} bytes, \
             {failures} failed nodes in {failed_faces} faces, build {time:?}; \
             {disagreements} of {points} random points disagree with dense polygons",
            doc.faces.len()
        );
        assert_eq!(disagreements, 0);
    }
}

fn arc(center: [f64; 2], r: f64, from: f64, to: f64) -> Trim {
    Trim {
        curve: Curve::Circle {
            center: center.into(),
            x_dir: [1.0, 0.0].into(),
            y_dir: [0.0, 1.0].into(),
            radius: r,
        },
        range: [from, to],
        edge: None,
    }
}

#[test]
fn c1_input_gives_c1_joints() {
    // A stadium: lines and half circles meeting with C1 continuity.
    let face = Face {
        id: 4,
        reversed: false,
        surface: plane(),
        bounds: [0.0, 1.0, 0.0, 1.0],
        loops: vec![Loop {
            trims: vec![
                line([0.2, 0.3], [0.8, 0.3]),
                arc([0.8, 0.5], 0.2, -PI / 2.0, PI / 2.0),
                line([0.8, 0.7], [0.2, 0.7]),
                arc([0.2, 0.5], 0.2, PI / 2.0, 1.5 * PI),
            ],
        }],
    };
    let loops = approximate_loops(&face, 1e-4).unwrap().loops;
    let pieces = &loops[0];
    assert!(pieces.len() > 8);
    let unit = |d: [f64; 2]| {
        let l = d[0].hypot(d[1]);
        [d[0] / l, d[1] / l]
    };
    let n = pieces.len();
    for i in 0..n {
        let (a, b) = (&pieces[i], &pieces[(i + 1) % n]);
        assert_eq!(a.p[2], b.p[0]);
        let ta = unit(if a.line {
            [a.p[2][0] - a.p[0][0], a.p[2][1] - a.p[0][1]]
        } else {
            [a.p[2][0] - a.p[1][0], a.p[2][1] - a.p[1][1]]
        });
        let tb = unit(if b.line {
            [b.p[2][0] - b.p[0][0], b.p[2][1] - b.p[0][1]]
        } else {
            [b.p[1][0] - b.p[0][0], b.p[1][1] - b.p[0][1]]
        });
        let cross = ta[0] * tb[1] - ta[1] * tb[0];
        let dot = ta[0] * tb[0] + ta[1] * tb[1];
        assert!(cross.abs() < 1e-9 && dot > 0.0, "joint {i}: {cross:e}");
    }
}

#[test]
fn world_tolerance_holds_on_a_cylinder() {
    let r = 10.0;
    let face = Face {
        id: 5,
        reversed: false,
        surface: Surface::Cylinder {
            frame: Frame {
                origin: [0.0, 0.0, 0.0].into(),
                x_dir: [1.0, 0.0, 0.0].into(),
                y_dir: [0.0, 1.0, 0.0].into(),
            },
            radius: r,
        },
        bounds: [0.0, PI, 0.0, 5.0],
        loops: vec![Loop {
            trims: vec![Trim {
                curve: Curve::Ellipse {
                    center: [1.5, 2.5].into(),
                    x_dir: [0.0, 1.0].into(),
                    y_dir: [-1.0, 0.0].into(),
                    major_radius: 2.0,
                    minor_radius: 1.0,
                },
                range: [0.0, TAU],
                edge: None,
            }],
        }],
    };
    let eps = 0.01;
    let t = TrimStructure::build(&face, eps).unwrap();
    // Su = r (−sin u, cos u, 0) and Sv = (0, 0, 1) are orthogonal: the Jacobian's largest
    // singular value is max(r, 1) = r.
    let expect = eps / (1.25 * r);
    assert!(
        (t.tolerance.eps_uv - expect).abs() < 1e-6 * expect,
        "{:?}",
        t.tolerance
    );
    let trim = &face.loops[0].trims[0];
    let n = 50_000;
    let world: Vec<[f64; 3]> = (0..=n)
        .map(|i| {
            let p = trim.curve.point(TAU * i as f64 / n as f64);
            face.surface.point(p[0], p[1]).to_array()
        })
        .collect();
    let mut worst: f64 = 0.0;
    for q in &t.loops[0] {
        for i in 0..=20 {
            let p = q.point(i as f64 / 20.0);
            let w = face.surface.point(p[0], p[1]);
            let d = world
                .iter()
                .map(|e| {
                    ((e[0] - w[0]).powi(2) + (e[1] - w[1]).powi(2) + (e[2] - w[2]).powi(2)).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
    }
    eprintln!(
        "cylinder: {} pieces, world distance {worst:.2e} (eps {eps})",
        t.loops[0].len()
    );
    assert!(worst <= eps);
    assert!(t.classify(1.5, 2.5) && !t.classify(0.2, 0.2));
}

/// Classifies random points of the face's bounds against even-odd on the loops sampled densely
/// (256 points per trim); counts the disagreements farther than the (u, v) tolerance plus the
/// polygons' own sampling error from the polygons.
fn compare_with_polygons(face: &Face, t: &TrimStructure) -> (usize, usize) {
    let polys = sampled_loops(face, 256);
    let [u0, u1, v0, v1] = face.bounds;
    let size = (u1 - u0).hypot(v1 - v0);
    let mut rng = Rng(face.id + 17);
    let (mut n, mut wrong) = (0, 0);
    for _ in 0..2000 {
        let p = [u0 + (u1 - u0) * rng.next(), v0 + (v1 - v0) * rng.next()];
        let (inside, dist) = exact_inside(&polys, p, face.loops.is_empty());
        n += 1;
        if t.classify(p[0], p[1]) != inside && dist > t.tolerance.eps_uv + 1e-3 * size {
            wrong += 1;
        }
    }
    (n, wrong)
}

#[test]
fn many_holes_classify_within_eps() {
    let n = 12;
    let r = 0.3 / n as f64;
    let centers: Vec<[f64; 2]> = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64]
        })
        .collect();
    let mut loops = vec![square()];
    loops.extend(centers.iter().map(|&c| circle(c, r, true)));
    let face = Face {
        id: 6,
        reversed: false,
        surface: plane(),
        bounds: [0.0, 1.0, 0.0, 1.0],
        loops,
    };
    let eps = 1e-4;
    let t = TrimStructure::build(&face, eps).unwrap();
    let mut rng = Rng(5);
    let (mut wrong, mut worst) = (0, 0.0f64);
    for _ in 0..100_000 {
        let p = [rng.next(), rng.next()];
        let d = centers
            .iter()
            .map(|c| (p[0] - c[0]).hypot(p[1] - c[1]))
            .fold(f64::INFINITY, f64::min);
        let on = d > r;
        let edge = p[0].min(1.0 - p[0]).min(p[1]).min(1.0 - p[1]);
        if t.classify(p[0], p[1]) != on {
            wrong += 1;
            worst = worst.max((d - r).abs().min(edge));
        }
    }
    eprintln!(
        "{} holes: {wrong} disagreements, farthest {worst:.1e}; {:?}",
        n * n,
        t.stats
    );
    assert!(worst <= eps);
}

/// A face whose outer loop is its patch rectangle (a slab's side with two round holes, the
/// rectangle split at a vertex as exporters do): the quadtree leaves the rectangle to its
/// root (`tessd_trim::patch_boundary`) and keeps the holes — fewer nodes and bytes than the
/// same face in a larger patch, where the rectangle must be walked — and both classify as
/// the exact loops do.
#[test]
fn an_outer_loop_along_the_patch_is_left_to_the_root() {
    let c = [[0.0, 0.0], [1.5, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]];
    let outer = Loop {
        trims: (0..5).map(|i| line(c[i], c[(i + 1) % 5])).collect(),
    };
    let face = |bounds: [f64; 4]| Face {
        id: 9,
        reversed: false,
        surface: plane(),
        bounds,
        loops: vec![
            outer.clone(),
            circle([0.75, 0.5], 0.3, true),
            circle([2.25, 0.5], 0.3, true),
        ],
    };
    let own = face([0.0, 3.0, 0.0, 1.0]);
    let wider = face([-0.5, 3.0, 0.0, 1.0]);
    let (a, b) = (
        TrimStructure::build(&own, 1e-4).unwrap(),
        TrimStructure::build(&wider, 1e-4).unwrap(),
    );
    assert_eq!(a.tree.base_winding, 1);
    assert_eq!(b.tree.base_winding, 0);
    assert!(
        a.stats.quadratics + 5 <= b.stats.quadratics,
        "{:?} {:?}",
        a.stats,
        b.stats
    );
    assert!(
        a.stats.bytes < b.stats.bytes,
        "{} {}",
        a.stats.bytes,
        b.stats.bytes
    );
    for (f, t) in [(&own, &a), (&wider, &b)] {
        let (n, wrong) = compare_with_polygons(f, t);
        assert_eq!(
            wrong, 0,
            "face bounds {:?}: {wrong} of {n} points",
            f.bounds
        );
    }
    // Corners and sides of the patch are on; beyond them, off; the holes' centres off.
    assert!(a.classify(0.0, 0.0) && a.classify(3.0, 1.0) && a.classify(1.5, 0.0));
    assert!(!a.classify(-1e-3, 0.5) && !a.classify(1.5, 1.001));
    assert!(!a.classify(0.75, 0.5) && !a.classify(2.25, 0.5));
    // The packed form (what the GPU walks) answers the same.
    let mut rng = Rng(3);
    for _ in 0..2000 {
        let (u, v) = (3.0 * rng.next(), rng.next());
        assert_eq!(
            classify(&a.packed, u, v, [0.0, 0.0]).on,
            a.classify(u, v),
            "({u}, {v})"
        );
    }
}
