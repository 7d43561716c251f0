//! Step 6a: curve records into exchange-format curves, as the Python exporters convert them
//! (ocp.py `_curve_on_range`): the same curve and parameter wherever the format has the type.
//!
//! Trimmed curves become their basis (same parameter), Béziers were read as their identical
//! B-spline, a parabola becomes the exact degree-2 B-spline of its range (it is polynomial in
//! its own parameter), a B-spline's range is clamped to its knot span (OCCT's ranges overshoot
//! it by rounding). A hyperbola becomes its exact rational B-spline, whose parameter equals the
//! hyperbola's at its knots (the exporters approximate it to 1e-9 on the very parameter
//! instead; no rational curve can). A periodic B-spline trimmed across its knot span becomes its
//! non-periodic segment on the range (as OCCT's converter cuts it for the exporters). Offset
//! curves are refused. Also here: placing 3D curves, mirroring pcurves for indirect frames, a
//! pcurve's (u, v) box, and the projection OCCT makes for an edge on a plane that stores no
//! pcurve.

use std::f64::consts::{PI, TAU};

use super::geometry::RawCurve;
use super::locations::{Trsf, normalized};
use super::segment::{periodic_segment, piece_poles};
use crate::model::{BSplineCurve, Curve, Curve2, Curve3, Frame};
use crate::vector::Point;
use crate::vector::{Point2, Point3};

/// `(curve, t0, t1)`: `raw` on `[t0, t1]` as a format curve with the same parameter, or why it
/// has none.
pub(crate) fn on_range<P: Point>(
    raw: &RawCurve<P>,
    t0: f64,
    t1: f64,
) -> Result<(Curve<P>, f64, f64), String> {
    let raw = basis(raw);
    if let Some(c) = exact(raw) {
        if let Curve::Bspline(b) = &c {
            let (lo, hi) = (b.knots[0], b.knots[b.knots.len() - 1]);
            let slack = 1e-12 * (hi - lo);
            if b.periodic && !(t0 >= lo - slack && t1 <= hi + slack) {
                // Its non-periodic segment on the range, same parameter.
                let seg = periodic_segment(b, t0, t1).ok_or_else(|| {
                    format!("a periodic B-spline on the range [{t0}, {t1}], not cut")
                })?;
                return Ok((Curve::Bspline(seg), t0, t1));
            }
            return Ok((c, t0.max(lo), t1.min(hi)));
        }
        return Ok((c, t0, t1));
    }
    match raw {
        RawCurve::Parabola {
            origin,
            x,
            y,
            focal,
        } => {
            if t1 <= t0 {
                return Err(format!("a parabola on the empty range [{t0}, {t1}]"));
            }
            Ok((parabola(*origin, *x, *y, *focal, t0, t1), t0, t1))
        }
        RawCurve::Hyperbola {
            center,
            x,
            y,
            major,
            minor,
        } => {
            if t1 <= t0 {
                return Err(format!("a hyperbola on the empty range [{t0}, {t1}]"));
            }
            let c = hyperbola(*center, *x, *y, *major, *minor, t0, t1)
                .ok_or_else(|| format!("a hyperbola on the range [{t0}, {t1}], too long"))?;
            Ok((c, t0, t1))
        }
        _ => Err("an offset curve".into()),
    }
}

/// The basis of a (nested) trimmed curve, same parameter.
fn basis<P>(raw: &RawCurve<P>) -> &RawCurve<P> {
    let mut raw = raw;
    while let RawCurve::Trimmed { basis, .. } = raw {
        raw = basis;
    }
    raw
}

/// A line, circle, ellipse or B-spline record as it is (ocp.py `_exact_curve`); `None` for the
/// other types.
fn exact<P: Point>(raw: &RawCurve<P>) -> Option<Curve<P>> {
    Some(match raw {
        RawCurve::Line { origin, dir } => Curve::Line {
            origin: *origin,
            dir: *dir,
        },
        RawCurve::Circle {
            center,
            x,
            y,
            radius,
        } => Curve::Circle {
            center: *center,
            x_dir: *x,
            y_dir: *y,
            radius: *radius,
        },
        RawCurve::Ellipse {
            center,
            x,
            y,
            major,
            minor,
        } => Curve::Ellipse {
            center: *center,
            x_dir: *x,
            y_dir: *y,
            major_radius: *major,
            minor_radius: *minor,
        },
        RawCurve::Bspline(b) => Curve::Bspline(b.clone()),
        _ => return None,
    })
}

