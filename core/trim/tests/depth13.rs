//! The configurations behind the depth-13 failures (paper 000, section 8, table 4) found on
//! the benchmark parts, as small faces: each must build without a failed leaf and classify
//! like an even-odd test on its densely sampled exact trims, away from the trims by more than
//! the (u, v) tolerance.
//!
//! - trims far shorter than ε doubling back on their neighbours (shell1.brep, CrankArm.brep,
//!   hammer.iges) or running on along them (M6 screw): three curves in every cell around them;
//! - a tangent cusp next to a trim approximated by a single quadratic (CrankArm.brep faces
//!   29, 30): its end tangents were not honoured, and the approximations crossed;
//! - a corner inside a B-spline trim (knots of full multiplicity, face2.brep): the C1 fit
//!   rounded it with a cluster of short spans.
//!
//! The fourth cause, a junction on a cell edge where one piece only touches the cell at its
//! end (hammer.iges face 37), is tested in `separate.rs`.

mod common;

use common::{Rng, exact_inside, line, plane};
use std::f64::consts::PI;
use tessd_brep::{BSplineCurve, Curve, Face, Loop, Trim};
use tessd_trim::{NodeKind, TrimStructure};

/// A clockwise arc (`y_dir` = `x_dir` turned −90°) of the ellipse at `center` with semi-axes
/// `a` along u and `b` along v, from angle `from` to `to` (walked with t increasing).
fn cw_ellipse(center: [f64; 2], a: f64, b: f64, from: f64, to: f64) -> Trim {
    Trim {
        curve: Curve::Ellipse {
            center: center.into(),
            x_dir: [1.0, 0.0].into(),
            y_dir: [0.0, -1.0].into(),
            major_radius: a,
            minor_radius: b,
        },
        range: [from, to],
        edge: None,
    }
}

fn bspline(degree: usize, poles: Vec<[f64; 2]>, knots: Vec<f64>, mults: Vec<u32>) -> Trim {
    let range = [knots[0], *knots.last().unwrap()];
    Trim {
        curve: Curve::Bspline(BSplineCurve {
            degree,
            poles: poles.into_iter().map(Into::into).collect(),
            weights: None,
            knots,
            mults,
            periodic: false,
            cache: Default::default(),
        }),
        range,
        edge: None,
    }
}

fn face(bounds: [f64; 4], trims: Vec<Trim>) -> Face {
    Face {
        id: 0,
        reversed: false,
        surface: plane(),
        bounds,
        loops: vec![Loop { trims }],
    }
}

/// Builds `face` at `eps`; asserts no failed leaf, and that random points of the bounds and
/// points around `spots` (at radii from 3 ε_uv to a tenth of the bounds) classify as
/// even-odd on the exact trims (1024 samples each) wherever they are farther than ε_uv from
/// the trims. Returns the structure.
fn check(name: &str, face: &Face, eps: f64, spots: &[[f64; 2]]) -> TrimStructure {
    let t = TrimStructure::build(face, eps).unwrap();
    let failed: Vec<_> = t
        .tree
        .nodes
        .iter()
        .filter(|n| n.kind == NodeKind::Failed)
        .map(|n| n.origin)
        .collect();
    assert_eq!(
        t.stats.failures, 0,
        "{name} at ε {eps}: failed leaves at {failed:?}"
    );
    let poly: Vec<[f64; 2]> = face.loops[0]
        .trims
        .iter()
        .flat_map(|tr| {
            let [t0, t1] = tr.range;
            (0..1024).map(move |i| {
                tr.curve
                    .point(t0 + (t1 - t0) * i as f64 / 1024.0)
                    .to_array()
            })
        })
        .collect();
    let [u0, u1, v0, v1] = face.bounds;
    let size = (u1 - u0).hypot(v1 - v0);
    let eps_uv = t.tolerance.eps_uv;
    let mut rng = Rng(0x5EED + (eps * 1e6) as u64);
    let mut points: Vec<[f64; 2]> = (0..5_000)
        .map(|_| [u0 + (u1 - u0) * rng.next(), v0 + (v1 - v0) * rng.next()])
        .collect();
    for s in spots {
        let mut r = 3.0 * eps_uv;
        while r < 0.1 * size {
            for _ in 0..200 {
                let (a, rr) = (2.0 * PI * rng.next(), r * rng.next().sqrt());
                points.push([s[0] + rr * a.cos(), s[1] + rr * a.sin()]);
            }
            r *= 4.0;
        }
    }
    let mut wrong = Vec::new();
    for p in points {
        let (inside, d) = exact_inside(std::slice::from_ref(&poly), p, false);
        if t.classify(p[0], p[1]) != inside && d > eps_uv {
            wrong.push((p, d));
        }
    }
    assert!(
        wrong.is_empty(),
        "{name} at ε {eps}: {} points misclassified beyond ε_uv {eps_uv:e}, e.g. {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(3)]
    );
    t
}

