//! The trim-curve approximation pipeline of paper 000, section 3.1, per trim and per loop:
//! sample the input curve, fit a dense uniform quadratic B-spline, remove knots to the (u, v)
//! tolerance, split into connected quadratic Béziers, and turn flat ones into lines.
//!
//! The tolerance `eps_uv` is shared out: half for the spline against the samples, a quarter
//! for flattening, the rest for the curve between samples (checked at the midpoints between
//! samples, and reported). Lines and degree-1 B-splines become segments directly.

use crate::bezier::{P2, Quadratic, dist};
use crate::knot_removal::remove_knots;
use crate::quadratic_fit::{QuadSpline, Samples, fit, max_error, uniform_breaks};
use tessd_brep::{Curve, Face, Trim};

/// The fewest samples per trim.
pub const MIN_SAMPLES: usize = 32;
/// The most samples per trim.
pub const MAX_SAMPLES: usize = 1 << 16;

/// One trim's approximation.
#[derive(Clone, Debug, PartialEq)]
pub struct TrimApprox {
    /// The pieces in the trim's direction, each starting where the previous ends.
    pub pieces: Vec<Quadratic>,
    /// The largest (u, v) distance measured between the pieces and the input curve (at the
    /// samples and the midpoints between them, flattening included).
    pub max_error: f64,
}

/// Why a trim could not be approximated.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the curve does not evaluate to finite points over its range")]
pub struct NotFinite;

fn degree_one_breaks(trim: &Trim) -> Option<Vec<f64>> {
    let Curve::Bspline(b) = &trim.curve else {
        return None;
    };
    if b.degree != 1 {
        return None;
    }
    let [t0, t1] = trim.range;
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let mut ts = vec![t0];
    let mut inner: Vec<f64> = b
        .knots
        .iter()
        .copied()
        .filter(|&k| k > lo + 1e-12 * (hi - lo) && k < hi - 1e-12 * (hi - lo))
        .collect();
    if t1 < t0 {
        inner.reverse();
    }
    ts.extend(inner);
    ts.push(t1);
    Some(ts)
}

/// Approximates one trim within `eps_uv`.
///
/// # Errors
/// [`NotFinite`] when the curve evaluates to NaN or infinity.
pub fn approximate_trim(trim: &Trim, eps_uv: f64) -> Result<TrimApprox, NotFinite> {
    let [t0, t1] = trim.range;
    let straight = match &trim.curve {
        Curve::Line { .. } => Some(vec![t0, t1]),
        _ => degree_one_breaks(trim),
    };
    if let Some(ts) = straight {
        let pts: Vec<P2> = ts.iter().map(|&t| trim.curve.point(t)).collect();
        if pts.iter().flatten().any(|c| !c.is_finite()) {
            return Err(NotFinite);
        }
        let pieces = pts
            .windows(2)
            .map(|w| Quadratic::segment(w[0], w[1]))
            .collect();
        return Ok(TrimApprox {
            pieces,
            max_error: 0.0,
        });
    }
    let tol = 0.5 * eps_uv;
    let mut count = (trim.curve.segments(t0, t1) * 8).clamp(MIN_SAMPLES, MAX_SAMPLES);
    let (samples, spline) = loop {
        let samples = Samples::of(trim, count);
        if !samples.is_finite() {
            return Err(NotFinite);
        }
        let dense = fit(&samples, &uniform_breaks((count / 4).max(1)));
        if max_error(&dense, &samples) <= tol * 0.5 || count >= MAX_SAMPLES {
            break (samples, dense);
        }
        count *= 2;
    };
    let thin = remove_knots(&samples, spline, tol);
    let flat_tol = 0.25 * eps_uv;
    let pieces: Vec<Quadratic> = thin
        .beziers()
        .into_iter()
        .map(|q| q.flattened(flat_tol))
        .collect();
    let max_error = measure(trim, &thin, &pieces, &samples);
    Ok(TrimApprox { pieces, max_error })
}

