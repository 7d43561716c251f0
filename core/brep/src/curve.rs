//! Curve evaluation, the same code for 2D trims (in (u, v)) and 3D edges and profiles: the point
//! and first derivative at a parameter, and how densely to sample a range so that a polyline
//! follows the curve (loop orientation, bounds checks).

use crate::bspline::{KnotError, KnotVector, eval_curve};
use crate::model::{BSplineCurve, Curve};
use crate::vector::{Point, combine};

impl<P: Point> BSplineCurve<P> {
    /// The curve's checked knot vector.
    ///
    /// # Errors
    /// When `degree`, `knots` or `mults` break the rules (see [`KnotVector::new`]).
    pub fn knot_vector(&self) -> Result<KnotVector, KnotError> {
        KnotVector::new(self.degree, &self.knots, &self.mults, self.periodic)
    }

    /// `(C(t), C'(t))`, or `None` for a curve [`crate::validate`] refuses.
    pub fn eval(&self, t: f64) -> Option<(P, P)> {
        let kv = self.cache.get_or_init(|| self.knot_vector().ok())?;
        eval_curve(kv, &self.poles, self.weights.as_deref(), t)
    }
}

impl<P: Point> Curve<P> {
    /// `(C(t), C'(t))`; NaN coordinates for a B-spline that does not validate.
    pub fn eval(&self, t: f64) -> (P, P) {
        let (c, s) = (t.cos(), t.sin());
        match self {
            Curve::Line { origin, dir } => (*origin + *dir * t, *dir),
            Curve::Circle {
                center,
                x_dir,
                y_dir,
                radius,
            } => (
                *center + combine(&[(radius * c, *x_dir), (radius * s, *y_dir)]),
                combine(&[(-radius * s, *x_dir), (radius * c, *y_dir)]),
            ),
            Curve::Ellipse {
                center,
                x_dir,
                y_dir,
                major_radius: a,
                minor_radius: b,
            } => (
                *center + combine(&[(a * c, *x_dir), (b * s, *y_dir)]),
                combine(&[(-a * s, *x_dir), (b * c, *y_dir)]),
            ),
            Curve::Bspline(b) => b.eval(t).unwrap_or((P::NAN, P::NAN)),
        }
    }

    /// `C(t)`.
    pub fn point(&self, t: f64) -> P {
        self.eval(t).0
    }

    /// How many segments a polyline needs between `t0` and `t1` to follow the curve closely
    /// enough for orientation and bounds checks: 1 for a line, one per 1/32 turn for conics,
    /// 4·degree per polynomial piece for B-splines (capped at 4096).
    pub fn segments(&self, t0: f64, t1: f64) -> usize {
        let span = (t1 - t0).abs();
        let n = match self {
            Curve::Line { .. } => 1.0,
            Curve::Circle { .. } | Curve::Ellipse { .. } => {
                conic_segments(span, std::f64::consts::TAU / 32.0)
            }
            Curve::Bspline(b) => match b.knot_vector() {
                Ok(kv) => (kv.pieces(t0, t1) * 4 * b.degree) as f64,
                Err(_) => 1.0,
            },
        };
        if n.is_finite() {
            n.clamp(1.0, 4096.0) as usize
        } else {
            1
        }
    }
}

/// The segments of at most `step` radians a conic's parameter span `span` is cut into:
/// `ceil(span / step)` with a slack of 1e-9 segment, so that a full turn rounded up in a file's
/// last digit (OCCT writes 2π as `6.28318530717959`, 4e-15 above it) counts the segments 2π
/// does, not one more.
pub fn conic_segments(span: f64, step: f64) -> f64 {
    (span / step - 1e-9).ceil()
}
