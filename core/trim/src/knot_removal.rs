//! Knot removal to a tolerance (paper 000, section 3.1, after Lyche and Mørken [LM87, LM88]):
//! the densely knotted uniform fit is thinned, knots of least significance first, as long as
//! the spline stays within the (u, v) tolerance of the input curve's samples.
//!
//! As in Lyche–Mørken's data-reduction strategy, every interior knot gets a *weight*: how
//! much the spline would have to change for that knot to go (the discrepancy between the
//! two ways of recovering the reduced spline's pole from the current poles, left and right of
//! the knot). The lightest half of the knots is removed at once, the spline refitted by least
//! squares on the reduced knots and checked against the tolerance; on failure half as many
//! are tried, down to one; the weights are recomputed after every success. The process stops
//! when not even the lightest knot can go.

use crate::bezier::{P2, dist};
use crate::quadratic_fit::{QuadSpline, Samples, fit_corrected, knot_vector};

/// The weight of each interior breakpoint `breaks[1 ..= L−1]` (index into `breaks`).
pub fn knot_weights(spline: &QuadSpline) -> Vec<(usize, f64)> {
    let tk = knot_vector(&spline.breaks); // T', length n + 3
    let q = &spline.poles;
    let mut out = Vec::new();
    for b in 1..spline.breaks.len() - 1 {
        let r = b + 2; // index of the knot in T'
        let t = tk[r];
        // The reduced vector T is T' without index r; T[i] = T'[i] below r, T'[i+1] from r.
        let tr = |i: usize| if i < r { tk[i] } else { tk[i + 1] };
        let k = r - 1; // span of t in T
        let a1 = (t - tr(k - 1)) / (tr(k + 1) - tr(k - 1));
        let a2 = (t - tr(k)) / (tr(k + 2) - tr(k));
        // Q[k−1] = a1 P[k−1] + (1 − a1) P[k−2],  Q[k] = a2 P[k] + (1 − a2) P[k−1],
        // P[k−2] = Q[k−2], P[k] = Q[k+1].
        let left: P2 = [
            (q[k - 1][0] - (1.0 - a1) * q[k - 2][0]) / a1,
            (q[k - 1][1] - (1.0 - a1) * q[k - 2][1]) / a1,
        ];
        let right: P2 = [
            (q[k][0] - a2 * q[k + 1][0]) / (1.0 - a2),
            (q[k][1] - a2 * q[k + 1][1]) / (1.0 - a2),
        ];
        let w = dist(left, right);
        out.push((b, if w.is_finite() { w } else { f64::INFINITY }));
    }
    out
}

/// Removes knots from `spline` while the refit stays within `tol` of `samples`
/// (see the module text). Each refit corrects the samples' parameters
/// ([`fit_corrected`]), so the tolerance is checked against the samples' distance to the
/// curve rather than to the point of the same parameter. Returns the thinned spline (the
/// input when nothing can go) and the samples' parameters it was fitted at.
pub fn remove_knots(samples: &Samples, spline: QuadSpline, tol: f64) -> (QuadSpline, Vec<f64>) {
    let mut current = spline;
    let mut at = samples.params.clone();
    loop {
        let mut weights = knot_weights(&current);
        if weights.is_empty() {
            return (current, at);
        }
        weights.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut count = weights.len().div_ceil(2);
        let mut accepted = None;
        while count >= 1 {
            let mut drop: Vec<usize> = weights[..count].iter().map(|w| w.0).collect();
            drop.sort_unstable();
            let breaks: Vec<f64> = current
                .breaks
                .iter()
                .enumerate()
                .filter(|(i, _)| drop.binary_search(i).is_err())
                .map(|(_, &b)| b)
                .collect();
            let (candidate, fitted_at, error) = fit_corrected(samples, &at, &breaks, tol);
            if error <= tol {
                accepted = Some((candidate, fitted_at));
                break;
            }
            count /= 2;
        }
        match accepted {
            Some((c, a)) => (current, at) = (c, a),
            None => return (current, at),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadratic_fit::{fit, uniform_breaks};

    #[test]
    fn a_parabola_needs_one_span() {
        let params: Vec<f64> = (0..=200).map(|i| i as f64 / 200.0).collect();
        let points: Vec<P2> = params.iter().map(|&s| [s, 3.0 * s * s]).collect();
        let samples = Samples {
            params,
            points,
            start_tangent: [1.0, 0.0],
            end_tangent: [1.0, 6.0],
            mids: Vec::new(),
        };
        let dense = fit(&samples, &uniform_breaks(40));
        let weights = knot_weights(&dense);
        assert!(weights.iter().all(|w| w.1 < 1e-9), "{weights:?}");
        let (thin, _) = remove_knots(&samples, dense, 1e-9);
        assert_eq!(thin.breaks.len(), 2);
    }
}
