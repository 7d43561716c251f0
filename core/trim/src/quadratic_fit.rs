//! Sampling a trim curve and fitting a quadratic B-spline to the samples by least squares
//! (paper 000, section 3.1: "we discretise each input curve and fit a uniform degree-2
//! B-spline"). The end points are interpolated so loops stay closed, and the end tangents
//! follow the input curve's, so that where two input curves meet with C1 continuity, so do
//! their approximations.

use crate::bezier::{P2, Quadratic};
use tessd_brep::{Curve, Trim};

/// Points of a trim at parameters `s ∈ [0, 1]` along its range (`t = t0 + s (t1 − t0)`, so a
/// reversed range walks the curve backwards), with the end derivatives in s.
#[derive(Clone, Debug)]
pub struct Samples {
    /// The parameters, increasing from 0 to 1.
    pub params: Vec<f64>,
    /// The points C(t(s)).
    pub points: Vec<P2>,
    /// dC/ds at s = 0.
    pub start_tangent: P2,
    /// dC/ds at s = 1.
    pub end_tangent: P2,
    /// The curve halfway (in the curve's parameter) between consecutive samples, one fewer
    /// than `points`, or empty. [`max_error`] checks them against the spline halfway between
    /// the samples' (corrected) parameters, so that a fit whose samples lie on the curve but
    /// which strays between them — parameter correction can match a sample to the wrong
    /// stretch of a curve that nearly doubles back — is seen.
    pub mids: Vec<P2>,
}

impl Samples {
    /// `count + 1` evenly spaced samples of `trim` (count ≥ 1), and its end derivatives.
    pub fn of(trim: &Trim, count: usize) -> Samples {
        let [t0, t1] = trim.range;
        let count = count.max(1);
        let params: Vec<f64> = (0..=count).map(|i| i as f64 / count as f64).collect();
        let points = params
            .iter()
            .map(|&s| trim.curve.point(t0 + s * (t1 - t0)).to_array())
            .collect();
        let mids = params
            .windows(2)
            .map(|w| {
                trim.curve
                    .point(t0 + 0.5 * (w[0] + w[1]) * (t1 - t0))
                    .to_array()
            })
            .collect();
        let d = |t: f64, inwards: f64| {
            let (_, d) = trim.curve.eval(inside_corner(trim, t, inwards));
            [d[0] * (t1 - t0), d[1] * (t1 - t0)]
        };
        Samples {
            params,
            points,
            start_tangent: d(t0, t1 - t0),
            end_tangent: d(t1, t0 - t1),
            mids,
        }
    }

    /// Whether every sample is finite.
    pub fn is_finite(&self) -> bool {
        self.points
            .iter()
            .chain(&self.mids)
            .flatten()
            .all(|c| c.is_finite())
    }
}

/// `t`, or, where `t` is an interior knot of a B-spline of multiplicity ≥ its degree (a
/// corner, where a trim is split, see `approximate`), `t` moved a hair in the direction of
/// `inwards`: the derivative at the knot itself may be the other segment's.
fn inside_corner(trim: &Trim, t: f64, inwards: f64) -> f64 {
    let Curve::Bspline(b) = &trim.curve else {
        return t;
    };
    let (Some(first), Some(last)) = (b.knots.first(), b.knots.last()) else {
        return t;
    };
    let span = (last - first).abs();
    let interior = b.knots.len().saturating_sub(2);
    let corner = b
        .knots
        .iter()
        .zip(&b.mults)
        .skip(1)
        .take(interior)
        .any(|(&k, &m)| m as usize >= b.degree && (k - t).abs() <= 1e-12 * span);
    if !corner {
        return t;
    }
    let step = (1e-12 * span).max(8.0 * f64::EPSILON * t.abs());
    t + step * inwards.signum()
}

/// A clamped quadratic B-spline on [0, 1] with simple interior knots: breakpoints
/// `0 = b0 < b1 < … < bL = 1` and `L + 2` poles.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadSpline {
    /// The breakpoints, from 0 to 1.
    pub breaks: Vec<f64>,
    /// The control points.
    pub poles: Vec<P2>,
}

impl QuadSpline {
    /// The full knot vector `[0, 0, 0, b1, …, b(L−1), 1, 1, 1]`.
    pub fn knots(&self) -> Vec<f64> {
        knot_vector(&self.breaks)
    }

