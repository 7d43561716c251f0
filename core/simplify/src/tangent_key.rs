//! The complexity goal's split key for a small cell when the output's representative is the
//! quadric point (issue 33, fandisk; beyond paper 004, whose section 4 keys by displacement).
//!
//! `feature_priority.rs` measures a cell's surface error from its barycentre: the largest
//! distance from it to the vertices' tangent planes. With the quadric representative that
//! overrates every cell across a crease — the barycentre cuts the corner, the quadric point
//! sits on the crease — so those cells took the vertices that coarse curved strips needed: on
//! fandisk at 648 vertices the largest keys (0.08–0.09) were crease cells, while the largest
//! distance to the input (0.0315, 4.5× meshoptimizer's) was on 22° fillets keyed 0.06.
//! Here the key is measured from the point the planes agree on instead: the minimiser of the
//! vertices' tangent-plane quadric (Lindstrom 2000's construction over vertex planes rather
//! than faces), with the barycentre estimate mixed back in for cells of few points, whose
//! 2–3 planes always meet somewhere (a 2-vertex cell across a 93° corner keyed 0 and left a
//! 0.042 error). Cells over [`SMALL_CELL`] points keep the barycentre key: they are split
//! long before the target anyway, and the extra quadric sums there cost the most.
//!
//! One pass for the sums (barycentre, quadric, box), one for the distances, both in point
//! order on one core: the key does not depend on the thread count.

use crate::feature_priority::{PackedNormal, plane_distance2, priority};
use crate::kd::{Bounds, Point};

/// The largest cell keyed from the quadric point; larger ones keep the barycentre key.
/// 64 against 256 or every cell: fandisk's Hausdorff gmean (÷ meshoptimizer's) 1.83 / 1.77 /
/// 1.72, for +10 % / +30 % / +100 % time on a 1 M-triangle torus at 10 %.
pub(crate) const SMALL_CELL: usize = 64;

/// Below this many points per plane, the barycentre estimate comes back in: the surface key
/// is `s_q + min(1, REDUNDANCY / points) · max(0, s_b − s_q)`.
const REDUNDANCY: f32 = 3.0;

/// The weight of the pull towards the barycentre, relative to the quadric's trace: along a
/// crease or on a flat cell the quadric is singular, and the point then stays near the
/// barycentre along the free directions (the role of the eigenvalue cut-off of
/// `Quadric::minimizer`, at the price of one 3 × 3 solve).
const PULL: f64 = 1e-3;

/// The square of the split key of a cell of `points` (at most [`SMALL_CELL`]), whose `i`-th
/// point has weight and normal `carried(i)`: [`priority`] of the surface estimate above and
/// the largest displacement from the quadric point.
pub(crate) fn key2(points: &[Point], carried: impl Fn(usize) -> (f32, PackedNormal)) -> f32 {
    let (mut sum, mut wsum) = ([0f64; 3], 0f64);
    let (mut a, mut b, mut bounds) = ([0f64; 6], [0f64; 3], Bounds::EMPTY);
    for (i, q) in points.iter().enumerate() {
        let (w, n) = carried(i);
        let (w, p) = (f64::from(w), q.p.map(f64::from));
        (0..3).for_each(|k| sum[k] += w * p[k]);
        wsum += w;
        bounds.add(&q.p);
        let n = n.direction().map(f64::from);
        let nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if nn > 0.0 {
            // The plane n·x = n·p, its normal made unit by the weight.
            let ww = w / nn;
            let d = -(n[0] * p[0] + n[1] * p[1] + n[2] * p[2]);
            let wn = n.map(|x| x * ww);
            a[0] += wn[0] * n[0];
            a[1] += wn[0] * n[1];
            a[2] += wn[0] * n[2];
            a[3] += wn[1] * n[1];
            a[4] += wn[1] * n[2];
            a[5] += wn[2] * n[2];
            (0..3).for_each(|k| b[k] += wn[k] * d);
        }
    }
    let bary = sum.map(|x| (x / wsum) as f32);
    let rep = pulled_minimiser(a, b, &bounds, bary);
    let (mut err2, mut sq2, mut sb2) = (0f32, 0f32, 0f32);
    for (i, q) in points.iter().enumerate() {
        let n = carried(i).1.direction();
        let d = [rep[0] - q.p[0], rep[1] - q.p[1], rep[2] - q.p[2]];
        let e = [bary[0] - q.p[0], bary[1] - q.p[1], bary[2] - q.p[2]];
        let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        err2 = err2.max(dd);
        sq2 = sq2.max(plane_distance2(d, dd, n));
        sb2 = sb2.max(plane_distance2(e, ee, n));
    }
    let share = (REDUNDANCY / points.len() as f32).min(1.0);
    let (sq, sb) = (sq2.sqrt(), sb2.sqrt());
    priority(sq + share * (sb - sq).max(0.0), err2.sqrt()).powi(2)
}

