//! Quadratic Bézier curves of the parameter plane (paper 000, section 3.1): evaluation,
//! de Casteljau subdivision and sub-curves (used for the separating lines of section 5.2),
//! and the flatness test that turns nearly straight pieces into line segments.

/// A point of the parameter plane.
pub type P2 = [f64; 2];

/// A quadratic Bézier `p0 (1−t)² + 2 p1 t(1−t) + p2 t²`, t ∈ [0, 1], or a line segment
/// (`line`, with `p1` the midpoint so that the Bézier form still describes it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadratic {
    /// The control points.
    pub p: [P2; 3],
    /// Whether this piece is a straight segment from `p[0]` to `p[2]`.
    pub line: bool,
}

pub(crate) fn lerp(a: P2, b: P2, t: f64) -> P2 {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

pub(crate) fn dist(a: P2, b: P2) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

impl Quadratic {
    /// A curved piece.
    pub fn new(p0: P2, p1: P2, p2: P2) -> Quadratic {
        Quadratic {
            p: [p0, p1, p2],
            line: false,
        }
    }

    /// A straight segment from `a` to `b`.
    pub fn segment(a: P2, b: P2) -> Quadratic {
        Quadratic {
            p: [a, lerp(a, b, 0.5), b],
            line: true,
        }
    }

    /// B(t).
    pub fn point(&self, t: f64) -> P2 {
        let [a, b, c] = self.p;
        let s = 1.0 - t;
        [
            s * s * a[0] + 2.0 * s * t * b[0] + t * t * c[0],
            s * s * a[1] + 2.0 * s * t * b[1] + t * t * c[1],
        ]
    }

    /// B'(t).
    pub fn derivative(&self, t: f64) -> P2 {
        let [a, b, c] = self.p;
        let s = 1.0 - t;
        [
            2.0 * (s * (b[0] - a[0]) + t * (c[0] - b[0])),
            2.0 * (s * (b[1] - a[1]) + t * (c[1] - b[1])),
        ]
    }

    /// De Casteljau at `t`: the pieces over [0, t] and [t, 1].
    pub fn split(&self, t: f64) -> (Quadratic, Quadratic) {
        let [a, b, c] = self.p;
        let ab = lerp(a, b, t);
        let bc = lerp(b, c, t);
        let m = lerp(ab, bc, t);
        (
            Quadratic {
                p: [a, ab, m],
                line: self.line,
            },
            Quadratic {
                p: [m, bc, c],
                line: self.line,
            },
        )
    }

    /// The piece over `[t0, t1]`, from the blossom `b(t0,t0), b(t0,t1), b(t1,t1)`.
    pub fn sub(&self, t0: f64, t1: f64) -> Quadratic {
        let blossom = |s: f64, t: f64| {
            let [a, b, c] = self.p;
            let w0 = (1.0 - s) * (1.0 - t);
            let w1 = (1.0 - s) * t + s * (1.0 - t);
            let w2 = s * t;
            [
                w0 * a[0] + w1 * b[0] + w2 * c[0],
                w0 * a[1] + w1 * b[1] + w2 * c[1],
            ]
        };
        Quadratic {
            p: [blossom(t0, t0), blossom(t0, t1), blossom(t1, t1)],
            line: self.line,
        }
    }

    /// The largest distance between B(t) and the chord's linear parametrisation
    /// `p0 + t (p2 − p0)`: `B(t) − L(t) = 2t(1−t)(p1 − (p0+p2)/2)`, largest at t = ½.
    pub fn flatness(&self) -> f64 {
        let [a, b, c] = self.p;
        dist(b, lerp(a, c, 0.5)) / 2.0
    }

    /// This piece as a line segment when its [`Quadratic::flatness`] is within `tol`
    /// ("flat ones to lines", section 3.1).
    pub fn flattened(self, tol: f64) -> Quadratic {
        if !self.line && self.flatness() <= tol {
            Quadratic::segment(self.p[0], self.p[2])
        } else {
            self
        }
    }

    /// `[min u, max u, min v, max v]` of the control points (a box holding the curve).
    pub fn control_box(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for q in &self.p {
            b[0] = b[0].min(q[0]);
            b[1] = b[1].max(q[0]);
            b[2] = b[2].min(q[1]);
            b[3] = b[3].max(q[1]);
        }
        b
    }

    /// The piece with every control point mapped by `f` (affine maps keep it exact).
    pub fn map(&self, f: impl Fn(P2) -> P2) -> Quadratic {
        Quadratic {
            p: [f(self.p[0]), f(self.p[1]), f(self.p[2])],
            line: self.line,
        }
    }

    /// The parameters t ∈ [0, 1] where coordinate `axis` of B(t) equals `c`.
    pub fn solve(&self, axis: usize, c: f64) -> Vec<f64> {
        let (a0, a1, a2) = (self.p[0][axis], self.p[1][axis], self.p[2][axis]);
        // B(t) = a0 + 2t(a1 − a0) + t²(a0 − 2a1 + a2)
        let qa = a0 - 2.0 * a1 + a2;
        let qb = 2.0 * (a1 - a0);
        let qc = a0 - c;
        let scale = a0
            .abs()
            .max(a1.abs())
            .max(a2.abs())
            .max(c.abs())
            .max(1e-300);
        let mut roots = Vec::with_capacity(2);
        if qa.abs() <= 1e-14 * scale {
            if qb.abs() > 1e-300 {
                roots.push(-qc / qb);
            }
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc >= 0.0 {
                let sq = disc.sqrt();
                let q = -0.5 * (qb + qb.signum() * sq);
                if q != 0.0 {
                    roots.push(q / qa);
                    roots.push(qc / q);
                } else {
                    roots.push(0.0);
                }
            }
        }
        roots.retain(|t| (-1e-12..=1.0 + 1e-12).contains(t));
        for t in &mut roots {
            *t = t.clamp(0.0, 1.0);
        }
        roots
    }

    /// The parameter interval of the part of the curve inside the rectangle
    /// `[u0, u1] × [v0, v1]` (the hull of all parts), or `None` when the curve misses it.
    /// Touching counts as crossing, so the quadtree errs towards subdividing.
    pub fn clip(&self, r: [f64; 4]) -> Option<[f64; 2]> {
        let b = self.control_box();
        if b[1] < r[0] || b[0] > r[1] || b[3] < r[2] || b[2] > r[3] {
            return None;
        }
        let inside = |q: P2| q[0] >= r[0] && q[0] <= r[1] && q[1] >= r[2] && q[1] <= r[3];
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut add = |t: f64| {
            lo = lo.min(t);
            hi = hi.max(t);
        };
        if inside(self.p[0]) {
            add(0.0);
        }
        if inside(self.p[2]) {
            add(1.0);
        }
        for (axis, c, other) in [(0, r[0], 1), (0, r[1], 1), (1, r[2], 0), (1, r[3], 0)] {
            let (o0, o1) = if other == 1 {
                (r[2], r[3])
            } else {
                (r[0], r[1])
            };
            for t in self.solve(axis, c) {
                let q = self.point(t)[other];
                if q >= o0 && q <= o1 {
                    add(t);
                }
            }
        }
        (lo <= hi).then_some([lo, hi])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_and_sub_agree_with_evaluation() {
        let q = Quadratic::new([0.0, 0.0], [1.0, 2.0], [3.0, 0.5]);
        let (a, b) = q.split(0.3);
        for i in 0..=10 {
            let t = i as f64 / 10.0;
            let pa = a.point(t);
            let qa = q.point(0.3 * t);
            assert!(dist(pa, qa) < 1e-12);
            let pb = b.point(t);
            let qb = q.point(0.3 + 0.7 * t);
            assert!(dist(pb, qb) < 1e-12);
            let s = q.sub(0.2, 0.9).point(t);
            assert!(dist(s, q.point(0.2 + 0.7 * t)) < 1e-12);
        }
    }

    #[test]
    fn flatness_and_clip() {
        let q = Quadratic::new([0.0, 0.0], [0.5, 1e-4], [1.0, 0.0]);
        assert!((q.flatness() - 5e-5).abs() < 1e-15);
        assert!(q.flattened(1e-4).line);
        assert!(!q.flattened(1e-5).line);
        let c = Quadratic::new([0.0, 0.0], [1.0, 2.0], [2.0, 0.0]);
        // apex at (1, 1)
        assert!(c.clip([0.9, 1.1, 0.99, 1.2]).is_some());
        assert!(c.clip([0.9, 1.1, 1.01, 1.2]).is_none());
        let [t0, t1] = c.clip([-1.0, 1.0, -1.0, 2.0]).unwrap();
        assert!(t0 == 0.0 && (t1 - 0.5).abs() < 1e-12);
    }
}
