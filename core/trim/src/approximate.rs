//! The trim-curve approximation pipeline of paper 000, section 3.1, per trim and per loop:
//! sample the input curve, fit a dense uniform quadratic B-spline, remove knots to the (u, v)
//! tolerance, split into connected quadratic Béziers, and turn flat ones into lines.
//!
//! The tolerance `eps_uv` is shared out: half for the spline against the samples and the
//! curve's midpoints between them, a quarter for flattening, the rest for the curve between
//! those checks (measured at the samples and midpoints again, and reported). The spline is
//! compared with each sample at the parameter it was fitted at after parameter correction
//! (`quadratic_fit::correct_params`): the samples' distance to the curve, not to the point of
//! the same uniform parameter, which overstated the deviation of arcs several times over.
//! Lines and degree-1 B-splines become segments directly; circles and ellipses become
//! Béziers directly too, with the same shares of the tolerance ([`conic_deviation`]); other
//! B-splines are split at their corners (knots of multiplicity ≥ the degree) first.

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

/// The trim's range split at the B-spline's interior knots of multiplicity ≥ its degree,
/// where the curve is only C0 (a corner, in general), in the trim's direction; `None` for
/// other curves or when there is no such knot. For degree 1 these are all the knots.
fn corner_breaks(trim: &Trim) -> Option<Vec<f64>> {
    let Curve::Bspline(b) = &trim.curve else {
        return None;
    };
    let [t0, t1] = trim.range;
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let mut inner: Vec<f64> = b
        .knots
        .iter()
        .zip(&b.mults)
        .filter(|&(&k, &m)| {
            m as usize >= b.degree && k > lo + 1e-12 * (hi - lo) && k < hi - 1e-12 * (hi - lo)
        })
        .map(|(&k, _)| k)
        .collect();
    if inner.is_empty() && b.degree > 1 {
        return None;
    }
    if t1 < t0 {
        inner.reverse();
    }
    let mut ts = vec![t0];
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
    let corners = corner_breaks(trim);
    let straight = match &trim.curve {
        Curve::Line { .. } => Some(vec![t0, t1]),
        Curve::Circle { center, radius, .. } => {
            return approximate_conic(trim, center.to_array(), *radius, eps_uv);
        }
        Curve::Ellipse {
            center,
            major_radius,
            minor_radius,
            ..
        } => {
            return approximate_conic(
                trim,
                center.to_array(),
                major_radius.max(*minor_radius),
                eps_uv,
            );
        }
        Curve::Bspline(b) if b.degree == 1 => corners,
        _ => {
            if let Some(ts) = corners {
                return approximate_between_corners(trim, &ts, eps_uv);
            }
            None
        }
    };
    if let Some(ts) = straight {
        let pts: Vec<P2> = ts.iter().map(|&t| trim.curve.point(t).to_array()).collect();
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
    let (thin, fitted_at) = remove_knots(&samples, spline, tol);
    let flat_tol = 0.25 * eps_uv;
    let pieces: Vec<Quadratic> = thin
        .beziers()
        .into_iter()
        .map(|q| q.flattened(flat_tol))
        .collect();
    let max_error = measure(trim, &thin, &pieces, &samples, &fitted_at);
    Ok(TrimApprox { pieces, max_error })
}

/// The most angle one conic piece spans (a quarter turn), whatever the tolerance.
const CONIC_MAX_ANGLE: f64 = std::f64::consts::FRAC_PI_2;

/// How far, relative to its radius, the quadratic Bézier of a circular arc of angle `angle`
/// (end points on the arc, middle control point where the end tangents meet) strays from
/// the circle: it lies outside it, farthest at its middle, by
/// `r ((c + 1/c)/2 − 1) = r (1 − c)² / (2c)` with `c = cos(angle / 2)`.
pub fn conic_deviation(angle: f64) -> f64 {
    let c = (0.5 * angle.abs()).cos();
    (1.0 - c) * (1.0 - c) / (2.0 * c)
}

/// A circle or ellipse trim (`radius`: the circle's, the ellipse's major radius) made of
/// quadratic Béziers directly, without sampling, fitting or knot removal: the range is cut
/// into `n` equal angles, each piece interpolating the curve at its ends with its middle
/// control point where the end tangents meet (so consecutive pieces meet with the curve's
/// tangent, and with equal speeds: C1 like section 3.1's spline), `n` the fewest for which
/// the deviation ([`conic_deviation`]) stays within the fit's share of the tolerance (half
/// of `eps_uv`, as for the spline). An ellipse is the affine image `center + M (cos t,
/// sin t)` of the unit circle, `M`'s largest singular value its major radius, and so are its
/// pieces of the unit circle's: the distance between them is at most `radius` times the
/// circle's. The pieces are then flattened as the spline's are (a quarter of `eps_uv`).
/// The error reported is that bound plus the flattened pieces' flatness, an upper bound of
/// the distance both ways (the pieces sweep the centre's angles monotonically, as the curve
/// does). This is what the sampled fit converges to on an arc, at a fraction of the cost (a
/// plate with 540 holes), and with fewer pieces.
fn approximate_conic(
    trim: &Trim,
    center: P2,
    radius: f64,
    eps_uv: f64,
) -> Result<TrimApprox, NotFinite> {
    let [t0, t1] = trim.range;
    let sweep = t1 - t0;
    let tol = 0.5 * eps_uv;
    if !(sweep.is_finite() && radius.is_finite() && center.iter().all(|c| c.is_finite())) {
        return Err(NotFinite);
    }
    // The largest angle with radius · conic_deviation(angle) ≤ tol: with x = 1 − c,
    // x² / (2 (1 − x)) ≤ τ for x ≤ √(τ² + 2τ) − τ.
    let tau = tol / radius.abs().max(f64::MIN_POSITIVE);
    let x = (tau * tau + 2.0 * tau).sqrt() - tau;
    let step = (2.0 * (1.0 - x).clamp(-1.0, 1.0).acos()).min(CONIC_MAX_ANGLE);
    let mut n = ((sweep.abs() / step).ceil() as usize).clamp(1, MAX_SAMPLES);
    while n < MAX_SAMPLES && radius * conic_deviation(sweep / n as f64) > tol {
        n += 1;
    }
    let fit_error = radius * conic_deviation(sweep / n as f64);
    let scale = 1.0 / (0.5 * sweep / n as f64).cos();
    let at = |k: usize| t0 + sweep * k as f64 / n as f64;
    let flat_tol = 0.25 * eps_uv;
    let mut pieces = Vec::with_capacity(n);
    let mut max_error: f64 = 0.0;
    let mut start = trim.curve.point(t0).to_array();
    for k in 0..n {
        let end = if k + 1 == n {
            trim.curve.point(t1)
        } else {
            trim.curve.point(at(k + 1))
        }
        .to_array();
        let m = trim.curve.point(0.5 * (at(k) + at(k + 1)));
        let mid = [
            center[0] + (m[0] - center[0]) * scale,
            center[1] + (m[1] - center[1]) * scale,
        ];
        let q = Quadratic::new(start, mid, end);
        let flat = q.flattened(flat_tol);
        let error = if flat.line {
            fit_error + q.flatness()
        } else {
            fit_error
        };
        max_error = max_error.max(error);
        pieces.push(flat);
        start = end;
    }
    if pieces
        .iter()
        .flat_map(|q| q.p)
        .flatten()
        .any(|c| !c.is_finite())
    {
        return Err(NotFinite);
    }
    Ok(TrimApprox { pieces, max_error })
}

/// A B-spline trim with corners (C0 knots) approximated one C1 stretch at a time, between
/// the parameters `ts`: section 3.1's spline is C1 and the paper keeps C1 only where the
/// input is C1. A fit across a corner would round it with a cluster of short spans, their
/// junctions closer together than the quadtree can separate (depth-13 failures, section 8);
/// split, the corner is a single junction.
fn approximate_between_corners(
    trim: &Trim,
    ts: &[f64],
    eps_uv: f64,
) -> Result<TrimApprox, NotFinite> {
    let mut out = TrimApprox {
        pieces: Vec::new(),
        max_error: 0.0,
    };
    for w in ts.windows(2) {
        let part = Trim {
            curve: trim.curve.clone(),
            range: [w[0], w[1]],
            edge: trim.edge,
        };
        let a = approximate_trim(&part, eps_uv)?;
        out.pieces.extend(a.pieces);
        out.max_error = out.max_error.max(a.max_error);
    }
    Ok(out)
}

/// The largest parametric distance between the pieces and the curve at the samples and the
/// midpoints between them: sample i of the curve (parameter `samples.params[i]`) against the
/// pieces at the parameter it was fitted at (`fitted_at[i]`, after parameter
/// correction), midpoints against midpoints — a monotone matching of the two curves.
fn measure(
    trim: &Trim,
    spline: &QuadSpline,
    pieces: &[Quadratic],
    samples: &Samples,
    fitted_at: &[f64],
) -> f64 {
    let [t0, t1] = trim.range;
    let b = &spline.breaks;
    let curved = spline.beziers();
    let mut span = 0;
    let mut worst: f64 = 0.0;
    let n = samples.params.len();
    let mid = |p: &[f64], i: usize| {
        if i.is_multiple_of(2) {
            p[i / 2]
        } else {
            0.5 * (p[i / 2] + p[i / 2 + 1])
        }
    };
    for i in 0..(2 * n - 1) {
        let s = mid(fitted_at, i);
        // The curve there: the sample, or the midpoint `Samples::of` evaluated already.
        let exact = match (i.is_multiple_of(2), samples.mids.get(i / 2)) {
            (true, _) => samples.points[i / 2],
            (false, Some(&m)) => m,
            (false, None) => trim
                .curve
                .point(t0 + mid(&samples.params, i) * (t1 - t0))
                .to_array(),
        };
        // s increases with i: walk the spans.
        while span + 2 < b.len() && b[span + 1] <= s {
            span += 1;
        }
        let local = (s - b[span]) / (b[span + 1] - b[span]);
        let q = &pieces[span];
        let p = if q.line {
            // a flattened piece: compare with the curve piece it replaced
            let cur = curved[span].point(local);
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
/// (counter-clockwise) when it has none. Pieces below the tolerance are dropped (see
/// [`drop_tiny`]). Each loop is closed: small gaps between trims are closed by moving the
/// next piece's start, larger ones bridged by a segment. Also returns the largest measured
/// error.
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
        let pieces = drop_tiny(pieces, (TINY * eps_uv).max(1e-12 * size));
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

/// Pieces whose control points all lie within `TINY · eps_uv` of the previous kept piece's
/// end are dropped from a loop (the next piece then starts where the previous kept one ends).
pub const TINY: f64 = 1.0 / 16.0;

/// Drops the pieces of a closed loop that stay within `delta` of the end of the last piece
/// kept before them; a loop lying entirely within a `delta` box goes altogether.
///
/// Such pieces come from trims far shorter than the tolerance (CAD edges of a few
/// nanometres, often doubling back on their neighbours). Kept, each adds two junctions closer
/// together than any quadtree cell can separate: the cell around them holds three curves at
/// every depth, a depth-13 failure of paper 000's table 4 (section 8, figure 14: junctions
/// are not placed to suit the subdivision). Dropping them moves the loop by at most `delta`
/// (the next piece's start, see `close`), within the tolerance. The walk starts at the
/// largest piece, which is always kept, and keeps the remaining pieces in loop order.
pub fn drop_tiny(pieces: Vec<Quadratic>, delta: f64) -> Vec<Quadratic> {
    let extent = |q: &Quadratic| {
        dist(q.p[0], q.p[1])
            .max(dist(q.p[1], q.p[2]))
            .max(dist(q.p[0], q.p[2]))
    };
    let Some(start) =
        (0..pieces.len()).max_by(|&i, &j| extent(&pieces[i]).total_cmp(&extent(&pieces[j])))
    else {
        return pieces;
    };
    let mut b = pieces[0].control_box();
    for q in &pieces {
        let c = q.control_box();
        b = [
            b[0].min(c[0]),
            b[1].max(c[1]),
            b[2].min(c[2]),
            b[3].max(c[3]),
        ];
    }
    if (b[1] - b[0]).hypot(b[3] - b[2]) <= delta {
        return Vec::new();
    }
    let n = pieces.len();
    let mut keep = vec![false; n];
    keep[start] = true;
    let mut anchor = pieces[start].p[2];
    for k in 1..n {
        let i = (start + k) % n;
        if pieces[i].p.iter().all(|&p| dist(p, anchor) <= delta) {
            continue;
        }
        keep[i] = true;
        anchor = pieces[i].p[2];
    }
    pieces
        .into_iter()
        .zip(keep)
        .filter_map(|(q, k)| k.then_some(q))
        .collect()
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
