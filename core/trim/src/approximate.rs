//! The trim-curve approximation pipeline of paper 000, section 3.1, per trim and per loop:
//! sample the input curve, fit a dense uniform quadratic B-spline, remove knots to the (u, v)
//! tolerance, split into connected quadratic Béziers, and turn flat ones into lines.
//!
//! The tolerance `eps_uv` is shared out: half for the spline against the samples and the
//! curve's midpoints between them, a quarter for flattening, the rest for the curve between
//! those checks (measured at the samples and midpoints again, and reported). The spline is
//! compared with each sample at the parameter it was fitted at after parameter correction
//! (`quadratic_fit::correct_params`): the samples' distance to the curve, not to the point of
//! the same uniform parameter, which overstated the deviation of arcs several times over. Lines and degree-1 B-splines become segments directly; other
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
        Curve::Bspline(b) if b.degree == 1 => corners,
        _ => {
            if let Some(ts) = corners {
                return approximate_between_corners(trim, &ts, eps_uv);
            }
            None
        }
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
/// pieces at the parameter it was fitted at (`fitted_at.params[i]`, after parameter
/// correction), midpoints against midpoints — a monotone matching of the two curves.
fn measure(
    trim: &Trim,
    spline: &QuadSpline,
    pieces: &[Quadratic],
    samples: &Samples,
    fitted_at: &Samples,
) -> f64 {
    let [t0, t1] = trim.range;
    let b = &spline.breaks;
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
        let (e, s) = (mid(&samples.params, i), mid(&fitted_at.params, i));
        let exact = trim.curve.point(t0 + e * (t1 - t0));
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
