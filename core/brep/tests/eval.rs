//! Surface and curve evaluation against hand-computed values and finite differences.

use serde_json::json;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_6, PI, SQRT_2};
use tessd_brep::bspline::KnotVector;
use tessd_brep::{Curve2, Curve3, DVec3, Surface};

fn surface(v: serde_json::Value) -> Surface {
    serde_json::from_value(v).unwrap()
}

fn close3(a: impl Into<[f64; 3]>, b: impl Into<[f64; 3]>, tol: f64) -> bool {
    let (a, b) = (a.into(), b.into());
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

#[track_caller]
fn assert_close3(a: impl Into<[f64; 3]>, b: impl Into<[f64; 3]>, tol: f64) {
    let (a, b) = (a.into(), b.into());
    assert!(close3(a, b, tol), "{a:?} != {b:?} (tol {tol})");
}

/// A frame that is not the world's, so axis mix-ups show: x = (0,1,0), y = (0,0,1), so
/// z = x × y = (1,0,0); origin (1,2,3).
fn frame() -> serde_json::Value {
    json!({"origin": [1, 2, 3], "x_dir": [0, 1, 0], "y_dir": [0, 0, 1]})
}

fn with_frame(mut extra: serde_json::Value) -> Surface {
    let f = frame();
    for k in ["origin", "x_dir", "y_dir"] {
        extra[k] = f[k].clone();
    }
    surface(extra)
}

#[test]
fn cylinder_point() {
    let s = with_frame(json!({"type": "cylinder", "radius": 2}));
    // u = π/2: the y axis (world z), times r = 2; v = 5 along z (world x).
    assert_close3(s.point(FRAC_PI_2, 5.0), [1.0 + 5.0, 2.0, 3.0 + 2.0], 1e-12);
    // u = 0: the x axis (world y).
    assert_close3(s.point(0.0, -1.0), [0.0, 4.0, 3.0], 1e-12);
}

#[test]
fn cone_point() {
    let s = with_frame(json!({"type": "cone", "radius": 1, "semi_angle": FRAC_PI_6}));
    // u = 0, v = 2: radius 1 + 2 sin 30° = 2 along x (world y), height 2 cos 30° = √3 along z.
    assert_close3(
        s.point(0.0, 2.0),
        [1.0 + 3f64.sqrt(), 2.0 + 2.0, 3.0],
        1e-12,
    );
    // u = π: radius 1 − 0.5 = 0.5 along −x at v = −1; height −cos 30°.
    assert_close3(
        s.point(PI, -1.0),
        [1.0 - 3f64.sqrt() / 2.0, 2.0 - 0.5, 3.0],
        1e-12,
    );
}

#[test]
fn sphere_point() {
    let s = with_frame(json!({"type": "sphere", "radius": 3}));
    // u = π, v = π/4: 3 cos 45° along −x (world −y), 3 sin 45° along z (world x).
    let h = 3.0 / SQRT_2;
    assert_close3(s.point(PI, FRAC_PI_4), [1.0 + h, 2.0 - h, 3.0], 1e-12);
    // The north pole.
    assert_close3(s.point(1.234, FRAC_PI_2), [4.0, 2.0, 3.0], 1e-12);
    // Outward normal there, though ∂S/∂u vanishes.
    assert_close3(s.normal(1.234, FRAC_PI_2).unwrap(), [1.0, 0.0, 0.0], 1e-12);
}

#[test]
fn torus_point() {
    let s = with_frame(json!({"type": "torus", "major_radius": 5, "minor_radius": 1}));
    // u = π/2, v = π: (5 − 1) along y (world z).
    assert_close3(s.point(FRAC_PI_2, PI), [1.0, 2.0, 3.0 + 4.0], 1e-12);
    // u = 0, v = π/2: 5 along x (world y), 1 along z (world x).
    assert_close3(s.point(0.0, FRAC_PI_2), [2.0, 7.0, 3.0], 1e-12);
}

#[test]
fn plane_point_and_reversed_face_normal() {
    let s = with_frame(json!({"type": "plane"}));
    assert_close3(s.point(2.0, -1.0), [1.0, 4.0, 2.0], 1e-15);
    assert_close3(s.normal(0.3, 0.4).unwrap(), [1.0, 0.0, 0.0], 1e-15);
    let face = |reversed: bool| tessd_brep::Face {
        id: 0,
        reversed,
        surface: s.clone(),
        bounds: [0.0, 1.0, 0.0, 1.0],
        loops: vec![],
    };
    assert_close3(
        face(false).normal(0.5, 0.5).unwrap(),
        [1.0, 0.0, 0.0],
        1e-15,
    );
    assert_close3(
        face(true).normal(0.5, 0.5).unwrap(),
        [-1.0, 0.0, 0.0],
        1e-15,
    );
}

/// A rational quadratic B-spline: a quarter of the unit circle in the (x, y) plane at u, a
/// straight line in z at v.
fn rational_bspline_surface() -> Surface {
    let w = FRAC_PI_4.cos();
    surface(json!({
        "type": "bspline", "degree_u": 2, "degree_v": 1,
        "poles": [[[1, 0, 0], [1, 0, 1]], [[1, 1, 0], [1, 1, 1]], [[0, 1, 0], [0, 1, 1]]],
        "weights": [[1, 1], [w, w], [1, 1]],
        "knots_u": [0, 1], "mults_u": [3, 3], "knots_v": [0, 1], "mults_v": [2, 2],
        "periodic_u": false, "periodic_v": false
    }))
}

/// A cubic B-spline space curve with an interior double knot.
fn space_bspline() -> serde_json::Value {
    json!({"type": "bspline", "degree": 3,
           "poles": [[2, 0, 0], [3, 0, 1], [2.5, 0, 2], [4, 0, 3], [3, 0, 4], [2, 0, 5]],
           "weights": [1, 2, 1, 0.5, 1, 1], "knots": [0, 0.4, 1], "mults": [4, 2, 4]})
}

#[test]
fn partial_derivatives_match_central_differences() {
    let surfaces = vec![
        ("plane", with_frame(json!({"type": "plane"})), (0.3, -0.7)),
        (
            "cylinder",
            with_frame(json!({"type": "cylinder", "radius": 2})),
            (0.7, 1.3),
        ),
        (
            "cone",
            with_frame(json!({"type": "cone", "radius": 1, "semi_angle": 0.4})),
            (2.1, 0.8),
        ),
        (
            "sphere",
            with_frame(json!({"type": "sphere", "radius": 3})),
            (4.0, 0.6),
        ),
        (
            "torus",
            with_frame(json!({"type": "torus", "major_radius": 5, "minor_radius": 1.5})),
            (1.1, 2.5),
        ),
        (
            "revolution of a circle",
            surface(json!({"type": "revolution", "axis_origin": [0, 0, 1],
                "axis_dir": [0.6, 0, 0.8],
                "curve": {"type": "circle", "center": [3, 0, 0], "x_dir": [1, 0, 0],
                          "y_dir": [0, 0, 1], "radius": 1}})),
            (0.9, 0.4),
        ),
        (
            "revolution of a B-spline",
            surface(json!({"type": "revolution", "axis_origin": [0, 0, 0],
                "axis_dir": [0, 0, 1], "curve": space_bspline()})),
            (2.0, 0.55),
        ),
        (
            "extrusion of an ellipse",
            surface(json!({"type": "extrusion", "direction": [0, 0.6, 0.8],
                "curve": {"type": "ellipse", "center": [0, 0, 0], "x_dir": [1, 0, 0],
                          "y_dir": [0, 1, 0], "major_radius": 3, "minor_radius": 1}})),
            (0.5, 2.0),
        ),
        (
            "extrusion of a B-spline",
            surface(json!({"type": "extrusion", "direction": [1, 0, 0],
                "curve": space_bspline()})),
            (0.3, -1.0),
        ),
        (
            "rational B-spline",
            rational_bspline_surface(),
            (0.37, 0.61),
        ),
    ];
    let h = 1e-6;
    for (name, s, (u, v)) in surfaces {
        let e = s.eval(u, v);
        let fd_u = central(|t| s.point(t, v), u, h);
        let fd_v = central(|t| s.point(u, t), v, h);
        for (what, exact, fd) in [("∂u", e.du, fd_u), ("∂v", e.dv, fd_v)] {
            let scale = exact.abs().max_element().max(1.0);
            assert!(
                close3(exact, fd, 1e-6 * scale),
                "{name}: {what} = {exact:?}, finite differences {fd:?}"
            );
        }
        assert!(e.normal().is_some(), "{name}: no normal at ({u}, {v})");
    }
}

fn central(f: impl Fn(f64) -> DVec3, t: f64, h: f64) -> [f64; 3] {
    let (a, b) = (f(t + h), f(t - h));
    [0, 1, 2].map(|i| (a[i] - b[i]) / (2.0 * h))
}

#[test]
fn rational_bspline_surface_is_a_cylinder() {
    let s = rational_bspline_surface();
    for i in 0..=20 {
        for j in 0..=4 {
            let (u, v) = (i as f64 / 20.0, j as f64 / 4.0);
            let p = s.point(u, v);
            assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-12, "{p:?}");
            assert!((p[2] - v).abs() < 1e-12, "{p:?}");
        }
    }
}

