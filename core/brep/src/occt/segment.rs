//! Knot insertion (Boehm), for two exact jobs on B-spline curves: the control points of the
//! piece of a pcurve on its trim range (whose hull bounds the trim tightly), and the
//! non-periodic segment of a periodic B-spline whose trim range runs across its knot span (what
//! the exporters get from OCCT's `GeomConvert` of the trimmed curve; the format wants a
//! periodic B-spline's range inside its span).
//!
//! Curves are handled in homogeneous coordinates `(w·x, w·y, w·z, w)` (2D: z = 0), so rational
//! curves are cut exactly; inserting a knot never changes the curve nor its parameter.

use crate::model::BSplineCurve;
use crate::vector::Point;

/// A B-spline as flat knots and homogeneous poles (non-periodic: `flat.len() = poles + p + 1`,
/// domain `[flat[p], flat[poles]]`).
struct Flat {
    p: usize,
    flat: Vec<f64>,
    hom: Vec<[f64; 4]>,
}

fn homogeneous<P: Point>(b: &BSplineCurve<P>, i: usize) -> [f64; 4] {
    let w = b.weights.as_ref().map_or(1.0, |w| w[i]);
    let c = b.poles[i].coords();
    let mut h = [0.0, 0.0, 0.0, w];
    for (k, x) in c.iter().enumerate() {
        h[k] = x * w;
    }
    h
}

fn cartesian<P: Point>(h: &[f64; 4]) -> P {
    let mut p = P::ZERO;
    for (k, x) in p.coords_mut().iter_mut().enumerate() {
        *x = h[k] / h[3];
    }
    p
}

impl Flat {
    /// A non-periodic curve as it is.
    fn of<P: Point>(b: &BSplineCurve<P>) -> Flat {
        Flat {
            p: b.degree,
            flat: b
                .knots
                .iter()
                .zip(&b.mults)
                .flat_map(|(&k, &m)| std::iter::repeat_n(k, m as usize))
                .collect(),
            hom: (0..b.poles.len()).map(|i| homogeneous(b, i)).collect(),
        }
    }

    /// Inserts `u` until it has multiplicity `p` (so the curve passes through one of the
    /// poles there), when it lies strictly inside the domain.
    fn split_at(&mut self, u: f64) {
        let p = self.p;
        for _ in 0..p {
            let n = self.hom.len();
            if !(self.flat[p] < u && u < self.flat[n]) {
                return;
            }
            if self.flat.iter().filter(|&&k| k == u).count() >= p {
                return;
            }
            // The span k with flat[k] ≤ u < flat[k + 1]; poles k − p + 1 ..= k change.
            let k = self.flat.partition_point(|&x| x <= u) - 1;
            let mut q = Vec::with_capacity(n + 1);
            q.extend_from_slice(&self.hom[..=k - p]);
            for i in k - p + 1..=k {
                let a = (u - self.flat[i]) / (self.flat[i + p] - self.flat[i]);
                let (x, y) = (self.hom[i], self.hom[i - 1]);
                q.push(std::array::from_fn(|c| a * x[c] + (1.0 - a) * y[c]));
            }
            q.extend_from_slice(&self.hom[k..]);
            self.hom = q;
            self.flat.insert(k + 1, u);
        }
    }

    /// The poles ruling `[lo, hi]`: those of the spans meeting it.
    fn ruling(&self, lo: f64, hi: f64) -> &[[f64; 4]] {
        let (p, n) = (self.p, self.hom.len());
        let first = self
            .flat
            .partition_point(|&x| x <= lo)
            .saturating_sub(1)
            .clamp(p, n - 1)
            - p;
        let last = self
            .flat
            .partition_point(|&x| x < hi)
            .saturating_sub(1)
            .clamp(p, n - 1);
        &self.hom[first..=last.max(first)]
    }
}

/// The control points of the piece of `b` on `[lo, hi]` (all of them for a periodic curve):
/// the hull of these holds the piece (weights are positive).
pub(crate) fn piece_poles<P: Point>(b: &BSplineCurve<P>, lo: f64, hi: f64) -> Vec<P> {
    if b.periodic || b.poles.len() <= b.degree {
        return b.poles.clone();
    }
    let mut f = Flat::of(b);
    f.split_at(lo);
    f.split_at(hi);
    f.ruling(lo, hi).iter().map(cartesian).collect()
}

