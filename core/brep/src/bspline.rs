//! B-spline machinery shared by curves and surfaces: the flat knot vector expanded from OCP's
//! distinct knots + multiplicities (periodic ones unrolled, so one evaluator serves both),
//! the non-zero basis functions with their first derivatives at a parameter (Cox–de Boor),
//! and rational evaluation of curves and tensor-product surfaces from them.
//!
//! Periodic conventions follow OCP's `BSplCLib`: with distinct knots `k0 < … < km`
//! (period `T = km − k0`, first and last multiplicities equal), the `n = Σ mults − m_last`
//! poles repeat with period `n`, and the span starting at distinct knot `ki` uses the poles
//! from `Σ_{j ≤ i} mults_j − m_0` on (modulo n), as a non-periodic curve uses them from
//! `Σ_{j ≤ i} mults_j − degree − 1`.

use crate::vector::{Point, Point3};
use thiserror::Error;

/// The highest degree accepted (OCP's `Geom_BSplineCurve::MaxDegree`), so that basis values
/// fit in fixed arrays.
pub const MAX_DEGREE: usize = 25;

/// Why a knot vector is refused; the caller adds which element it belongs to.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum KnotError {
    /// Degree 0 or above [`MAX_DEGREE`].
    #[error("degree {degree} is outside 1..={MAX_DEGREE}")]
    Degree {
        /// The degree given.
        degree: usize,
    },
    /// `knots` and `mults` differ in length.
    #[error("{knots} knots but {mults} multiplicities")]
    Lengths {
        /// Number of knots.
        knots: usize,
        /// Number of multiplicities.
        mults: usize,
    },
    /// Fewer than two distinct knots.
    #[error("needs at least 2 distinct knots, got {count}")]
    TooFewKnots {
        /// Number of knots.
        count: usize,
    },
    /// A knot is NaN or infinite.
    #[error("knot {index} is not finite")]
    NonFinite {
        /// Index in `knots`.
        index: usize,
    },
    /// The distinct knots are not strictly increasing.
    #[error("knots are not strictly increasing: knot {index} ({value}) follows {previous}")]
    NotIncreasing {
        /// Index in `knots` of the offending knot.
        index: usize,
        /// The knot before it.
        previous: f64,
        /// The knot.
        value: f64,
    },
    /// A multiplicity below 1 or above the degree (degree + 1 at the ends when non-periodic).
    #[error("multiplicity {index} is {mult}; it must be from 1 to {max}")]
    Multiplicity {
        /// Index in `mults`.
        index: usize,
        /// The multiplicity.
        mult: u32,
        /// The largest allowed there.
        max: u32,
    },
    /// A periodic knot vector whose first and last multiplicities differ (they are one knot).
    #[error("periodic, but the first multiplicity ({first}) differs from the last ({last})")]
    PeriodicEnds {
        /// First multiplicity.
        first: u32,
        /// Last multiplicity.
        last: u32,
    },
    /// The multiplicities leave too few poles for the degree.
    #[error("the multiplicities give {poles} poles; degree {degree} needs at least {needed}")]
    TooFewPoles {
        /// Poles the knots imply.
        poles: usize,
        /// The degree.
        degree: usize,
        /// The least pole count.
        needed: usize,
    },
}

/// A checked knot vector in flat form, ready to evaluate basis functions.
#[derive(Clone, Debug, PartialEq)]
pub struct KnotVector {
    degree: usize,
    /// Flat knots; for periodic vectors, unrolled by whole periods on both sides.
    flat: Vec<f64>,
    /// Poles of the curve (periodic: distinct poles, before wrapping).
    poles: usize,
    periodic: bool,
    domain: [f64; 2],
}

/// The `degree + 1` basis functions that may be non-zero at a parameter, and their first
/// derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Basis {
    /// Index of the pole of `values[0]` (already reduced modulo the pole count when periodic).
    pub first: usize,
    /// `degree + 1`.
    pub count: usize,
    /// Pole count, for wrapping periodic indices.
    poles: usize,
    /// `N_{first+k}(t)`.
    pub values: [f64; MAX_DEGREE + 1],
    /// `N'_{first+k}(t)` (zero when only the values were asked for).
    pub derivs: [f64; MAX_DEGREE + 1],
}

impl Basis {
    /// The pole index of the `k`-th non-zero function (wrapping for periodic vectors).
    pub fn pole(&self, k: usize) -> usize {
        (self.first + k) % self.poles.max(1)
    }