/// The classic 9-pole rational quadratic full circle (radius 2, centre (1, −1)).
fn rational_circle() -> Curve2 {
    let w = SQRT_2 / 2.0;
    let (cx, cy, r) = (1.0, -1.0, 2.0);
    let corners = [
        [1, 0],
        [1, 1],
        [0, 1],
        [-1, 1],
        [-1, 0],
        [-1, -1],
        [0, -1],
        [1, -1],
        [1, 0],
    ];
    let poles: Vec<[f64; 2]> = corners
        .iter()
        .map(|[x, y]| [cx + r * *x as f64, cy + r * *y as f64])
        .collect();
    serde_json::from_value(json!({
        "type": "bspline", "degree": 2, "poles": poles,
        "weights": [1, w, 1, w, 1, w, 1, w, 1],
        "knots": [0, 0.25, 0.5, 0.75, 1], "mults": [3, 2, 2, 2, 3], "periodic": false
    }))
    .unwrap()
}

#[test]
fn rational_quadratic_circle_lies_on_the_circle() {
    let c = rational_circle();
    for k in 0..=1000 {
        let t = k as f64 / 1000.0;
        let (p, d) = c.eval(t);
        let (x, y) = (p[0] - 1.0, p[1] + 1.0);
        assert!((x.hypot(y) - 2.0).abs() < 1e-12, "t = {t}: {p:?}");
        // The tangent is perpendicular to the radius.
        assert!(
            (x * d[0] + y * d[1]).abs() < 1e-9 * d[0].hypot(d[1]),
            "t = {t}"
        );
    }
    // Quarter knots land on the axes.
    let p = c.point(0.25);
    assert!(
        (p[0] - 1.0).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15,
        "{p:?}"
    );
}

