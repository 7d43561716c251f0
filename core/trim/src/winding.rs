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
    let mut w = 0;
    for q in curves {
        let b = q.control_box();
        if b[1] < u || b[2] > v || b[3] < v {
            continue;
        }
        let [p0, p1, p2] = q.p;
        let den = p0[1] - 2.0 * p1[1] + p2[1];
        let mut cuts = vec![0.0];
        if !q.line && den != 0.0 {
            let t = (p0[1] - p1[1]) / den;
            if t > 0.0 && t < 1.0 {
                cuts.push(t);
            }
        }
        cuts.push(1.0);
        for pair in cuts.windows(2) {
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
    }
    w
}