    /// The pole indices of all `count` non-zero functions (one division-free pass, for the
    /// inner loops of surface evaluation).
    pub fn pole_indices(&self) -> [usize; MAX_DEGREE + 1] {
        let n = self.poles.max(1);
        let mut out = [0; MAX_DEGREE + 1];
        let mut i = self.first % n;
        for o in out.iter_mut().take(self.count) {
            *o = i;
            i += 1;
            if i == n {
                i = 0;
            }
        }
        out
    }
}

impl KnotVector {
    /// Checks `knots` + `mults` (OCP form) for a B-spline of `degree` and expands them.
    ///
    /// # Errors
    /// A [`KnotError`] for the first rule broken.
    pub fn new(
        degree: usize,
        knots: &[f64],
        mults: &[u32],
        periodic: bool,
    ) -> Result<KnotVector, KnotError> {
        if degree == 0 || degree > MAX_DEGREE {
            return Err(KnotError::Degree { degree });
        }
        if knots.len() != mults.len() {
            return Err(KnotError::Lengths {
                knots: knots.len(),
                mults: mults.len(),
            });
        }
        if knots.len() < 2 {
            return Err(KnotError::TooFewKnots { count: knots.len() });
        }
        if let Some(index) = knots.iter().position(|k| !k.is_finite()) {
            return Err(KnotError::NonFinite { index });
        }
        if let Some(i) = (1..knots.len()).find(|&i| knots[i] <= knots[i - 1]) {
            return Err(KnotError::NotIncreasing {
                index: i,
                previous: knots[i - 1],
                value: knots[i],
            });
        }
        let last = mults.len() - 1;
        let p = degree as u32;
        for (index, &mult) in mults.iter().enumerate() {
            let max = if !periodic && (index == 0 || index == last) {
                p + 1
            } else {
                p
            };
            if mult < 1 || mult > max {
                return Err(KnotError::Multiplicity { index, mult, max });
            }
        }
        let sum: usize = mults.iter().map(|&m| m as usize).sum();
        let domain = [knots[0], knots[last]];
        if periodic {
            if mults[0] != mults[last] {
                return Err(KnotError::PeriodicEnds {
                    first: mults[0],
                    last: mults[last],
                });
            }
            let n = sum - mults[last] as usize;
            if n < 2 {
                return Err(KnotError::TooFewPoles {
                    poles: n,
                    degree,
                    needed: 2,
                });
            }
            // One period of flat knots, k0 (m0 times) … k_{m−1}; the unrolled vector is that
            // sequence shifted by whole periods, from index −(p + 1 − m0) to n + p.
            let period: Vec<f64> = knots[..last]
                .iter()
                .zip(mults)
                .flat_map(|(&k, &m)| std::iter::repeat_n(k, m as usize))
                .collect();
            let t = domain[1] - domain[0];
            let lead = (degree + 1 - mults[0] as usize) as i64;
            let flat = (-lead..=(n + degree) as i64)
                .map(|q| {
                    let wraps = q.div_euclid(n as i64);
                    period[q.rem_euclid(n as i64) as usize] + wraps as f64 * t
                })
                .collect();
            Ok(KnotVector {
                degree,
                flat,
                poles: n,
                periodic,
                domain,
            })
        } else {
            let n = sum as i64 - degree as i64 - 1;
            if n < degree as i64 + 1 {
                return Err(KnotError::TooFewPoles {
                    poles: n.max(0) as usize,
                    degree,
                    needed: degree + 1,
                });
            }
            let flat = knots
                .iter()
                .zip(mults)
                .flat_map(|(&k, &m)| std::iter::repeat_n(k, m as usize))
                .collect();
            Ok(KnotVector {
                degree,
                flat,
                poles: n as usize,
                periodic,
                domain,
            })
        }
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The number of poles the curve must have (periodic: distinct poles).
    pub fn pole_count(&self) -> usize {
        self.poles
    }

    /// Whether the vector is periodic.
    pub fn is_periodic(&self) -> bool {
        self.periodic
    }

    /// `[first knot, last knot]`: the parameter range (one period when periodic).
    pub fn domain(&self) -> [f64; 2] {
        self.domain
    }

    /// The flat knots (periodic vectors unrolled: `pole_count + 2·degree + 2 − m0` knots).
    pub fn flat(&self) -> &[f64] {
        &self.flat
    }

    /// About how many polynomial pieces the range between `a` and `b` crosses (at least 1),
    /// so samplers can place a few points on each.
    pub fn pieces(&self, a: f64, b: f64) -> usize {
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        let inner = &self.flat[self.degree..self.flat.len() - self.degree];
        if self.periodic {
            let t = self.domain[1] - self.domain[0];
            let mut distinct = inner.to_vec();
            distinct.dedup();
            let per_period = distinct
                .iter()
                .filter(|&&k| k >= self.domain[0] && k < self.domain[1])
                .count();
            (((hi - lo) / t).min(1e3) * per_period as f64).ceil() as usize + 1
        } else {
            let mut distinct = inner.to_vec();
            distinct.dedup();
            distinct.iter().filter(|&&k| k > lo && k < hi).count() + 1
        }
    }

    /// The span index `s` (flat) with `flat[s] ≤ t < flat[s+1]`, the parameter wrapped into
    /// one period when periodic; outside a non-periodic domain the end spans extend the
    /// polynomial pieces.
    fn span(&self, t: f64) -> (usize, f64) {
        let p = self.degree;
        let t = if self.periodic {
            let len = self.domain[1] - self.domain[0];
            self.domain[0] + (t - self.domain[0]).rem_euclid(len)
        } else {
            t
        };
        // The last span that holds poles: flat[n + p − m0 + 1 …] for periodic vectors is
        // beyond the first period; the span search is limited to [p, len − p − 2].
        let hi = self.flat.len() - p - 2;
        let mut s = self.flat.partition_point(|&k| k <= t).saturating_sub(1);
        s = s.clamp(p, hi);
        while s > p && self.flat[s] >= self.flat[s + 1] {
            s -= 1;
        }
        (s, t)
    }

    /// The non-zero basis functions at `t` and their derivatives.
    pub fn basis(&self, t: f64) -> Basis {
        self.basis_with(t, true)
    }

    /// The non-zero basis functions at `t`, with their derivatives when `derivs` (else zeros).
    pub fn basis_with(&self, t: f64, derivs: bool) -> Basis {
        let p = self.degree;
        let (s, t) = self.span(t);
        let k = &self.flat;
        let mut n = [0.0; MAX_DEGREE + 1];
        let mut prev = [0.0; MAX_DEGREE + 1];
        let mut left = [0.0; MAX_DEGREE + 1];
        let mut right = [0.0; MAX_DEGREE + 1];
        n[0] = 1.0;
        for j in 1..=p {
            if j == p {
                prev[..p].copy_from_slice(&n[..p]);
            }
            left[j] = t - k[s + 1 - j];
            right[j] = k[s + j] - t;
            let mut saved = 0.0;
            for r in 0..j {
                let temp = n[r] / (right[r + 1] + left[j - r]);
                n[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            n[j] = saved;
        }
        // N'_{i,p} = p (N_{i,p−1} / (k[i+p] − k[i]) − N_{i+1,p−1} / (k[i+p+1] − k[i+1])),
        // with prev[r] = N_{s−p+1+r, p−1}.
        let mut d = [0.0; MAX_DEGREE + 1];
        let first = s - p;
        for (r, dr) in d
            .iter_mut()
            .enumerate()
            .take(if derivs { p + 1 } else { 0 })
        {
            let i = first + r;
            let mut v = 0.0;
            if r >= 1 {
                let den = k[i + p] - k[i];
                if den > 0.0 {
                    v += prev[r - 1] / den;
                }
            }
            if r < p {
                let den = k[i + p + 1] - k[i + 1];
                if den > 0.0 {
                    v -= prev[r] / den;
                }
            }
            *dr = p as f64 * v;
        }
        Basis {
            first: if self.periodic {
                first % self.poles
            } else {
                first
            },
            count: p + 1,
            poles: self.poles,
            values: n,
            derivs: d,
        }
    }
}

/// A point of a (rational) B-spline curve and its first derivative, or `None` when the poles
/// or weights do not match the knot vector.
pub fn eval_curve<P: Point>(
    kv: &KnotVector,
    poles: &[P],
    weights: Option<&[f64]>,
    t: f64,
) -> Option<(P, P)> {
    if poles.len() != kv.pole_count() || weights.is_some_and(|w| w.len() != poles.len()) {
        return None;
    }
    let b = kv.basis(t);
    let idx = b.pole_indices();
    let (mut a, mut da) = (P::ZERO, P::ZERO);
    let (mut w, mut dw) = (0.0, 0.0);
    for (k, &i) in idx[..b.count].iter().enumerate() {
        let wi = weights.map_or(1.0, |ws| ws[i]);
        a = a + poles[i] * (b.values[k] * wi);
        da = da + poles[i] * (b.derivs[k] * wi);
        w += b.values[k] * wi;
        dw += b.derivs[k] * wi;
    }
    let c = a * (1.0 / w);
    Some((c, (da - c * dw) * (1.0 / w)))
}

/// The u and v bases at (u, v) with their pole indices.
fn tensor_basis(
    ku: &KnotVector,
    kv: &KnotVector,
    u: f64,
    v: f64,
    derivs: bool,
) -> [(Basis, [usize; MAX_DEGREE + 1]); 2] {
    [ku.basis_with(u, derivs), kv.basis_with(v, derivs)].map(|b| (b, b.pole_indices()))
}

/// A point of a (rational) tensor-product B-spline surface without its derivatives (a third of
/// the sums of [`eval_surface`]), for poles and weights that [`surface_fits`] accepted.
pub fn eval_surface_point(
    ku: &KnotVector,
    kv: &KnotVector,
    poles: &[Vec<Point3>],
    weights: Option<&[Vec<f64>]>,
    u: f64,
    v: f64,
) -> Point3 {
    let [(bu, iu), (bv, iv)] = tensor_basis(ku, kv, u, v, false);
    let mut a = Point3::ZERO;
    let mut w = 0.0;
    for (ku_, &i) in iu[..bu.count].iter().enumerate() {
        let row = &poles[i];
        let wrow = weights.map(|ws| &ws[i]);
        let mut ra = Point3::ZERO;
        let mut rw = 0.0;
        for (kv_, &j) in iv[..bv.count].iter().enumerate() {
            let n = bv.values[kv_] * wrow.map_or(1.0, |r| r[j]);
            ra += row[j] * n;
            rw += n;
        }
        a += ra * bu.values[ku_];
        w += rw * bu.values[ku_];
    }
    a * (1.0 / w)
}

/// Whether the poles (and weights) match the knot vectors' pole counts.
pub fn surface_fits(
    ku: &KnotVector,
    kv: &KnotVector,
    poles: &[Vec<Point3>],
    weights: Option<&[Vec<f64>]>,
) -> bool {
    poles.len() == ku.pole_count()
        && poles.iter().all(|row| row.len() == kv.pole_count())
        && weights.is_none_or(|ws| {
            ws.len() == poles.len() && ws.iter().all(|row| row.len() == kv.pole_count())
        })
}

/// A point of a (rational) tensor-product B-spline surface and its two partial derivatives
/// `(S, ∂S/∂u, ∂S/∂v)`, for poles and weights that [`surface_fits`] accepted (checked once per
/// surface, not per point).
pub fn eval_surface(
    ku: &KnotVector,
    kv: &KnotVector,
    poles: &[Vec<Point3>],
    weights: Option<&[Vec<f64>]>,
    u: f64,
    v: f64,
) -> (Point3, Point3, Point3) {
    let [(bu, iu), (bv, iv)] = tensor_basis(ku, kv, u, v, true);
    let zero = Point3::ZERO;
    let (mut a, mut au, mut av) = (zero, zero, zero);
    let (mut w, mut wu, mut wv) = (0.0, 0.0, 0.0);
    for (ku_, &i) in iu[..bu.count].iter().enumerate() {
        let row = &poles[i];
        let wrow = weights.map(|ws| &ws[i]);
        for (kv_, &j) in iv[..bv.count].iter().enumerate() {
            let wij = wrow.map_or(1.0, |r| r[j]);
            let p = row[j];
            let n = bu.values[ku_] * bv.values[kv_] * wij;
            let nu = bu.derivs[ku_] * bv.values[kv_] * wij;
            let nv = bu.values[ku_] * bv.derivs[kv_] * wij;
            a += p * n;
            au += p * nu;
            av += p * nv;
            w += n;
            wu += nu;
            wv += nv;
        }
    }
    let s = a * (1.0 / w);
    (s, (au - s * wu) * (1.0 / w), (av - s * wv) * (1.0 / w))
}