#[test]
fn curve_derivatives_match_central_differences() {
    let curves: Vec<Curve2> = vec![
        rational_circle(),
        serde_json::from_value(
            json!({"type": "ellipse", "center": [1, 2], "x_dir": [0.6, 0.8],
            "y_dir": [-0.8, 0.6], "major_radius": 3, "minor_radius": 1}),
        )
        .unwrap(),
        serde_json::from_value(json!({"type": "circle", "center": [1, 2], "x_dir": [0, 1],
            "y_dir": [1, 0], "radius": 0.5}))
        .unwrap(),
        serde_json::from_value(json!({"type": "line", "origin": [1, 2], "dir": [0.6, 0.8]}))
            .unwrap(),
    ];
    let h = 1e-6;
    for c in &curves {
        for t in [0.1, 0.3, 0.62, 0.9] {
            let d = c.eval(t).1;
            let (a, b) = (c.point(t + h), c.point(t - h));
            for i in 0..2 {
                let fd = (a[i] - b[i]) / (2.0 * h);
                assert!(
                    (fd - d[i]).abs() <= 1e-6 * d[i].abs().max(1.0),
                    "{c:?} at {t}"
                );
            }
        }
    }
    let c3: Curve3 = serde_json::from_value(space_bspline()).unwrap();
    for t in [0.05, 0.39, 0.41, 0.8] {
        let d = c3.eval(t).1;
        let fd = central(|s| c3.point(s), t, h);
        assert!(close3(d, fd, 1e-6 * d.abs().max_element().max(1.0)));
    }
}

#[test]
fn basis_functions_partition_unity() {
    let vectors = [
        KnotVector::new(3, &[0.0, 1.0, 2.5, 3.0, 5.0], &[4, 1, 2, 3, 4], false).unwrap(),
        KnotVector::new(2, &[0.0, 1.0], &[3, 3], false).unwrap(),
        KnotVector::new(1, &[0.0, 0.5, 2.0], &[2, 1, 2], false).unwrap(),
        KnotVector::new(3, &[0.0, 1.0, 2.0, 3.0, 4.0, 5.0], &[1; 6], true).unwrap(),
        KnotVector::new(4, &[-1.0, 0.0, 0.5, 2.0], &[2, 3, 1, 2], true).unwrap(),
    ];
    for kv in &vectors {
        let [a, b] = kv.domain();
        for k in 0..=200 {
            let t = a + (b - a) * k as f64 / 200.0;
            let basis = kv.basis(t);
            let sum: f64 = basis.values[..basis.count].iter().sum();
            let dsum: f64 = basis.derivs[..basis.count].iter().sum();
            assert!((sum - 1.0).abs() < 1e-14, "{kv:?} at {t}: Σ N = {sum}");
            assert!(dsum.abs() < 1e-9, "{kv:?} at {t}: Σ N' = {dsum}");
            assert!(basis.values[..basis.count].iter().all(|&n| n >= -1e-15));
        }
    }
}