/// The exact B-spline of a parabola `O + t²/(4f)·X + t·Y` on `[t0, t1]`, same parameter: the
/// quadratic Bézier of the range (OCCT's converter writes the same poles, in the parabola's
/// own frame first).
fn parabola<P: Point>(o: P, x: P, y: P, f: f64, t0: f64, t1: f64) -> Curve<P> {
    // Local (along X, along Y) coordinates of the poles; f = 0 is OCCT's degenerate case,
    // the line O + t·X.
    let local = if f > 0.0 {
        [
            (t0 * t0 / (4.0 * f), t0),
            (t0 * t1 / (4.0 * f), (t0 + t1) / 2.0),
            (t1 * t1 / (4.0 * f), t1),
        ]
    } else {
        [(t0, 0.0), ((t0 + t1) / 2.0, 0.0), (t1, 0.0)]
    };
    Curve::Bspline(BSplineCurve {
        degree: 2,
        poles: local.iter().map(|&(a, b)| o + x * a + y * b).collect(),
        weights: None,
        knots: vec![t0, t1],
        mults: vec![3, 3],
        periodic: false,
        cache: Default::default(),
    })
}

/// A hyperbola arc's pieces are at most this long in its parameter.
const HYPERBOLA_PIECE: f64 = 0.25;

/// The most pieces a hyperbola arc is cut into (beyond, its coordinates overflow anyway).
const HYPERBOLA_PIECES: f64 = 1024.0;

/// A hyperbola `C + a cosh t·X + b sinh t·Y` on `[t0, t1]` as an exact rational quadratic
/// B-spline: one conic piece per stretch of at most [`HYPERBOLA_PIECE`], each the rational
/// Bézier through C(ta), the meeting point of the tangents, C(tb) with middle weight
/// cosh((tb − ta)/2). Its knots are the hyperbola's own parameters, so it agrees with the
/// hyperbola's parameter at every knot and at both ends (the range is unchanged); in between
/// the parameters differ slightly (no rational curve follows cosh t at the same parameter),
/// which the format allows (docs/brep-format.md, Trim). A 2D hyperbola and the 3D one it is
/// the pcurve of become curves of equal parameter, being converted with the same knots and
/// weights.
fn hyperbola<P: Point>(o: P, x: P, y: P, a: f64, b: f64, t0: f64, t1: f64) -> Option<Curve<P>> {
    let n = ((t1 - t0) / HYPERBOLA_PIECE).ceil().max(1.0);
    if n.is_nan() || n > HYPERBOLA_PIECES {
        return None;
    }
    let n = n as usize;
    let at = |(u, v): (f64, f64)| o + x * (a * u) + y * (b * v);
    let knots: Vec<f64> = (0..=n)
        .map(|i| {
            if i == n {
                t1
            } else {
                t0 + (t1 - t0) * i as f64 / n as f64
            }
        })
        .collect();
    let mut poles = vec![at((t0.cosh(), t0.sinh()))];
    let mut weights = vec![1.0];
    for k in knots.windows(2) {
        let (m, h) = ((k[0] + k[1]) / 2.0, (k[1] - k[0]) / 2.0);
        poles.push(at((m.cosh() / h.cosh(), m.sinh() / h.cosh())));
        weights.push(h.cosh());
        poles.push(at((k[1].cosh(), k[1].sinh())));
        weights.push(1.0);
    }
    if !poles.iter().all(|p| Point::is_finite(*p)) {
        return None;
    }
    let mut mults = vec![2; n + 1];
    (mults[0], mults[n]) = (3, 3);
    Some(Curve::Bspline(BSplineCurve {
        degree: 2,
        poles,
        weights: Some(weights),
        knots,
        mults,
        periodic: false,
        cache: Default::default(),
    }))
}

