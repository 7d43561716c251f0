//! The winding number of a point with respect to closed chains of quadratic pieces, by a ray
//! cast towards +u. With loops in the normalised orientation (outer counter-clockwise,
//! holes clockwise, islands counter-clockwise) the face's material is where it is positive.
//! The quadtree uses it to tell curve-free cells on from off (section 4), and for the
//! coverage of cells it gives up on.

use crate::bezier::Quadratic;

/// Σ over the curves of their signed crossings of the ray from (u, v) towards +u (upward +1).
/// Each curve is cut at its v-extremum into monotone parts; a part counts when
/// `v_start ≤ v < v_end` (or the reverse), so shared end points count once.
pub fn winding(curves: &[Quadratic], u: f64, v: f64) -> i32 {
    curves
        .iter()
        .map(|q| crossings(q, &q.control_box(), u, v))
        .sum()
}

/// The signed crossings of one curve (control box `b`) with the ray from (u, v) towards +u.
fn crossings(q: &Quadratic, b: &[f64; 4], u: f64, v: f64) -> i32 {
    if b[1] < u || b[2] > v || b[3] < v {
        return 0;
    }
    let [p0, p1, p2] = q.p;
    let den = p0[1] - 2.0 * p1[1] + p2[1];
    let mut cuts = [0.0, 1.0, 1.0];
    let mut parts = 1;
    if !q.line && den != 0.0 {
        let t = (p0[1] - p1[1]) / den;
        if t > 0.0 && t < 1.0 {
            cuts[1] = t;
            parts = 2;
        }
    }
    let mut w = 0;
    for pair in cuts[..=parts].windows(2) {
        let (ta, tb) = (pair[0], pair[1]);
        let (va, vb) = (q.point(ta)[1], q.point(tb)[1]);
        let sign = if va <= v && v < vb {
            1
        } else if vb <= v && v < va {
            -1
        } else {
            continue;
        };
        // v(t) = v on [ta, tb], monotone: bisection.
        let (mut lo, mut hi) = (ta, tb);
        let up = vb > va;
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if (q.point(mid)[1] < v) == up {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        if q.point(0.5 * (lo + hi))[0] > u {
            w += sign;
        }
    }
    w
}

/// [`winding`] for many points against the same curves: the curves' control boxes are
/// bucketed by v, so a point visits only the curves whose v-range can hold it instead of all
/// of them (the quadtree asks once per empty leaf, and a face with hundreds of holes has
/// thousands of pieces and of empty leaves). The answer is exactly [`winding`]'s: a curve
/// left out of the point's bucket fails the control-box test anyway.
pub struct WindingIndex<'a> {
    curves: &'a [Quadratic],
    boxes: Vec<[f64; 4]>,
    v0: f64,
    scale: f64,
    /// Curve indices per bucket, bucket k holding v in `[v0 + k / scale, v0 + (k+1) / scale)`.
    buckets: Vec<Vec<u32>>,
}

impl<'a> WindingIndex<'a> {
    /// The index of `curves`.
    pub fn new(curves: &'a [Quadratic]) -> WindingIndex<'a> {
        let boxes: Vec<[f64; 4]> = curves.iter().map(Quadratic::control_box).collect();
        let (lo, hi) = boxes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), b| {
                (l.min(b[2]), h.max(b[3]))
            });
        let count = curves.len().div_ceil(4).max(1);
        let scale = if hi > lo && (hi - lo).is_finite() {
            count as f64 / (hi - lo)
        } else {
            0.0
        };
        let mut index = WindingIndex {
            curves,
            boxes,
            v0: if lo.is_finite() { lo } else { 0.0 },
            scale,
            buckets: vec![Vec::new(); count],
        };
        for (i, b) in index.boxes.iter().enumerate() {
            let (k0, k1) = (index.bucket(b[2]), index.bucket(b[3]));
            for k in k0..=k1 {
                index.buckets[k].push(i as u32);
            }
        }
        index
    }

    /// The bucket of `v`, clamped to the first and last; monotone in `v`.
    fn bucket(&self, v: f64) -> usize {
        let k = ((v - self.v0) * self.scale).floor();
        if k >= 0.0 {
            (k as usize).min(self.buckets.len() - 1)
        } else {
            0
        }
    }

    /// [`winding`]`(curves, u, v)`.
    pub fn winding(&self, u: f64, v: f64) -> i32 {
        if v.is_nan() {
            return winding(self.curves, u, v);
        }
        self.buckets[self.bucket(v)]
            .iter()
            .map(|&i| crossings(&self.curves[i as usize], &self.boxes[i as usize], u, v))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The index answers as the scan over all curves, inside, outside and on the curves'
    /// v-range boundaries.
    #[test]
    fn the_index_agrees_with_the_scan() {
        let mut curves = Vec::new();
        for k in 0..30 {
            let (cx, cy, r) = (0.1 + 0.03 * k as f64, 0.2 + 0.02 * (k % 7) as f64, 0.01);
            let pts: Vec<[f64; 2]> = (0..8)
                .map(|i| {
                    let a = i as f64 * std::f64::consts::TAU / 8.0;
                    [cx + r * a.cos(), cy + r * a.sin()]
                })
                .collect();
            for i in 0..8 {
                let (a, b) = (pts[i], pts[(i + 1) % 8]);
                let m = [0.5 * (a[0] + b[0]) * 1.01, 0.5 * (a[1] + b[1])];
                curves.push(if i % 3 == 0 {
                    Quadratic::segment(a, b)
                } else {
                    Quadratic::new(a, m, b)
                });
            }
        }
        let index = WindingIndex::new(&curves);
        for i in 0..=200 {
            for j in 0..=200 {
                let (u, v) = (i as f64 / 200.0, 0.15 + 0.2 * j as f64 / 200.0);
                assert_eq!(index.winding(u, v), winding(&curves, u, v), "{u} {v}");
            }
        }
        for q in &curves {
            for p in q.p {
                assert_eq!(
                    index.winding(p[0] - 1e-3, p[1]),
                    winding(&curves, p[0] - 1e-3, p[1])
                );
            }
        }
        assert_eq!(WindingIndex::new(&[]).winding(0.5, 0.5), 0);
    }
}
