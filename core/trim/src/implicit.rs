//! The Loop–Blinn implicit form of a quadratic Bézier (paper 000, section 3.2) and the point
//! classification against one curve (section 5.1).
//!
//! A point (u, v) is taken to the curve's *quadratic space* (x, y) by the inverse of
//! `[u v 1]ᵀ = M [x y 1]ᵀ`, `M = [2(p1−p0) | p0−2p1+p2 | p0]`, so that p0, p1, p2 land on
//! (0, 0), (½, 0), (1, 1) and the curve is `y = x²`. (The paper prints the last column as
//! `−p0`; only `+p0` maps x = y = 0 to p0, so that is what is used.) The face lies left of
//! every curve; when the curve turns left (`det M > 0`) the face is locally convex and on
//! the face means `f = y − x² ≥ 0`, otherwise (concave) `f = x² − y ≥ 0`.
//!
//! Outside the control triangle the paper's tests of section 5.1 decide: off when `y < 0` or
//! `y − 2x + 1 < 0` (beyond the end tangents), on when `y − x ≥ 0` (beyond the chord), in the
//! convex case; inverted in the concave case. The region so described is the convex set
//! bounded by the arc and its two end tangents, which is also what triangle classification
//! (section 6) relies on. Line segments classify by the side of their line.
//!
//! The map is stored in `f32`, as the GPU reads it, and evaluated in `f64`, so the CPU
//! classifier and one reading the packed buffers agree bit for bit.

use crate::bezier::Quadratic;

/// How a curve classifies points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImplicitKind {
    /// A straight segment: `x = a u + b v + c ≥ 0` (x is the signed distance, left positive).
    Line = 0,
    /// Turning left: on the face where `y − x² ≥ 0` (section 3.2).
    Convex = 1,
    /// Turning right: on the face where `x² − y ≥ 0`.
    Concave = 2,
}

/// The implicit form of one curve: an affine map (u, v) → (x, y) and the curve's kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Implicit {
    /// `x = m[0] u + m[1] v + m[2]`, `y = m[3] u + m[4] v + m[5]`.
    pub m: [f32; 6],
    /// Line, convex or concave.
    pub kind: ImplicitKind,
}

impl Implicit {
    /// The implicit form of `q`. A curve whose control points are (nearly) collinear is
    /// classified by its chord, as a line.
    pub fn of(q: &Quadratic) -> Implicit {
        let [p0, p1, p2] = q.p;
        let a = [2.0 * (p1[0] - p0[0]), 2.0 * (p1[1] - p0[1])];
        let b = [p0[0] - 2.0 * p1[0] + p2[0], p0[1] - 2.0 * p1[1] + p2[1]];
        let det = a[0] * b[1] - b[0] * a[1];
        let scale = (a[0].hypot(a[1])) * (b[0].hypot(b[1]));
        if q.line || det.abs() <= 1e-9 * scale || det.abs() < 1e-300 {
            return Implicit::line(p0, p2);
        }
        let m = [
            b[1] / det,
            -b[0] / det,
            -(b[1] * p0[0] - b[0] * p0[1]) / det,
            -a[1] / det,
            a[0] / det,
            (a[1] * p0[0] - a[0] * p0[1]) / det,
        ];
        Implicit {
            m: m.map(|x| x as f32),
            kind: if det > 0.0 {
                ImplicitKind::Convex
            } else {
                ImplicitKind::Concave
            },
        }
    }

    fn line(p0: [f64; 2], p2: [f64; 2]) -> Implicit {
        let d = [p2[0] - p0[0], p2[1] - p0[1]];
        let len = d[0].hypot(d[1]).max(1e-300);
        let n = [-d[1] / len, d[0] / len];
        let c = -(n[0] * p0[0] + n[1] * p0[1]);
        Implicit {
            m: [n[0] as f32, n[1] as f32, c as f32, 0.0, 0.0, 0.0],
            kind: ImplicitKind::Line,
        }
    }

    /// (x, y) of the point in quadratic space (for a line, x is the signed distance).
    pub fn xy(&self, u: f64, v: f64) -> (f64, f64) {
        let m = self.m.map(f64::from);
        (m[0] * u + m[1] * v + m[2], m[3] * u + m[4] * v + m[5])
    }

    /// Whether (u, v) lies in the convex one of the two regions the curve bounds: for a
    /// convex or concave curve the region bounded by its arc and end tangents (section 5.1:
    /// inside the control triangle `y − x² ≥ 0`, outside it the triangle-edge tests).
    /// For a line, its left half-plane.
    pub fn in_convex_region(&self, u: f64, v: f64) -> bool {
        let (x, y) = self.xy(u, v);
        match self.kind {
            ImplicitKind::Line => x >= 0.0,
            _ => {
                if y < 0.0 || y - 2.0 * x + 1.0 < 0.0 {
                    false
                } else if y - x >= 0.0 {
                    true
                } else {
                    y - x * x >= 0.0
                }
            }
        }
    }

    /// Whether the convex region of [`Implicit::in_convex_region`] is on the face.
    pub fn convex_region_is_on(&self) -> bool {
        self.kind != ImplicitKind::Concave
    }

    /// Whether (u, v) is on the face according to this curve alone (section 5.1).
    pub fn classify(&self, u: f64, v: f64) -> bool {
        self.in_convex_region(u, v) == self.convex_region_is_on()
    }

    /// Whether a whole triangle classifies alike (section 6): its vertices all in the convex
    /// region (so is the triangle); for a line, all on one side. `Some(on)` then.
    pub fn classify_triangle(&self, tri: &[[f64; 2]; 3]) -> Option<bool> {
        let inside = tri.map(|p| self.in_convex_region(p[0], p[1]));
        if inside.iter().all(|&b| b) {
            Some(self.convex_region_is_on())
        } else if self.kind == ImplicitKind::Line && inside.iter().all(|&b| !b) {
            Some(false)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_points_map_to_the_canonical_triangle() {
        let q = Quadratic::new([1.0, 1.0], [2.0, 3.0], [4.0, 1.5]);
        let im = Implicit::of(&q);
        for (p, want) in q.p.iter().zip([(0.0, 0.0), (0.5, 0.0), (1.0, 1.0)]) {
            let (x, y) = im.xy(p[0], p[1]);
            assert!(
                (x - want.0).abs() < 1e-6 && (y - want.1).abs() < 1e-6,
                "{x} {y}"
            );
        }
        // The curve is y = x².
        for i in 0..=10 {
            let c = q.point(i as f64 / 10.0);
            let (x, y) = im.xy(c[0], c[1]);
            assert!((y - x * x).abs() < 1e-6);
        }
    }
}