/// The meridian or profile of a surface of revolution or extrusion: ocp.py's `_exact_curve`
/// (trimmed curves unwrapped; lines, circles, ellipses and B-splines only).
pub(crate) fn exact3(raw: &RawCurve<Point3>) -> Option<Curve3> {
    exact(basis(raw))
}

/// The parameter range a curve record is defined on, when bounded (a trimmed curve's trim, a
/// closed conic's period, a B-spline's knots): what `Geom_Curve::First/LastParameter` give.
pub(crate) fn natural_range(raw: &RawCurve<Point3>) -> Option<[f64; 2]> {
    match raw {
        RawCurve::Trimmed { u1, u2, .. } => Some([*u1, *u2]),
        RawCurve::Circle { .. } | RawCurve::Ellipse { .. } => Some([0.0, TAU]),
        RawCurve::Bspline(b) => Some([b.knots[0], b.knots[b.knots.len() - 1]]),
        _ => None,
    }
}

/// A 3D curve placed by a rigid motion.
pub(crate) fn transformed(c: Curve3, t: &Trsf) -> Curve3 {
    match c {
        Curve::Line { origin, dir } => Curve::Line {
            origin: t.point(origin),
            dir: t.dir(dir),
        },
        Curve::Circle {
            center,
            x_dir,
            y_dir,
            radius,
        } => Curve::Circle {
            center: t.point(center),
            x_dir: t.dir(x_dir),
            y_dir: t.dir(y_dir),
            radius,
        },
        Curve::Ellipse {
            center,
            x_dir,
            y_dir,
            major_radius,
            minor_radius,
        } => Curve::Ellipse {
            center: t.point(center),
            x_dir: t.dir(x_dir),
            y_dir: t.dir(y_dir),
            major_radius,
            minor_radius,
        },
        Curve::Bspline(mut b) => {
            b.poles.iter_mut().for_each(|p| *p = t.point(*p));
            Curve::Bspline(b)
        }
    }
}

/// A pcurve mirrored about u = π (u → 2π − u), for faces on an indirect frame: every type maps
/// to itself with the same parameter (points and both axes mirrored, as OCCT's
/// `Geom2d_Curve::Mirrored`).
pub(crate) fn mirrored(c: Curve2) -> Curve2 {
    let p = |q: Point2| Point2::new(2.0 * PI - q[0], q[1]);
    let d = |q: Point2| Point2::new(-q[0], q[1]);
    match c {
        Curve::Line { origin, dir } => Curve::Line {
            origin: p(origin),
            dir: d(dir),
        },
        Curve::Circle {
            center,
            x_dir,
            y_dir,
            radius,
        } => Curve::Circle {
            center: p(center),
            x_dir: d(x_dir),
            y_dir: d(y_dir),
            radius,
        },
        Curve::Ellipse {
            center,
            x_dir,
            y_dir,
            major_radius,
            minor_radius,
        } => Curve::Ellipse {
            center: p(center),
            x_dir: d(x_dir),
            y_dir: d(y_dir),
            major_radius,
            minor_radius,
        },
        Curve::Bspline(mut b) => {
            b.poles.iter_mut().for_each(|q| *q = p(*q));
            Curve::Bspline(b)
        }
    }
}