fn periodic_cubic() -> Curve3 {
    serde_json::from_value(json!({
        "type": "bspline", "degree": 3,
        "poles": [[0, 0, 0], [4, 0, 0], [6, 3, 1], [4, 6, 0], [0, 6, 2], [-2, 3, 0]],
        "weights": null, "knots": [0, 1, 2, 3, 4, 5, 6], "mults": [1, 1, 1, 1, 1, 1, 1],
        "periodic": true
    }))
    .unwrap()
}

#[test]
fn periodic_bspline_curve_closes() {
    let c = periodic_cubic();
    let (p0, d0) = c.eval(0.0);
    let (p1, d1) = c.eval(6.0);
    assert_close3(p0, p1, 1e-12);
    assert_close3(d0, d1, 1e-12);
    // Uniform cubic: at the first knot, (P0 + 4 P1 + P2) / 6 (OCP's pole alignment).
    assert_close3(p0, [(0.0 + 16.0 + 6.0) / 6.0, 3.0 / 6.0, 1.0 / 6.0], 1e-12);
    // Continuity across the seam and periodicity beyond it.
    assert_close3(c.point(-1e-9), c.point(1e-9), 1e-8);
    for t in [0.3, 2.7, 5.9] {
        assert_close3(c.point(t), c.point(t + 6.0), 1e-12);
        assert_close3(c.point(t), c.point(t - 12.0), 1e-12);
    }
    // A rational periodic curve with a double knot still closes.
    let c: Curve2 = serde_json::from_value(json!({
        "type": "bspline", "degree": 2, "poles": [[1, 0], [1, 1], [-1, 1], [-1, -1], [1, -1]],
        "weights": [1, 0.5, 2, 1, 0.7], "knots": [0, 1, 2, 3], "mults": [2, 1, 2, 2],
        "periodic": true
    }))
    .unwrap();
    let (a, b) = (c.eval(0.0), c.eval(3.0));
    assert!((a.0[0] - b.0[0]).abs() < 1e-12 && (a.0[1] - b.0[1]).abs() < 1e-12);
    // Double knot: the curve passes through the pole at its start.
    assert!(
        (a.0[0] - 1.0).abs() < 1e-12 && a.0[1].abs() < 1e-12,
        "{a:?}"
    );
}

/// Rows of poles grown from each pole of [`periodic_cubic`] by `row`, with its knots and
/// multiplicities (u of a surface periodic in u).
fn periodic_rows(row: impl Fn(DVec3) -> Vec<DVec3>) -> (Vec<Vec<DVec3>>, Vec<f64>, Vec<u32>) {
    let Curve3::Bspline(b) = periodic_cubic() else {
        unreachable!()
    };
    (b.poles.iter().map(|&p| row(p)).collect(), b.knots, b.mults)
}

#[test]
fn periodic_surface_wraps() {
    // A torus-like periodic B-spline surface in u: the same rows as the curve above.
    let c = periodic_cubic();
    let (poles, knots, mults) = periodic_rows(|p| vec![p, DVec3::new(p[0], p[1], p[2] + 1.0)]);
    let s = surface(json!({
        "type": "bspline", "degree_u": 3, "degree_v": 1, "poles": poles, "weights": null,
        "knots_u": knots, "mults_u": mults, "knots_v": [0, 1], "mults_v": [2, 2],
        "periodic_u": true, "periodic_v": false
    }));
    for t in [0.0, 1.5, 4.2] {
        let p = s.point(t, 0.25);
        let q = c.point(t);
        assert_close3(p, [q[0], q[1], q[2] + 0.25], 1e-12);
        assert_close3(s.point(t + 6.0, 0.25), p, 1e-12);
    }
}