/// The periodic B-spline `b` on `[t0, t1]` (t0 < t1, any position relative to its knot span)
/// as a non-periodic clamped B-spline with the same parameter, or `None` when the range is
/// degenerate or spans more periods than is sane.
pub(crate) fn periodic_segment<P: Point>(
    b: &BSplineCurve<P>,
    t0: f64,
    t1: f64,
) -> Option<BSplineCurve<P>> {
    let (p, n) = (b.degree, b.poles.len());
    let last = b.knots.len() - 1;
    let (k0, period) = (b.knots[0], b.knots[last] - b.knots[0]);
    if !(t0 < t1 && period > 0.0) || (t1 - t0) / period > 64.0 {
        return None;
    }
    // One period of flat knots: k_0 (m_0 times) … k_{last−1}; F[q] = one[q mod n] + ⌊q/n⌋·T.
    let one: Vec<f64> = b.knots[..last]
        .iter()
        .zip(&b.mults)
        .flat_map(|(&k, &m)| std::iter::repeat_n(k, m as usize))
        .collect();
    if one.len() != n {
        return None;
    }
    let shift = ((t0 - k0) / period).floor();
    let (a, z) = (t0 - shift * period, t1 - shift * period);
    // Far from the span, the shifted range loses its digits: refuse rather than walk far.
    if !(a >= k0 && a <= k0 + period && z > a && z - a <= 64.0 * period) {
        return None;
    }
    let f = |q: i64| one[q.rem_euclid(n as i64) as usize] + q.div_euclid(n as i64) as f64 * period;
    // The span of F holding a, and the one ending at or after z.
    let mut sa = 0_i64;
    while f(sa + 1) <= a {
        sa += 1;
    }
    let mut sz = sa;
    while f(sz + 1) < z {
        sz += 1;
    }
    // Unrolled: flat knots U[i] = F[i + base], poles Q[i] = P[(i + base + p + 1 − m0) mod n]
    // (the span of F starting at k_i uses the poles from Σ_{j≤i} m_j − m_0 on, modulo n),
    // a period more on either side so that a and z are strictly inside the domain.
    let base = sa - p as i64 - n as i64;
    let count = (sz + 1 + n as i64 - base) as usize;
    let m0 = b.mults[0] as i64;
    let mut fl = Flat {
        p,
        flat: (0..count + p + 1).map(|i| f(i as i64 + base)).collect(),
        hom: (0..count)
            .map(|i| {
                let k = (i as i64 + base + p as i64 + 1 - m0).rem_euclid(n as i64) as usize;
                homogeneous(b, k)
            })
            .collect(),
    };
    fl.split_at(a);
    fl.split_at(z);
    // The pole at a (p copies of a from index ia) is Q[ia − 1]; likewise at z.
    let ia = fl.flat.iter().position(|&x| x == a)?;
    let iz = fl.flat.iter().position(|&x| x == z)?;
    if iz <= ia || ia == 0 {
        return None;
    }
    let hom = fl.hom.get(ia - 1..iz)?;
    let mut flat = vec![t0; p + 1];
    flat.extend(fl.flat.get(ia + p..iz)?.iter().map(|&k| k + shift * period));
    flat.extend(std::iter::repeat_n(t1, p + 1));
    let mut knots: Vec<f64> = Vec::new();
    let mut mults: Vec<u32> = Vec::new();
    for k in flat {
        match knots.last() {
            Some(&l) if l == k => *mults.last_mut()? += 1,
            Some(&l) if l > k => return None,
            _ => {
                knots.push(k);
                mults.push(1);
            }
        }
    }
    if mults.iter().sum::<u32>() as usize != hom.len() + p + 1 {
        return None;
    }
    Some(BSplineCurve {
        degree: p,
        poles: hom.iter().map(cartesian).collect(),
        weights: b
            .weights
            .as_ref()
            .map(|_| hom.iter().map(|h| h[3]).collect()),
        knots,
        mults,
        periodic: false,
        cache: Default::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Curve;
    use crate::vector::Point2;

    fn periodic_circle_like() -> BSplineCurve<Point2> {
        // A periodic rational quadratic: 4 poles on a square, weights 1, 0.5, 1, 0.5.
        BSplineCurve {
            degree: 2,
            poles: vec![
                Point2::new(1.0, 0.0),
                Point2::new(1.0, 1.0),
                Point2::new(-1.0, 1.0),
                Point2::new(-1.0, -1.0),
                Point2::new(1.0, -1.0),
            ],
            weights: Some(vec![1.0, 0.7, 1.3, 0.9, 1.1]),
            knots: vec![0.0, 1.0, 2.5, 3.0, 4.0, 5.0],
            mults: vec![1, 1, 1, 1, 1, 1],
            periodic: true,
            cache: Default::default(),
        }
    }

    #[test]
    fn a_segment_across_the_span_is_the_same_curve_at_the_same_parameter() {
        let b = periodic_circle_like();
        let whole = Curve::Bspline(b.clone());
        for (t0, t1) in [(3.7, 6.2), (-1.3, 0.4), (0.5, 4.5), (9.1, 12.0), (2.5, 3.0)] {
            let seg = periodic_segment(&b, t0, t1).unwrap();
            assert_eq!((seg.knots[0], *seg.knots.last().unwrap()), (t0, t1));
            seg.knot_vector().unwrap();
            let seg = Curve::Bspline(seg);
            for i in 0..=40 {
                let t = t0 + (t1 - t0) * i as f64 / 40.0;
                let (a, b) = (whole.point(t), seg.point(t));
                assert!((a - b).length() < 1e-12, "[{t0}, {t1}] at {t}: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn piece_poles_hold_the_piece_tightly() {
        let b = BSplineCurve {
            degree: 3,
            poles: vec![
                Point2::new(0.0, 0.0),
                Point2::new(1.0, 3.0),
                Point2::new(2.0, -3.0),
                Point2::new(3.0, 3.0),
                Point2::new(4.0, 0.0),
            ],
            weights: None,
            knots: vec![0.0, 0.5, 1.0],
            mults: vec![4, 1, 4],
            periodic: false,
            cache: Default::default(),
        };
        let c = Curve::Bspline(b.clone());
        let poles = piece_poles(&b, 0.6, 0.7);
        assert_eq!(poles.len(), 4);
        assert!((poles[0] - c.point(0.6)).length() < 1e-12);
        assert!((poles[3] - c.point(0.7)).length() < 1e-12);
    }
}