/// The minimiser of the quadric `xᵀAx + 2bᵀx + …` (`a` its upper triangle) plus
/// [`PULL`]` · tr(A) · |x − x0|²`, by one solve; `x0` when that is singular, not finite or
/// farther than a quarter of the box's diagonal outside `bounds` (the rule of
/// `representative::quadric_point`).
fn pulled_minimiser(a: [f64; 6], b: [f64; 3], bounds: &Bounds, x0: [f32; 3]) -> [f32; 3] {
    let eps = PULL * (a[0] + a[3] + a[5]);
    if !(eps > 0.0 && eps.is_finite()) {
        return x0;
    }
    let m = [a[0] + eps, a[1], a[2], a[3] + eps, a[4], a[5] + eps];
    let x = x0.map(f64::from);
    // The step from x0: (A + εI)⁻¹ · −(b + A x0), by the adjugate.
    let r = [
        -(b[0] + a[0] * x[0] + a[1] * x[1] + a[2] * x[2]),
        -(b[1] + a[1] * x[0] + a[3] * x[1] + a[4] * x[2]),
        -(b[2] + a[2] * x[0] + a[4] * x[1] + a[5] * x[2]),
    ];
    let c00 = m[3] * m[5] - m[4] * m[4];
    let c01 = m[2] * m[4] - m[1] * m[5];
    let c02 = m[1] * m[4] - m[2] * m[3];
    let c11 = m[0] * m[5] - m[2] * m[2];
    let c12 = m[1] * m[2] - m[0] * m[4];
    let c22 = m[0] * m[3] - m[1] * m[1];
    let det = m[0] * c00 + m[1] * c01 + m[2] * c02;
    if !(det.abs() > 0.0 && det.is_finite()) {
        return x0;
    }
    let y = [
        x[0] + (c00 * r[0] + c01 * r[1] + c02 * r[2]) / det,
        x[1] + (c01 * r[0] + c11 * r[1] + c12 * r[2]) / det,
        x[2] + (c02 * r[0] + c12 * r[1] + c22 * r[2]) / det,
    ];
    let margin = 0.25 * f64::from(bounds.diagonal2()).sqrt();
    let inside = (0..3).all(|k| {
        y[k] >= f64::from(bounds.lo[k]) - margin && y[k] <= f64::from(bounds.hi[k]) + margin
    });
    if inside && y.iter().all(|v| v.is_finite()) {
        y.map(|v| v as f32)
    } else {
        x0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feature_priority::DISPLACEMENT_SHARE;

    fn points(p: &[[f32; 3]]) -> Vec<Point> {
        p.iter()
            .enumerate()
            .map(|(i, &p)| Point { p, id: i as u32 })
            .collect()
    }

    /// Today's key (`feature_priority`): from the barycentre, equal weights.
    fn barycentre_key(p: &[[f32; 3]], n: &[PackedNormal]) -> f32 {
        let c = [0, 1, 2].map(|k| p.iter().map(|q| q[k]).sum::<f32>() / p.len() as f32);
        let (mut s, mut e) = (0f32, 0f32);
        for (q, n) in p.iter().zip(n) {
            let d = [c[0] - q[0], c[1] - q[1], c[2] - q[2]];
            let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            s = s.max(plane_distance2(d, dd, n.direction()));
            e = e.max(dd);
        }
        priority(s.sqrt(), e.sqrt())
    }

    #[test]
    fn a_crease_cell_is_keyed_by_what_the_quadric_point_misses() {
        // A 90° roof, ridge along y at x = 0, z = 0: 8 points a slope, normals of the slopes.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let (mut p, mut n) = (Vec::new(), Vec::new());
        for i in 1..=4 {
            for y in [0.0, 1.0] {
                let x = i as f32 * 0.25;
                p.extend([[-x, y, -x], [x, y, -x]]);
                n.extend([
                    PackedNormal::pack([-s, 0.0, s]),
                    PackedNormal::pack([s, 0.0, s]),
                ]);
            }
        }
        let k = key2(&points(&p), |i| (1.0, n[i])).sqrt();
        let old = barycentre_key(&p, &n);
        // The barycentre lies 0.625 below the ridge, 0.44 off both slopes; the quadric point
        // is on the ridge, so only the few-points term (3/16 of the barycentre estimate) and
        // the displacement share (about 1.5/256) remain.
        assert!(old > 0.4, "{old}");
        let expected = 3.0 / 16.0 * old + DISPLACEMENT_SHARE * 1.5;
        assert!((k - expected).abs() < 0.01, "{k} vs {expected}");
    }

    #[test]
    fn few_points_keep_the_barycentre_estimate_and_flat_cells_have_none() {
        // Two points across a corner: their two planes always meet, the key must not be 0.
        let p = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
        let n = [
            PackedNormal::pack([0.0, 0.0, 1.0]),
            PackedNormal::pack([1.0, 0.0, 0.0]),
        ];
        let k = key2(&points(&p), |i| (1.0, n[i])).sqrt();
        assert!(k >= 0.99 * barycentre_key(&p, &n) - 0.01, "{k}");
        assert!(k > 0.4, "{k}");
        // A flat cell: the displacement share alone.
        let flat: Vec<[f32; 3]> = (0..16)
            .map(|i| [(i % 4) as f32, (i / 4) as f32, 2.0])
            .collect();
        let up = PackedNormal::pack([0.0, 0.0, 1.0]);
        let k = key2(&points(&flat), |_| (1.0, up)).sqrt();
        let disp = (1.5f32 * 1.5 * 2.0).sqrt();
        assert!((k - DISPLACEMENT_SHARE * disp).abs() < 1e-4, "{k}");
    }
}
