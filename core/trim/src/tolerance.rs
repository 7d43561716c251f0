//! From the world tolerance ε to a tolerance in the parameter plane (paper 000, section 3.1:
//! "an approximation error expressed in parameter space, computed from ε").
//!
//! A parameter-plane displacement δ = (δu, δv) moves the surface point by about
//! `J δ = ∂S/∂u δu + ∂S/∂v δv`, and `|J δ| ≤ (|∂S/∂u| |δu| + |∂S/∂v| |δv|)
//! ≤ √(Mu² + Mv²) |δ|` with Mu, Mv bounds of the partial derivatives' lengths over the face.
//! So a trim approximation within `ε_uv = ε / √(Mu² + Mv²)` in (u, v) stays within ε in the
//! world. Mu and Mv are taken as the largest lengths on a grid over the face's bounds,
//! times a safety factor for what lies between the samples: conservative (an upper bound of
//! the displacement) wherever the derivatives do not peak sharply between grid points.

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
    /// `ε / √(Mu² + Mv²)`: the largest (u, v) distance allowed between a trim and its
    /// approximation.
    pub eps_uv: f64,
}

/// The (u, v) tolerance of `face` for the world tolerance `eps_world`. Where the derivatives
/// are not finite or vanish everywhere (a degenerate surface) the derivative bound is taken as
/// 1, and the result is kept above 1e-9 of the bounds' size so fitting terminates.
pub fn uv_tolerance(face: &Face, eps_world: f64) -> UvTolerance {
    let [u0, u1, v0, v1] = face.bounds;
    let mut mu: f64 = 0.0;
    let mut mv: f64 = 0.0;
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
        }
    }
    let (mu, mv) = (mu * SAFETY, mv * SAFETY);
    let m = mu.hypot(mv);
    let m = if m > 0.0 && m.is_finite() { m } else { 1.0 };
    let size = (u1 - u0).hypot(v1 - v0);
    UvTolerance {
        eps_world,
        max_du: mu,
        max_dv: mv,
        eps_uv: (eps_world / m).max(size * 1e-9),
    }
}