/// The largest parametric distance between the pieces and the curve at the samples and the
/// midpoints between them.
fn measure(trim: &Trim, spline: &QuadSpline, pieces: &[Quadratic], samples: &Samples) -> f64 {
    let [t0, t1] = trim.range;
    let b = &spline.breaks;
    let mut worst: f64 = 0.0;
    let n = samples.params.len();
    for i in 0..(2 * n - 1) {
        let s = if i % 2 == 0 {
            samples.params[i / 2]
        } else {
            0.5 * (samples.params[i / 2] + samples.params[i / 2 + 1])
        };
        let exact = trim.curve.point(t0 + s * (t1 - t0));
        let span = b.partition_point(|&x| x <= s).clamp(1, b.len() - 1) - 1;
        let local = (s - b[span]) / (b[span + 1] - b[span]);
        let q = &pieces[span];
        let p = if q.line {
            // a flattened piece: compare with the curve piece it replaced
            let cur = spline.beziers()[span].point(local);
            let chord = crate::bezier::lerp(q.p[0], q.p[2], local);
            worst = worst.max(dist(cur, exact) + dist(cur, chord));
            continue;
        } else {
            q.point(local)
        };
        worst = worst.max(dist(p, exact));
    }
    worst
}

/// The approximated loops of a face, in (u, v): the face's loops, or its bounds rectangle
/// (counter-clockwise) when it has none. Each loop is closed: small gaps between trims are
/// closed by moving the next piece's start, larger ones bridged by a segment. Also returns
/// the largest measured error.
///
/// # Errors
/// `(loop, trim)` of a trim that does not evaluate.
pub fn approximate_loops(face: &Face, eps_uv: f64) -> Result<LoopsApprox, (usize, usize)> {
    let [u0, u1, v0, v1] = face.bounds;
    if face.loops.is_empty() {
        let c = [[u0, v0], [u1, v0], [u1, v1], [u0, v1]];
        let rect = (0..4)
            .map(|i| Quadratic::segment(c[i], c[(i + 1) % 4]))
            .collect();
        return Ok(LoopsApprox {
            loops: vec![rect],
            max_error: 0.0,
        });
    }
    let size = (u1 - u0).hypot(v1 - v0);
    let mut worst: f64 = 0.0;
    let mut loops = Vec::with_capacity(face.loops.len());
    for (li, lp) in face.loops.iter().enumerate() {
        let mut pieces: Vec<Quadratic> = Vec::new();
        for (ti, trim) in lp.trims.iter().enumerate() {
            let a = approximate_trim(trim, eps_uv).map_err(|_| (li, ti))?;
            worst = worst.max(a.max_error);
            pieces.extend(a.pieces);
        }
        pieces.retain(|q| dist(q.p[0], q.p[2]) + dist(q.p[0], q.p[1]) > 1e-12 * size);
        loops.push(close(pieces, eps_uv));
    }
    Ok(LoopsApprox {
        loops,
        max_error: worst,
    })
}

/// A face's approximated loops.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopsApprox {
    /// The closed loops of pieces, in (u, v).
    pub loops: Vec<Vec<Quadratic>>,
    /// The largest measured error of their trims.
    pub max_error: f64,
}

fn close(pieces: Vec<Quadratic>, eps_uv: f64) -> Vec<Quadratic> {
    let n = pieces.len();
    let mut out: Vec<Quadratic> = Vec::with_capacity(n + 2);
    for i in 0..n {
        let mut q = pieces[i];
        let prev_end = pieces[(i + n - 1) % n].p[2];
        let gap = dist(prev_end, q.p[0]);
        if gap > eps_uv {
            out.push(Quadratic::segment(prev_end, q.p[0]));
        } else if gap > 0.0 {
            q.p[0] = prev_end;
            if q.line {
                q = Quadratic::segment(q.p[0], q.p[2]);
            }
        }
        out.push(q);
    }
    out
}