/// shell1.brep face 13: a curve comes down to the bottom edge, where a 5e-7 long line steps
/// back before the bottom line runs on to the right — and the same at the top.
fn spike_face() -> Face {
    let a = [0.610636474890603, 1.0];
    let b = [0.5999992484795699, 0.0];
    let b2 = [0.5999987035470085, 0.0];
    let a2 = [0.610636491492605, 1.0];
    face(
        [0.0, 1.0, 0.0, 1.0],
        vec![
            bspline(
                2,
                vec![a, [0.6060755508003743, 0.605324232300815], b],
                vec![0.0, 1.0],
                vec![3, 3],
            ),
            line(b, b2),
            line(b2, [1.0, 0.0]),
            line([1.0, 0.0], [1.0, 1.0]),
            line([1.0, 1.0], a2),
            line(a2, a),
        ],
    )
}

#[test]
fn tiny_trims_doubling_back_are_dropped() {
    let f = spike_face();
    for eps in [0.1, 0.01, 1e-3, 1e-4] {
        let t = check("spike", &f, eps, &[[0.6, 0.0], [0.6106, 1.0]]);
        // the two 5e-7 lines are gone
        assert_eq!(t.stats.quadratics, 4, "{:?}", t.loops);
    }
}

/// M6-1x12-countersunk-screw.step face 24: the unit square whose left side starts with a
/// 4e-8 long piece below the top-left corner.
#[test]
fn tiny_trims_running_on_are_dropped() {
    let c = [0.0, 0.9999999599200037];
    let f = face(
        [0.0, 1.0, 0.0, 1.0],
        vec![
            line([0.0, 1.0], c),
            line(c, [0.0, 0.0]),
            line([0.0, 0.0], [1.0, 0.0]),
            line([1.0, 0.0], [1.0, 1.0]),
            line([1.0, 1.0], [0.0, 1.0]),
        ],
    );
    for eps in [0.1, 0.01, 1e-4] {
        check("run-on", &f, eps, &[[0.0, 1.0]]);
    }
}

/// Two ellipses touching at the origin, semi-axes `a` along u and `b` along v (the lower
/// one, `[a, b]`, the upper one `[a, b2]`): the face is the thin curved triangle right of both,
/// out to the angle `alpha` on each. Its boundary comes into the origin along the upper
/// ellipse heading −u and leaves along the lower one heading +u, a tangent cusp, with the
/// curvature growing away from it (CrankArm.brep faces 29, 30: a cusp between two fillets,
/// each trim one quadratic at ε = 0.1 mm).
fn cusp_face(a: f64, b: f64, b2: f64, alpha: f64) -> Face {
    let (s, c) = alpha.sin_cos();
    let lower = [a * s, -b * (1.0 - c)];
    let upper = [a * s, b2 * (1.0 - c)];
    face(
        [0.0, a * s, lower[1], upper[1]],
        vec![
            cw_ellipse([0.0, -b], a, b, -PI / 2.0, -PI / 2.0 + alpha),
            line(lower, upper),
            cw_ellipse([0.0, b2], a, b2, PI / 2.0 - alpha, PI / 2.0),
        ],
    )
}

#[test]
fn tangent_cusps_keep_their_tangents() {
    for (a, b, b2, alpha) in [(13.0, 4.0, 13.0, 30.0f64), (20.0, 3.0, 6.0, 40.0)] {
        let f = cusp_face(a, b, b2, alpha.to_radians());
        for eps in [0.1, 0.03, 0.01, 1e-3] {
            let t = check("cusp", &f, eps, &[[0.0, 0.0]]);
            // the pieces at the cusp leave it along ±u
            for q in t.loops[0].iter().filter(|q| !q.line) {
                for (end, next) in [(q.p[0], q.p[1]), (q.p[2], q.p[1])] {
                    if end[0].hypot(end[1]) < 1e-12 {
                        assert!(
                            next[1].abs() <= 1e-12 * next[0].abs(),
                            "{a} {b} {b2} ε {eps}: {q:?}"
                        );
                    }
                }
            }
        }
    }
}