/// The pcurve OCCT computes for an edge on a plane that stores none (`BRep_Tool::
/// CurveOnPlane`): the edge's world curve in the plane's (u, v). Exact for B-splines (the
/// projection is affine); lines, circles and ellipses must lie in the plane (else their
/// projection changes parametrisation, and it is refused).
pub(crate) fn on_plane(c: &Curve3, plane: &Frame) -> Result<Curve2, String> {
    let uv = |q: Point3| {
        let d = q - plane.origin;
        Point2::new(d.dot(plane.x_dir), d.dot(plane.y_dir))
    };
    let vec = |q: Point3| Point2::new(q.dot(plane.x_dir), q.dot(plane.y_dir));
    let in_plane = |v: Point2| (v.length() - 1.0).abs() <= 1e-9;
    let out = "its 3D curve is not in the face's plane".to_string();
    Ok(match c {
        Curve::Line { origin, dir } => {
            let d = vec(*dir);
            if !in_plane(d) {
                return Err(out);
            }
            Curve::Line {
                origin: uv(*origin),
                dir: normalized(d),
            }
        }
        Curve::Circle {
            center,
            x_dir,
            y_dir,
            radius,
        } => {
            let (x, y) = (vec(*x_dir), vec(*y_dir));
            if !(in_plane(x) && in_plane(y)) {
                return Err(out);
            }
            let (x_dir, y_dir) = axes22d(x, y);
            Curve::Circle {
                center: uv(*center),
                x_dir,
                y_dir,
                radius: *radius,
            }
        }
        Curve::Ellipse {
            center,
            x_dir,
            y_dir,
            major_radius,
            minor_radius,
        } => {
            let (x, y) = (vec(*x_dir), vec(*y_dir));
            if !(in_plane(x) && in_plane(y)) {
                return Err(out);
            }
            let (x_dir, y_dir) = axes22d(x, y);
            Curve::Ellipse {
                center: uv(*center),
                x_dir,
                y_dir,
                major_radius: *major_radius,
                minor_radius: *minor_radius,
            }
        }
        Curve::Bspline(b) => Curve::Bspline(BSplineCurve {
            degree: b.degree,
            poles: b.poles.iter().map(|&q| uv(q)).collect(),
            weights: b.weights.clone(),
            knots: b.knots.clone(),
            mults: b.mults.clone(),
            periodic: b.periodic,
            cache: Default::default(),
        }),
    })
}

/// `gp_Ax22d(P, X, Y)`: X normalised, Y = X turned ±90° by the sense of X × Y.
fn axes22d(x: Point2, y: Point2) -> (Point2, Point2) {
    let x = normalized(x);
    let y = if x[0] * y[1] - x[1] * y[0] >= 0.0 {
        Point2::new(-x[1], x[0])
    } else {
        Point2::new(x[1], -x[0])
    };
    (x, y)
}

/// `[u0, u1, v0, v1]` holding the pcurve on its range: a line's ends; an arc's ends and the
/// extreme angles it passes; the poles of a B-spline's piece on the range (their hull holds
/// it).
pub(crate) fn trim_box(c: &Curve2, t0: f64, t1: f64) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut add = |p: Point2| {
        b = [
            b[0].min(p[0]),
            b[1].max(p[0]),
            b[2].min(p[1]),
            b[3].max(p[1]),
        ];
    };
    let (lo, hi) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
    match c {
        Curve::Line { .. } => {
            add(c.point(t0));
            add(c.point(t1));
        }
        Curve::Circle {
            x_dir,
            y_dir,
            radius,
            ..
        } => {
            add(c.point(t0));
            add(c.point(t1));
            extremes(c, *x_dir, *y_dir, *radius, *radius, lo, hi, &mut add);
        }
        Curve::Ellipse {
            x_dir,
            y_dir,
            major_radius,
            minor_radius,
            ..
        } => {
            add(c.point(t0));
            add(c.point(t1));
            extremes(
                c,
                *x_dir,
                *y_dir,
                *major_radius,
                *minor_radius,
                lo,
                hi,
                &mut add,
            );
        }
        Curve::Bspline(bs) => {
            for p in piece_poles(bs, lo, hi) {
                add(p);
            }
        }
    }
    b
}