/// Values printed by OCP 7.9.3 (`Geom_BSplineCurve::D1`, cadquery-ocp) for the same periodic
/// curves: the pole alignment of periodic B-splines is OCP's.
#[test]
fn periodic_bsplines_match_ocp() {
    let c = periodic_cubic();
    for (t, p, d) in [
        (
            0.0,
            [3.6666666666666665, 0.5, 0.16666666666666669],
            [3.0, 1.5, 0.5],
        ),
        (
            0.3,
            [4.467666666666666, 1.0715, 0.34816666666666674],
            [2.31, 2.265, 0.665],
        ),
        (
            2.7,
            [1.305333333333333, 5.815, 1.1848333333333334],
            [-3.42, -0.6, 0.885],
        ),
        (5.9, [3.3573333333333353, 0.365, 0.1215], [3.18, 1.2, 0.405]),
    ] {
        let (q, e) = c.eval(t);
        assert_close3(q, p, 1e-12);
        assert_close3(e, d, 1e-12);
    }
    let c: Curve2 = serde_json::from_value(json!({
        "type": "bspline", "degree": 2, "poles": [[1, 0], [1, 1], [-1, 1], [-1, -1], [1, -1]],
        "weights": [1, 0.5, 2, 1, 0.7], "knots": [0, 1, 2, 3], "mults": [2, 1, 2, 2],
        "periodic": true
    }))
    .unwrap();
    for (t, p, d) in [
        (0.4, [0.6, 0.55], [-2.0, 1.5]),
        (
            1.3,
            [-0.8411669367909239, 0.8833063209076175],
            [-0.500145788294382, -0.7439143237655935],
        ),
        (
            2.2,
            [-0.41592920353982255, -0.9557522123893806],
            [2.9759573968204247, 0.4600986764821055],
        ),
        (
            2.9,
            [0.9788583509513741, -0.14376321353065552],
            [0.43356024476040256, 1.4682942309669287],
        ),
    ] {
        let (q, e) = c.eval(t);
        for i in 0..2 {
            assert!(
                (q[i] - p[i]).abs() < 1e-12 && (e[i] - d[i]).abs() < 1e-12,
                "t = {t}: {q:?} {e:?}"
            );
        }
    }
}

/// Values printed by OCP 7.9.3 (`Geom_SurfaceOfRevolution::Value`, `Geom_ConicalSurface::Value`)
/// for the same surfaces: rotation sense and the cone's parametrisation are OCP's.
#[test]
fn revolution_and_cone_match_ocp() {
    let s = surface(json!({"type": "revolution", "axis_origin": [0, 0, 1],
        "axis_dir": [0.6, 0, 0.8],
        "curve": {"type": "line", "origin": [3, 0, 0], "dir": [0, 0.6, 0.8]}}));
    assert_close3(
        s.point(0.9, 0.4),
        [1.9995858660747436, 2.348768354618933, 1.0703106004439422],
        1e-12,
    );
    let s = with_frame(json!({"type": "cone", "radius": 1, "semi_angle": 0.4}));
    assert_close3(
        s.point(2.1, 0.8),
        [1.7368487952023082, 1.3378768288607374, 4.132129015149437],
        1e-12,
    );
}

/// `Surface::point` takes a derivative-free path for B-splines: it must give `eval`'s point.
#[test]
fn bspline_point_path_matches_eval() {
    let (poles, knots, mults) = periodic_rows(|p| {
        vec![
            p,
            DVec3::new(p[0] + 0.5, p[1], p[2] + 1.0),
            DVec3::new(p[0], p[1] + 0.3, p[2] + 2.0),
        ]
    });
    let weights: Vec<Vec<f64>> = (0..poles.len())
        .map(|i| vec![1.0, 0.5 + 0.1 * i as f64, 2.0])
        .collect();
    let periodic = surface(json!({
        "type": "bspline", "degree_u": 3, "degree_v": 2, "poles": poles, "weights": weights,
        "knots_u": knots, "mults_u": mults, "knots_v": [0, 1], "mults_v": [3, 3],
        "periodic_u": true, "periodic_v": false
    }));
    for s in [periodic, rational_bspline_surface()] {
        for (u, v) in [
            (0.0, 0.0),
            (0.37, 0.61),
            (1.5, 0.25),
            (4.2, 0.999),
            (-0.3, 1.0),
        ] {
            let (p, e) = (s.point(u, v), s.eval(u, v).point);
            let scale = e.abs().max_element().max(1.0);
            assert_close3(p, e, 1e-14 * scale);
        }
    }
}