/// CrankArm.brep face 29 around its cusp, moved to the origin: a quartic B-spline trim
/// comes in, a sextic one goes back out along the same tangent, curving the other way, and a
/// line closes the loop. At ε = 0.1 mm the quartic is one quadratic whose end tangent was off
/// by 8e-4 rad: the approximations crossed 0.01 mm from the cusp.
fn crank_cusp_face() -> Face {
    let quartic = bspline(
        4,
        vec![
            [3.183092820765, 2.471774179297],
            [2.828570718408, 2.098214208598],
            [2.456498387650, 1.744588286807],
            [2.068538868522, 1.411836737998],
            [1.269047176154, 0.793298214347],
            [0.857864875545, 0.506986208435],
            [0.434334558253, 0.242386446424],
            [0.0, 0.0],
        ],
        vec![0.0, 0.50309607563181, 1.0],
        vec![5, 3, 5],
    );
    let mut sextic = bspline(
        6,
        vec![
            [9.310948878970, 2.200497859278],
            [8.757224298436, 2.225010893328],
            [8.194772085107, 2.228890635160],
            [7.633073649487, 2.210601116107],
            [7.079674184406, 2.170915773197],
            [6.540195862790, 2.111969257885],
            [5.591282061049, 1.974501404640],
            [5.175466446236, 1.901379472611],
            [4.772120971107, 1.818264213671],
            [4.381517647191, 1.726400227426],
            [4.003433868254, 1.626833265664],
            [3.510095593049, 1.483373912355],
            [3.384383159500, 1.445566106337],
            [3.260079288903, 1.406957443667],
            [3.137205061507, 1.367591643120],
            [3.015690901348, 1.327488439772],
            [2.350461280470, 1.101553218810],
            [1.833316243048, 0.901917208808],
            [1.341606478411, 0.690302714729],
            [0.873374952586, 0.468578468141],
            [0.426756763444, 0.238157545431],
            [-0.000000005537, -0.000000006874],
        ],
        vec![
            0.0,
            0.294674815906856,
            0.536015963842083,
            0.619826933433331,
            1.0,
        ],
        vec![7, 5, 5, 5, 7],
    );
    sextic.range = [1.0, 0.0];
    face(
        [0.0, 9.32, 0.0, 2.48],
        vec![
            quartic,
            sextic,
            line(
                [9.310948878970, 2.200497859278],
                [3.183092820765, 2.471774179297],
            ),
        ],
    )
}

#[test]
fn crossing_approximations_at_a_cusp_are_gone() {
    let f = crank_cusp_face();
    for eps in [0.1, 0.05, 0.01, 1e-3] {
        check("CrankArm cusp", &f, eps, &[[0.0, 0.0], [0.01, 0.005]]);
    }
}

/// A 200 mm plate whose top edge is a cubic B-spline with a 3° corner at an interior knot of
/// full multiplicity (face2.brep face 1: degree-10 trims made of C0-joined segments).
fn corner_face() -> Face {
    let k = (3.0f64).to_radians().tan() * 40.0;
    let top = bspline(
        3,
        vec![
            [90.0, 90.0],
            [60.0, 90.0 + k * 0.75],
            [30.0, 90.0 + k * 1.5],
            [10.0, 90.0 + k * 2.0],
            [-30.0, 90.0 + k * 1.0],
            [-60.0, 90.0 + k * 0.4],
            [-90.0, 90.0],
        ],
        vec![0.0, 0.5, 1.0],
        vec![4, 3, 4],
    );
    face(
        [-100.0, 100.0, -100.0, 100.0],
        vec![
            line([-90.0, 90.0], [-90.0, -90.0]),
            line([-90.0, -90.0], [90.0, -90.0]),
            line([90.0, -90.0], [90.0, 90.0]),
            top,
        ],
    )
}

#[test]
fn corners_inside_bsplines_are_junctions() {
    let f = corner_face();
    let corner = f.loops[0].trims[3].curve.point(0.5);
    for eps in [0.1, 0.01, 1e-3] {
        let t = check("corner", &f, eps, &[corner.into()]);
        let at_corner = t.loops[0]
            .iter()
            .filter(|q| (q.p[2][0] - corner[0]).hypot(q.p[2][1] - corner[1]) < 1e-9)
            .count();
        assert_eq!(at_corner, 1, "ε {eps}: no junction at the corner");
    }
}