/// Adds the points of a conic `C + a cos t·X + b sin t·Y` on `[lo, hi]` where u or v is
/// extreme: coordinate k is `c_k + A cos(t − φ)`, extreme at φ + nπ.
#[allow(clippy::too_many_arguments)]
fn extremes(
    c: &Curve2,
    x: Point2,
    y: Point2,
    a: f64,
    b: f64,
    lo: f64,
    hi: f64,
    add: &mut impl FnMut(Point2),
) {
    for k in 0..2 {
        let phase = (b * y[k]).atan2(a * x[k]);
        let mut n = ((lo - phase) / PI).ceil();
        // A range of many turns adds every extreme once anyway: four are enough.
        for _ in 0..4 {
            let t = phase + n * PI;
            if t.is_nan() || t > hi {
                break;
            }
            add(c.point(t));
            n += 1.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_is_exact_and_same_parameter() {
        let raw = RawCurve::Parabola {
            origin: Point2::new(1.0, 2.0),
            x: Point2::new(0.0, 1.0),
            y: Point2::new(-1.0, 0.0),
            focal: 0.5,
        };
        let (c, a, b) = on_range(&raw, -1.0, 3.0).unwrap();
        assert_eq!((a, b), (-1.0, 3.0));
        for t in [-1.0, 0.0, 0.3, 2.0, 3.0] {
            let want = [1.0 - t, 2.0 + t * t / 2.0];
            let got = c.point(t);
            assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn hyperbola_is_exact_and_agrees_at_its_knots() {
        let raw = RawCurve::Hyperbola {
            center: Point3::new(1.0, 2.0, 3.0),
            x: Point3::new(0.0, 1.0, 0.0),
            y: Point3::new(0.0, 0.0, 1.0),
            major: 2.0,
            minor: 0.5,
        };
        let (c, a, b) = on_range(&raw, -1.1, 0.7).unwrap();
        assert_eq!((a, b), (-1.1, 0.7));
        let Curve::Bspline(bs) = &c else { panic!() };
        assert_eq!(bs.knots.len(), 9);
        for &k in &bs.knots {
            let p = c.point(k);
            let want = Point3::new(1.0, 2.0 + 2.0 * k.cosh(), 3.0 + 0.5 * k.sinh());
            assert!((p - want).length() < 1e-12, "{k}: {p:?} {want:?}");
        }
        // Between knots every point is on the hyperbola: ((y−2)/2)² − ((z−3)/0.5)² = 1.
        for i in 0..=100 {
            let p = c.point(-1.1 + 1.8 * i as f64 / 100.0);
            let (u, v) = ((p[1] - 2.0) / 2.0, (p[2] - 3.0) / 0.5);
            assert!((u * u - v * v - 1.0).abs() < 1e-12 && u > 0.0);
        }
    }

    #[test]
    fn arcs_box_their_extremes_bsplines_their_acting_poles() {
        let c = Curve::Circle {
            center: Point2::new(1.0, 1.0),
            x_dir: Point2::new(1.0, 0.0),
            y_dir: Point2::new(0.0, 1.0),
            radius: 2.0,
        };
        let b = trim_box(&c, 0.0, PI);
        let want = [-1.0, 3.0, 1.0, 3.0];
        assert!(
            b.iter().zip(want).all(|(x, y)| (x - y).abs() < 1e-12),
            "{b:?}"
        );
        let bs = Curve::Bspline(BSplineCurve {
            degree: 1,
            poles: vec![
                Point2::new(0.0, 0.0),
                Point2::new(1.0, 5.0),
                Point2::new(2.0, 0.0),
                Point2::new(3.0, -5.0),
            ],
            weights: None,
            knots: vec![0.0, 1.0, 2.0, 3.0],
            mults: vec![2, 1, 1, 2],
            periodic: false,
            cache: Default::default(),
        });
        // Degree 1: the piece's poles are its points at 1.2 and 1.8.
        let b = trim_box(&bs, 1.2, 1.8);
        let want = [1.2, 1.8, 1.0, 4.0];
        assert!(
            b.iter().zip(want).all(|(x, y)| (x - y).abs() < 1e-12),
            "{b:?}"
        );
        assert_eq!(trim_box(&bs, 0.0, 3.0), [0.0, 3.0, -5.0, 5.0]);
        assert_eq!(trim_box(&bs, 1.0, 2.0), [1.0, 2.0, 0.0, 5.0]);
    }
}
