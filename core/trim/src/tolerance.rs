//! From the world tolerance ε to a tolerance in the parameter plane (paper 000, section 3.1:
//! "an approximation error expressed in parameter space, computed from ε").
//!
//! A parameter-plane displacement δ = (δu, δv) moves the surface point by
//! `S(p + δ) − S(p) = ∫₀¹ J(p + τδ) δ dτ`, J = [∂S/∂u ∂S/∂v] the 3 × 2 Jacobian, so
//! `|S(p + δ) − S(p)| ≤ σ |δ|` with σ a bound of J's largest singular value (its operator
//! norm, `√λmax(JᵀJ)`) over the face. A trim approximation within `ε_uv = ε / σ` in (u, v)
//! therefore stays within ε in the world. σ is taken as the largest singular value on a grid
//! over the face's bounds, times a safety factor for what lies between the samples:
//! conservative wherever the derivatives do not peak sharply between grid points.
//!
//! (An earlier bound, `√(Mu² + Mv²)` with Mu, Mv the largest |∂S/∂u|, |∂S/∂v|, is also an upper
//! bound of |J δ| / |δ| but never a smaller one, by √2 on a plane or any surface with
//! orthogonal, equally fast directions: a looser tolerance now gives fewer pieces for the
//! same world guarantee.)

use tessd_brep::Face;
use tessd_brep::vector::Vector;

/// Grid points per direction when bounding the derivatives.
pub const GRID: usize = 17;

/// The factor applied to the sampled maxima for the variation between grid points.
pub const SAFETY: f64 = 1.25;

/// The parameter-plane tolerance of one face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTolerance {
    /// The world tolerance it came from.
    pub eps_world: f64,
    /// The bound of |∂S/∂u| over the bounds (safety factor included).
    pub max_du: f64,
    /// The bound of |∂S/∂v| over the bounds (safety factor included).
    pub max_dv: f64,
    /// The bound σ of the Jacobian's largest singular value over the bounds (safety factor
    /// included): `|S(p + δ) − S(p)| ≤ σ |δ|`.
    pub max_stretch: f64,
    /// `ε / σ`: the largest (u, v) distance allowed between a trim and its approximation.
    pub eps_uv: f64,
}

/// The (u, v) tolerance of `face` for the world tolerance `eps_world`. Where the derivatives
/// are not finite or vanish everywhere (a degenerate surface) the derivative bound is taken as
/// 1, and the result is kept above 1e-9 of the bounds' size so fitting terminates.
pub fn uv_tolerance(face: &Face, eps_world: f64) -> UvTolerance {
    let [u0, u1, v0, v1] = face.bounds;
    let mut mu: f64 = 0.0;
    let mut mv: f64 = 0.0;
    let mut ms: f64 = 0.0;
    for i in 0..GRID {
        let u = u0 + (u1 - u0) * i as f64 / (GRID - 1) as f64;
        for j in 0..GRID {
            let v = v0 + (v1 - v0) * j as f64 / (GRID - 1) as f64;
            let sp = face.surface.eval(u, v);
            let (a, b) = (sp.du.norm(), sp.dv.norm());
            if a.is_finite() {
                mu = mu.max(a);
            }
            if b.is_finite() {
                mv = mv.max(b);
            }
            let s = largest_singular_value(sp.du, sp.dv);
            if s.is_finite() {
                ms = ms.max(s);
            }
        }
    }
    let (mu, mv, ms) = (mu * SAFETY, mv * SAFETY, ms * SAFETY);
    let m = if ms > 0.0 && ms.is_finite() { ms } else { 1.0 };
    let size = (u1 - u0).hypot(v1 - v0);
    UvTolerance {
        eps_world,
        max_du: mu,
        max_dv: mv,
        max_stretch: ms,
        eps_uv: (eps_world / m).max(size * 1e-9),
    }
}

/// The largest singular value of the 3 × 2 matrix [a b]: `√λmax` of the Gram matrix
/// `[[a·a, a·b], [a·b, b·b]]`, `λmax = (E + G) / 2 + √(((E − G) / 2)² + F²)`. Rounded up
/// by a few ulps, so that it never falls below |a| or |b| by rounding.
pub fn largest_singular_value(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let (e, f, g) = (dot(a, a), dot(a, b), dot(b, b));
    let half = 0.5 * (e - g);
    let lambda = 0.5 * (e + g) + half.hypot(f);
    lambda.sqrt() * (1.0 + 8.0 * f64::EPSILON)
}
