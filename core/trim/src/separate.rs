//! The separating line of a two-curve cell (paper 000, section 5.2): a line with one curve
//! on each side, found among the edges of the curves' control polygons, subdivided by de
//! Casteljau until one of them works (the separating axis theorem: of two disjoint convex
//! polygons, an edge of one supports a separating line). Only the parts of the curves inside
//! the cell are considered.

use crate::bezier::Quadratic;

/// Rounds of subdivision tried before giving up (2^6 pieces per curve at the last).
pub const MAX_ROUNDS: u32 = 6;

fn points(q: &Quadratic) -> Vec<[f64; 2]> {
    if q.line {
        vec![q.p[0], q.p[2]]
    } else {
        q.p.to_vec()
    }
}

fn edges(q: &Quadratic) -> Vec<([f64; 2], [f64; 2])> {
    if q.line {
        vec![(q.p[0], q.p[2])]
    } else {
        vec![(q.p[0], q.p[1]), (q.p[1], q.p[2]), (q.p[0], q.p[2])]
    }
}

/// `(min, max)` of `n·p + c` over the pieces' control points.
fn range(pieces: &[Quadratic], l: [f64; 3]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for q in pieces {
        for p in points(q) {
            let d = l[0] * p[0] + l[1] * p[1] + l[2];
            lo = lo.min(d);
            hi = hi.max(d);
        }
    }
    (lo, hi)
}

/// A ray `origin + t·dir`, t ≥ 0.
pub type Ray = ([f64; 2], [f64; 2]);

/// Whether the rays of one curve stay out of that curve's side (`sign` = +1: the side where
/// the line is ≥ 0; −1: ≤ 0): a curve classifies its side of the cell by its implicit rule,
/// whose region is bounded by the arc *and* its end tangents, so an end tangent starting in
/// the cell (at a junction) must lead into the other curve's side, or along the line.
fn rays_stay_out(l: [f64; 3], rays: &[Ray], sign: f64, tol: f64) -> bool {
    rays.iter().all(|(o, d)| {
        let at = sign * (l[0] * o[0] + l[1] * o[1] + l[2]);
        let len = d[0].hypot(d[1]);
        let towards = sign * (l[0] * d[0] + l[1] * d[1]);
        at <= tol && towards <= 1e-9 * len
    })
}

/// A line `a s + b t + c` (unit normal) that is ≥ 0 on curve `a`'s part `ra` and ≤ 0 on
/// curve `b`'s part `rb` (touching allowed, within 1e-9 of the cell size `h`), and such that
/// each curve's end-tangent rays that start in the cell (`rays_a`, `rays_b`) do not run into
/// its own side; or `None` when none is found within [`MAX_ROUNDS`] subdivisions.
pub fn separating_line(
    a: &Quadratic,
    ra: [f64; 2],
    rays_a: &[Ray],
    b: &Quadratic,
    rb: [f64; 2],
    rays_b: &[Ray],
    h: f64,
) -> Option<[f64; 3]> {
    let tol = 1e-9 * h;
    let mut pa = vec![a.sub(ra[0], ra[1])];
    let mut pb = vec![b.sub(rb[0], rb[1])];
    for _ in 0..=MAX_ROUNDS {
        for (own, other, own_is_a) in [(&pa, &pb, true), (&pb, &pa, false)] {
            for q in own.iter() {
                for (p, r) in edges(q) {
                    let d = [r[0] - p[0], r[1] - p[1]];
                    let len = d[0].hypot(d[1]);
                    if len <= tol {
                        continue;
                    }
                    let n = [-d[1] / len, d[0] / len];
                    let l = [n[0], n[1], -(n[0] * p[0] + n[1] * p[1])];
                    let (olo, ohi) = range(own, l);
                    let (xlo, xhi) = range(other, l);
                    let flip = |l: [f64; 3]| [-l[0], -l[1], -l[2]];
                    // Own on the positive side and other on the negative side, or the
                    // reverse. Both hold when every control point lies on the line (a
                    // piece reduced to the point where it touches the cell, at a junction):
                    // then the orientation is free and only the end-tangent rays decide, so
                    // both are tried.
                    let orientations = [
                        (olo >= -tol && xhi <= tol).then_some(l),
                        (ohi <= tol && xlo >= -tol).then_some(flip(l)),
                    ];
                    for l in orientations.into_iter().flatten() {
                        // `l` is ≥ 0 on `own`
                        let l = if own_is_a { l } else { flip(l) };
                        if rays_stay_out(l, rays_a, 1.0, tol) && rays_stay_out(l, rays_b, -1.0, tol)
                        {
                            return Some(l);
                        }
                    }
                }
            }
        }
        let halve = |v: &Vec<Quadratic>| {
            v.iter()
                .flat_map(|q| {
                    let (x, y) = q.split(0.5);
                    [x, y]
                })
                .collect::<Vec<_>>()
        };
        pa = halve(&pa);
        pb = halve(&pb);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// hammer.iges face 37 at ε = 0.1 mm: a line leaves a junction that lies on the top
    /// edge of the cell, and the piece arriving there from above only touches the cell at its
    /// end, a slight kink away from the line. Every control point of that piece's part lies
    /// on the line through the junction, so the line may face either way; only one way keeps
    /// the arriving piece's end tangent out of its own side.
    #[test]
    fn a_piece_touching_the_cell_at_its_end_takes_either_side() {
        let p = [2.244204147, 0.8499997720000001];
        let a = Quadratic::segment(p, [2.244201742003995, 0.8456631564694607]);
        let b = Quadratic::new(
            [2.235351278840194, 0.9480585678054261],
            [2.244416406508326, 0.898430826180249],
            p,
        );
        let rays_a = [(p, [a.p[0][0] - a.p[2][0], a.p[0][1] - a.p[2][1]])];
        let rays_b = [(p, [p[0] - b.p[1][0], p[1] - b.p[1][1]])];
        let h = 3.2e-4;
        for rb in [[1.0, 1.0], [0.99, 1.0]] {
            let l = separating_line(&a, [0.0, 0.0478], &rays_a, &b, rb, &rays_b, h);
            let l = l.unwrap_or_else(|| panic!("no line for {rb:?}"));
            let side = |q: [f64; 2]| l[0] * q[0] + l[1] * q[1] + l[2];
            for k in 0..=10 {
                let t = k as f64 / 10.0;
                assert!(side(a.sub(0.0, 0.0478).point(t)) >= -1e-12);
                assert!(side(b.sub(rb[0], rb[1]).point(t)) <= 1e-12);
            }
        }
    }
}
