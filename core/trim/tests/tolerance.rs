//! The (u, v) tolerance of section 3.1 (`tolerance.rs`): tight — the Jacobian's largest
//! singular value, not the hypotenuse of the two derivative bounds — and still a bound:
//! every (u, v) displacement of length ε_uv moves the surface point by at most ε.

mod common;

use common::{Rng, plane};
use tessd_brep::{BSplineSurface, Face, Frame, Surface};
use tessd_trim::tolerance::{SAFETY, largest_singular_value, uv_tolerance};

fn frame() -> Frame {
    let (c, s) = (0.6f64, 0.8f64);
    Frame {
        origin: [1.0, -2.0, 0.5],
        x_dir: [c, s, 0.0],
        y_dir: [0.0, 0.0, 1.0],
    }
}

fn face(surface: Surface, bounds: [f64; 4]) -> Face {
    Face {
        id: 0,
        reversed: false,
        surface,
        bounds,
        loops: Vec::new(),
    }
}

/// A bicubic patch with uneven speeds and a strong twist (Su and Sv far from orthogonal).
fn sheared_bspline() -> Surface {
    let poles: Vec<Vec<[f64; 3]>> = (0..4)
        .map(|i| {
            (0..4)
                .map(|j| {
                    let (x, y) = (i as f64, j as f64);
                    [
                        3.0 * x + 2.5 * y,
                        0.4 * x * y + y,
                        (x - 1.5) * (y - 1.5) * 0.8,
                    ]
                })
                .collect()
        })
        .collect();
    Surface::Bspline(BSplineSurface {
        degree_u: 3,
        degree_v: 3,
        poles,
        weights: None,
        knots_u: vec![0.0, 1.0],
        mults_u: vec![4, 4],
        knots_v: vec![0.0, 2.0],
        mults_v: vec![4, 4],
        periodic_u: false,
        periodic_v: false,
        cache: Default::default(),
    })
}

/// The surfaces of the check, with bounds.
fn surfaces() -> Vec<(&'static str, Face)> {
    vec![
        ("plane", face(plane(), [-3.0, 5.0, 0.0, 2.0])),
        (
            "cylinder",
            face(
                Surface::Cylinder {
                    frame: frame(),
                    radius: 2.5,
                },
                [0.0, 6.0, -1.0, 4.0],
            ),
        ),
        (
            "cone",
            face(
                Surface::Cone {
                    frame: frame(),
                    radius: 1.0,
                    semi_angle: 0.5,
                },
                [0.0, 6.2, 0.0, 5.0],
            ),
        ),
        (
            "sphere",
            face(
                Surface::Sphere {
                    frame: frame(),
                    radius: 4.0,
                },
                [0.0, 6.2, -1.5, 1.5],
            ),
        ),
        (
            "torus",
            face(
                Surface::Torus {
                    frame: frame(),
                    major_radius: 5.0,
                    minor_radius: 1.5,
                },
                [0.0, 6.2, 0.0, 6.2],
            ),
        ),
        ("bspline", face(sheared_bspline(), [0.0, 1.0, 0.0, 2.0])),
    ]
}

/// The old bound, `ε / √((1.25 max|Su|)² + (1.25 max|Sv|)²)`, was ε / 1.77 on a unit-speed
/// plane; the Jacobian's largest singular value (1 there) gives ε / 1.25.
#[test]
fn a_unit_plane_gets_eps_over_the_safety_factor() {
    let eps = 0.01;
    let t = uv_tolerance(&face(plane(), [0.0, 3.0, 0.0, 2.0]), eps);
    assert!(
        (t.eps_uv - eps / SAFETY).abs() < 1e-12 * eps,
        "ε_uv = {} (ε / {:.4})",
        t.eps_uv,
        eps / t.eps_uv
    );
    // A cylinder of radius 2 with a unit-speed axis: σ = max(r, 1) = 2.
    let cyl = Surface::Cylinder {
        frame: frame(),
        radius: 2.0,
    };
    let t = uv_tolerance(&face(cyl, [0.0, 3.0, 0.0, 2.0]), eps);
    assert!(
        (t.eps_uv - eps / (2.0 * SAFETY)).abs() < 1e-12 * eps,
        "{t:?}"
    );
}

#[test]
fn the_singular_value_bounds_every_direction() {
    let mut rng = Rng(5);
    for _ in 0..10_000 {
        let mut r = || 4.0 * rng.next() - 2.0;
        let (a, b) = ([r(), r(), r()], [r(), r(), r()]);
        let s = largest_singular_value(a, b);
        let (c, d) = (r(), r());
        let n = c.hypot(d);
        let j = [0, 1, 2].map(|k| a[k] * c + b[k] * d);
        let stretched = (j[0] * j[0] + j[1] * j[1] + j[2] * j[2]).sqrt();
        assert!(stretched <= s * n * (1.0 + 1e-12), "{a:?} {b:?} {s}");
    }
}

/// Random points and directions: a (u, v) step of length ε_uv never moves the surface point
/// by more than ε (paper 000, section 3.1: the parameter-space error computed from ε).
#[test]
fn eps_uv_steps_stay_within_eps_in_the_world() {
    let mut rng = Rng(42);
    for (name, f) in surfaces() {
        for eps in [0.1, 0.01, 1e-4] {
            let t = uv_tolerance(&f, eps);
            let [u0, u1, v0, v1] = f.bounds;
            let mut worst: f64 = 0.0;
            for _ in 0..20_000 {
                let u = u0 + t.eps_uv + (u1 - u0 - 2.0 * t.eps_uv) * rng.next();
                let v = v0 + t.eps_uv + (v1 - v0 - 2.0 * t.eps_uv) * rng.next();
                let a = std::f64::consts::TAU * rng.next();
                let (du, dv) = (t.eps_uv * a.cos(), t.eps_uv * a.sin());
                let p = f.surface.eval(u, v).point;
                let q = f.surface.eval(u + du, v + dv).point;
                let d =
                    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                worst = worst.max(d / eps);
            }
            assert!(worst <= 1.0, "{name} at ε {eps}: a step moved {worst} ε");
            // Tight: the largest step found is no less than 70 % of ε (1 / SAFETY = 80 % is
            // where the bound sits where σ is attained on the grid).
            assert!(worst >= 0.7, "{name} at ε {eps}: at most {worst} ε: loose");
        }
    }
}