    /// The spline at `s`.
    pub fn point(&self, s: f64) -> P2 {
        let knots = self.knots();
        let (j, n) = basis(&knots, self.poles.len(), s);
        let mut p = [0.0; 2];
        for (k, w) in n.iter().enumerate() {
            let q = self.poles[j - 2 + k];
            p[0] += w * q[0];
            p[1] += w * q[1];
        }
        p
    }

    /// The Bézier pieces, one per knot span (section 3.1, "decomposed into connected quadratic
    /// Bézier curves"): the middle control point of span i is pole i + 1, and the junction at
    /// breakpoint i divides poles i, i + 1 in the ratio of the neighbouring span lengths,
    /// which is where the C1 spline's two pieces meet.
    pub fn beziers(&self) -> Vec<Quadratic> {
        let l = self.breaks.len() - 1;
        let h: Vec<f64> = self.breaks.windows(2).map(|w| w[1] - w[0]).collect();
        let junction = |i: usize| -> P2 {
            if i == 0 {
                return self.poles[0];
            }
            if i == l {
                return self.poles[l + 1];
            }
            let (a, b) = (self.poles[i], self.poles[i + 1]);
            let w = h[i - 1] / (h[i - 1] + h[i]);
            [a[0] + (b[0] - a[0]) * w, a[1] + (b[1] - a[1]) * w]
        };
        (0..l)
            .map(|i| Quadratic::new(junction(i), self.poles[i + 1], junction(i + 1)))
            .collect()
    }
}

/// `[0, 0, 0, b1, …, b(L−1), 1, 1, 1]`.
pub fn knot_vector(breaks: &[f64]) -> Vec<f64> {
    let mut k = vec![0.0, 0.0];
    k.extend_from_slice(breaks);
    k.push(1.0);
    k.push(1.0);
    k
}

/// The span j (poles j−2 ..= j are non-zero) and the three non-zero quadratic B-spline basis
/// functions at `s` (Cox–de Boor).
pub fn basis(knots: &[f64], poles: usize, s: f64) -> (usize, [f64; 3]) {
    // Largest j in [2, poles − 1] with knots[j] ≤ s.
    let (mut lo, mut hi) = (2, poles - 1);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if knots[mid] <= s {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    (lo, basis_in(knots, lo, s))
}

/// The three non-zero quadratic basis functions at `s` in span `j` (Cox–de Boor), for a
/// caller that walks sorted parameters through the spans instead of searching each.
fn basis_in(knots: &[f64], j: usize, s: f64) -> [f64; 3] {
    let mut n = [1.0, 0.0, 0.0];
    let mut left = [0.0; 3];
    let mut right = [0.0; 3];
    for d in 1..=2 {
        left[d] = s - knots[j + 1 - d];
        right[d] = knots[j + d] - s;
        let mut saved = 0.0;
        for r in 0..d {
            let den = right[r + 1] + left[d - r];
            let temp = if den != 0.0 { n[r] / den } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[d - r] * temp;
        }
        n[d] = saved;
    }
    n
}

/// The index of the span of `breaks` holding `s` (`breaks[i] ≤ s < breaks[i+1]`, the last
/// span closed, the first for `s` below 0), searching from `from`: parameters visited in
/// increasing order cost one pass over the breaks in all instead of a binary search each.
#[inline]
fn span_from(breaks: &[f64], from: usize, s: f64) -> usize {
    let last = breaks.len() - 2;
    let mut i = from.min(last);
    while i > 0 && breaks[i] > s {
        i -= 1;
    }
    while i < last && breaks[i + 1] <= s {
        i += 1;
    }
    i
}

fn dist2(a: P2, b: P2) -> f64 {
    let (x, y) = (a[0] - b[0], a[1] - b[1]);
    x * x + y * y
}

/// Evenly spaced breakpoints for `spans` spans (the uniform B-spline).
pub fn uniform_breaks(spans: usize) -> Vec<f64> {
    (0..=spans).map(|i| i as f64 / spans as f64).collect()
}

/// The least-squares quadratic B-spline on `breaks` through the first and last samples,
/// then with its second and last-but-one poles moved onto the input's end tangents (C1
/// across trims where the input is C1). A banded (width 2) Cholesky solves the normal
/// equations.
pub fn fit(samples: &Samples, breaks: &[f64]) -> QuadSpline {
    fit_at(samples, &samples.params, breaks)
}

/// [`fit`] with sample i at parameter `params[i]` (increasing) instead of `samples.params[i]`.
pub fn fit_at(samples: &Samples, params: &[f64], breaks: &[f64]) -> QuadSpline {
    let knots = knot_vector(breaks);
    let n = breaks.len() + 1;
    let first = samples.points[0];
    let last = *samples.points.last().expect("samples");
    let mut poles = vec![first; n];
    poles[n - 1] = last;
    let unknowns = n - 2;
    if unknowns > 0 {
        // Band storage: a[i][k] = A[i][i − 2 + k], k = 0..=2 (lower part).
        let mut a = vec![[0.0f64; 3]; unknowns];
        let mut rhs = vec![[0.0f64; 2]; unknowns];
        let mut span = 0;
        for (&s, &p) in params.iter().zip(&samples.points) {
            span = span_from(breaks, span, s);
            let j = span + 2;
            let w = basis_in(&knots, j, s);
            let mut r = p;
            for (k, &wk) in w.iter().enumerate() {
                let idx = j - 2 + k;
                if idx == 0 || idx == n - 1 {
                    r[0] -= wk * poles[idx][0];
                    r[1] -= wk * poles[idx][1];
                }
            }
            for (k, &wk) in w.iter().enumerate() {
                let idx = j - 2 + k;
                if idx == 0 || idx == n - 1 {
                    continue;
                }
                let row = idx - 1;
                rhs[row][0] += wk * r[0];
                rhs[row][1] += wk * r[1];
                for (l, &wl) in w.iter().enumerate().take(k + 1) {
                    let col_idx = j - 2 + l;
                    if col_idx == 0 || col_idx == n - 1 {
                        continue;
                    }
                    let col = col_idx - 1;
                    a[row][2 + col - row] += wk * wl;
                }
            }
        }
        let trace: f64 = a.iter().map(|r| r[2]).sum::<f64>() / unknowns as f64;
        for r in &mut a {
            r[2] += 1e-12 * trace.max(1e-300);
        }
        let x = band_solve(&mut a, &rhs);
        poles[1..(unknowns + 1)].copy_from_slice(&x);
    }
    let mut spline = QuadSpline {
        breaks: breaks.to_vec(),
        poles,
    };
    follow_end_tangents(&mut spline, samples.start_tangent, samples.end_tangent);
    spline
}

/// Cholesky of a symmetric positive definite band matrix (half width 2, lower band stored as
/// `a[i][k] = A[i][i−2+k]`), then the two triangular solves, for two right-hand sides.
fn band_solve(a: &mut [[f64; 3]], rhs: &[[f64; 2]]) -> Vec<P2> {
    let n = a.len();
    for i in 0..n {
        for k in 0..3 {
            let j = i + k;
            if j < 2 {
                continue;
            }
            let j = j - 2; // column
            let mut sum = a[i][k];
            // Σ over c in max(i,j)-2 ..< j of L[i][c] L[j][c]
            let c0 = i.saturating_sub(2);
            for c in c0..j {
                let lic = a[i][c + 2 - i];
                let ljc = a[j][c + 2 - j];
                sum -= lic * ljc;
            }
            if j == i {
                a[i][2] = sum.max(1e-300).sqrt();
            } else {
                a[i][k] = sum / a[j][2];
            }
        }
    }
    let mut y = vec![[0.0; 2]; n];
    for i in 0..n {
        let mut s = rhs[i];
        for c in i.saturating_sub(2)..i {
            let l = a[i][c + 2 - i];
            s[0] -= l * y[c][0];
            s[1] -= l * y[c][1];
        }
        y[i] = [s[0] / a[i][2], s[1] / a[i][2]];
    }
    let mut x = vec![[0.0; 2]; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        for (r, xr) in x.iter().enumerate().take((i + 3).min(n)).skip(i + 1) {
            let l = a[r][i + 2 - r];
            s[0] -= l * xr[0];
            s[1] -= l * xr[1];
        }
        x[i] = [s[0] / a[i][2], s[1] / a[i][2]];
    }
    x
}

fn unit(d: P2) -> Option<P2> {
    let len = d[0].hypot(d[1]);
    (len > 0.0 && len.is_finite()).then(|| [d[0] / len, d[1] / len])
}

/// Moves the second pole onto the start tangent line and the last-but-one onto the end
/// tangent line (a single span: its middle pole to where the two tangent lines meet), when
/// that keeps them ahead of / behind the end points.
pub fn follow_end_tangents(spline: &mut QuadSpline, start: P2, end: P2) {
    let n = spline.poles.len();
    let (Some(d0), Some(d1)) = (unit(start), unit(end)) else {
        return;
    };
    let p0 = spline.poles[0];
    let pn = spline.poles[n - 1];
    if n == 3 {
        // p0 + a d0 = pn − b d1, i.e. a d0 + b d1 = pn − p0 (Cramer's rule), with a, b > 0:
        // the middle pole behind pn along d1, ahead of p0 along d0.
        let det = d0[0] * d1[1] - d1[0] * d0[1];
        let r = [pn[0] - p0[0], pn[1] - p0[1]];
        if det.abs() > 1e-12 {
            let a = (r[0] * d1[1] - d1[0] * r[1]) / det;
            let b = (d0[0] * r[1] - d0[1] * r[0]) / det;
            if a > 0.0 && b > 0.0 {
                spline.poles[1] = [p0[0] + a * d0[0], p0[1] + a * d0[1]];
            }
        }
        return;
    }
    let q = spline.poles[1];
    let a = (q[0] - p0[0]) * d0[0] + (q[1] - p0[1]) * d0[1];
    if a > 0.0 {
        spline.poles[1] = [p0[0] + a * d0[0], p0[1] + a * d0[1]];
    }
    let q = spline.poles[n - 2];
    let b = (pn[0] - q[0]) * d1[0] + (pn[1] - q[1]) * d1[1];
    if b > 0.0 {
        spline.poles[n - 2] = [pn[0] - b * d1[0], pn[1] - b * d1[1]];
    }
}

/// Rounds of parameter correction after each least-squares fit (see [`fit_corrected`]).
pub const CORRECTION_ROUNDS: usize = 3;

/// Parameter correction (Hoschek's "intrinsic parametrisation", as in Lyche–Mørken's data
/// reduction \[LM87\] that section 3.1 follows): one Newton step per sample towards the foot of
/// its perpendicular on `spline`, kept only where it brings the spline point closer, with
/// the ends fixed and the order of the samples kept. The fit's error at the corrected
/// parameters is then (nearly) the samples' distance to the curve instead of to the point of
/// the same parameter: a quadratic tracks a circular arc far better in shape than in
/// speed, so the uniform parameters alone overstate the (u, v) deviation several times over
/// and cost pieces (see `approximate`).
pub fn correct_params(spline: &QuadSpline, samples: &Samples) -> Samples {
    Samples {
        params: correct(spline, samples, &samples.params),
        ..samples.clone()
    }
}

/// [`correct_params`] from the parameters `from` (one per sample, increasing): the corrected
/// parameters.
fn correct(spline: &QuadSpline, samples: &Samples, from: &[f64]) -> Vec<f64> {
    let pieces = spline.beziers();
    let b = &spline.breaks;
    let eval = |span: usize, s: f64| {
        let h = b[span + 1] - b[span];
        let q = &pieces[span];
        let t = (s - b[span]) / h;
        let d = q.derivative(t);
        let [a, m, c] = q.p;
        let dd = [
            2.0 * (a[0] - 2.0 * m[0] + c[0]),
            2.0 * (a[1] - 2.0 * m[1] + c[1]),
        ];
        (
            q.point(t),
            [d[0] / h, d[1] / h],
            [dd[0] / (h * h), dd[1] / (h * h)],
        )
    };
    let n = from.len();
    let mut params = from.to_vec();
    let mut span = 0;
    for i in 1..n.saturating_sub(1) {
        let (s, p) = (params[i], samples.points[i]);
        span = span_from(b, span, s);
        let (c, d1, d2) = eval(span, s);
        let r = [c[0] - p[0], c[1] - p[1]];
        let num = r[0] * d1[0] + r[1] * d1[1];
        let den = d1[0] * d1[0] + d1[1] * d1[1] + r[0] * d2[0] + r[1] * d2[1];
        if den.is_nan() || den <= 0.0 {
            continue;
        }
        // Between the (already corrected) previous sample and the next one.
        let (lo, hi) = (params[i - 1], from[i + 1]);
        let t = (s - num / den).clamp(lo, hi);
        if t.is_finite() {
            let at = span_from(b, span, t);
            if dist2(eval(at, t).0, p) < dist2(c, p) {
                params[i] = t;
            }
        }
    }
    params
}

/// The fewest samples a span keeps under parameter correction.
pub const MIN_PER_SPAN: usize = 3;

fn every_span_sampled(params: &[f64], breaks: &[f64]) -> bool {
    let mut counts = vec![0usize; breaks.len() - 1];
    let mut span = 0;
    for &s in params {
        span = span_from(breaks, span, s);
        counts[span] += 1;
    }
    counts.iter().all(|&c| c >= MIN_PER_SPAN)
}

/// [`fit`] on `breaks` with the samples at the parameters `from`, then up to
/// [`CORRECTION_ROUNDS`] rounds of [`correct_params`] and refit, stopping early once the
/// error ([`max_error`]) is within `target`. Returns the spline, the parameters it was fitted
/// at and its error. A round that would leave a span with fewer than [`MIN_PER_SPAN`]
/// samples is not taken: the fit and its error would no longer see that span.
pub fn fit_corrected(
    samples: &Samples,
    from: &[f64],
    breaks: &[f64],
    target: f64,
) -> (QuadSpline, Vec<f64>, f64) {
    let mut spline = fit_at(samples, from, breaks);
    let mut at = from.to_vec();
    let mut error = max_error_at(&spline, samples, &at, f64::INFINITY);
    for round in 0..CORRECTION_ROUNDS {
        if error <= target {
            break;
        }
        let next = correct(&spline, samples, &at);
        if !every_span_sampled(&next, breaks) {
            break;
        }
        let refit = fit_at(samples, &next, breaks);
        // A refit worse than the current one is not taken: its exact error is not needed.
        let e = max_error_at(&refit, samples, &next, error);
        if e > error {
            break;
        }
        // Stop when even the last round's gain, repeated every remaining round, would not
        // bring the error within `target`: the candidate is failing (a knot removal that
        // goes too far, or a correction that has stalled), and the gains shrink from round
        // to round.
        let left = (CORRECTION_ROUNDS - 1 - round) as f64;
        let hopeless = e - left * (error - e) > target;
        (spline, at, error) = (refit, next, e);
        if hopeless {
            break;
        }
    }
    (spline, at, error)
}

/// The largest distance between the spline at the sample parameters and the samples (the
/// parametric error, an upper bound of the distance between the curves there), and, where
/// the samples carry them, between the spline halfway between consecutive parameters and
/// the curve's midpoints.
pub fn max_error(spline: &QuadSpline, samples: &Samples) -> f64 {
    max_error_at(spline, samples, &samples.params, f64::INFINITY)
}

/// [`max_error`] with sample i at parameter `params[i]` (increasing), stopping at the first
/// distance above `cap` (the result is then that distance, some error above `cap`, not
/// necessarily the largest): a fit that fails its tolerance is known to fail at its first
/// bad sample. Squared distances, the spline as its Bézier pieces and the spans walked with
/// the parameters keep the pass cheap.
pub fn max_error_at(spline: &QuadSpline, samples: &Samples, params: &[f64], cap: f64) -> f64 {
    let pieces = spline.beziers();
    let b = &spline.breaks;
    let at = |span: usize, s: f64| pieces[span].point((s - b[span]) / (b[span + 1] - b[span]));
    let cap2 = cap * cap;
    let mut worst2: f64 = 0.0;
    let mut span = 0;
    let n = params.len();
    for i in 0..n {
        let s = params[i];
        span = span_from(b, span, s);
        let d2 = dist2(samples.points[i], at(span, s));
        if d2 > worst2 {
            worst2 = d2;
        }
        if let (Some(&m), Some(&next)) = (samples.mids.get(i), params.get(i + 1)) {
            let s = 0.5 * (s + next);
            span = span_from(b, span, s);
            let d2 = dist2(m, at(span, s));
            if d2 > worst2 {
                worst2 = d2;
            }
        }
        if worst2 > cap2 {
            break;
        }
    }
    worst2.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bezier::dist;

    /// One span (the fewest knot removal can leave): its middle pole is where the two end
    /// tangents meet, so pieces of consecutive trims meet with the input's tangents — at a
    /// tangent cusp too, where a tilted end tangent makes the approximations cross.
    #[test]
    fn a_single_span_follows_both_end_tangents() {
        let (r, a0, a1) = (2.0, 0.3f64, 0.9f64);
        let params: Vec<f64> = (0..=64).map(|i| i as f64 / 64.0).collect();
        let at = |s: f64| a0 + s * (a1 - a0);
        let points: Vec<P2> = params
            .iter()
            .map(|&s| [r * at(s).cos(), r * at(s).sin()])
            .collect();
        let tangent = |a: f64| [-r * a.sin() * (a1 - a0), r * a.cos() * (a1 - a0)];
        let samples = Samples {
            params,
            points,
            start_tangent: tangent(a0),
            end_tangent: tangent(a1),
            mids: Vec::new(),
        };
        let sp = fit(&samples, &uniform_breaks(1));
        let [p0, p1, p2] = [sp.poles[0], sp.poles[1], sp.poles[2]];
        let cross = |a: P2, b: P2| a[0] * b[1] - a[1] * b[0];
        let d0 = [p1[0] - p0[0], p1[1] - p0[1]];
        let d1 = [p2[0] - p1[0], p2[1] - p1[1]];
        assert!(cross(d0, tangent(a0)).abs() < 1e-12, "{d0:?}");
        assert!(cross(d1, tangent(a1)).abs() < 1e-12, "{d1:?}");
        // ahead of p0, behind p2
        assert!(d0[0] * tangent(a0)[0] + d0[1] * tangent(a0)[1] > 0.0);
        assert!(d1[0] * tangent(a1)[0] + d1[1] * tangent(a1)[1] > 0.0);
    }

    #[test]
    fn basis_is_a_partition_of_unity_and_fit_reproduces_a_parabola() {
        let breaks = uniform_breaks(5);
        let knots = knot_vector(&breaks);
        for i in 0..=20 {
            let (_, n) = basis(&knots, 7, i as f64 / 20.0);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        // A parabola is a quadratic spline: the fit is exact.
        let params: Vec<f64> = (0..=50).map(|i| i as f64 / 50.0).collect();
        let points: Vec<P2> = params.iter().map(|&s| [s, s * s]).collect();
        let samples = Samples {
            params,
            points,
            start_tangent: [1.0, 0.0],
            end_tangent: [1.0, 2.0],
            mids: Vec::new(),
        };
        let sp = fit(&samples, &breaks);
        assert!(
            max_error(&sp, &samples) < 1e-9,
            "{}",
            max_error(&sp, &samples)
        );
        for b in sp.beziers() {
            for i in 0..=4 {
                let p = b.point(i as f64 / 4.0);
                assert!((p[1] - p[0] * p[0]).abs() < 1e-9);
            }
        }
    }

    /// A quarter circle on two spans: parameter correction lowers the error (the samples'
    /// distance to the fit, no longer the same-parameter drift), keeps the parameters in
    /// order with the ends fixed, and its midpoints check still sees the curve.
    #[test]
    fn parameter_correction_measures_distance_not_drift() {
        let n = 64;
        let params: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
        let arc = |s: f64| {
            let a = s * std::f64::consts::FRAC_PI_2;
            [a.cos(), a.sin()]
        };
        let points: Vec<P2> = params.iter().map(|&s| arc(s)).collect();
        let mids = params
            .windows(2)
            .map(|w| arc(0.5 * (w[0] + w[1])))
            .collect();
        let samples = Samples {
            params,
            points,
            start_tangent: [0.0, 1.0],
            end_tangent: [-1.0, 0.0],
            mids,
        };
        let breaks = uniform_breaks(2);
        let plain = fit(&samples, &breaks);
        let (corrected, at, e1) = fit_corrected(&samples, &samples.params, &breaks, 0.0);
        let e0 = max_error(&plain, &samples);
        assert_eq!(e1, max_error_at(&corrected, &samples, &at, f64::INFINITY));
        assert!(e1 < 0.8 * e0, "{e0:e} → {e1:e}");
        assert!(at.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!((at[0], at[n]), (0.0, 1.0));
        // e1 bounds the true distance from the arc to the fit, sampled densely.
        for i in 0..=1000 {
            let p = arc(i as f64 / 1000.0);
            let d = (0..=4000)
                .map(|k| dist(corrected.point(k as f64 / 4000.0), p))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= e1 * 1.01, "{d:e} > {e1:e}");
        }
    }
}
