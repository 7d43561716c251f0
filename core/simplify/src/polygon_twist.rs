//! How far apart two triangulations of one input polygon can lie: the report's
//! `polygon_twist`, and the note that says which triangulation the quality bound holds for.
//!
//! A non-planar polygon has no single surface: the adaptive goals fan-triangulate it
//! (`triangulate.rs`: the first corner to every other edge) and bound the distance to that
//! fan, while a reader that splits it otherwise (MeshLab takes a quad's other diagonal)
//! measures against another surface. By the triangle inequality of the Hausdorff distance, a
//! bound `e` against the fan is a bound `e + twist` against any other triangulation, where
//! `twist` is the distance between the two.
//!
//! **Quads** (exact). Let the fan be `A = {v0v1v2, v0v2v3}` (diagonal `v0v2`) and the other
//! split `B = {v0v1v3, v1v2v3}` (diagonal `v1v3`). A point `p` of `v0v1v2` is
//! `b·v1 + (1 − b)·q` with `q` on the diagonal `v0v2`; both triangles of `B` hold `v1`, so if
//! `x` is the point of `B` closest to `q`, the segment `v1x` lies in `B` and
//! `d(p, B) ≤ |p − (b·v1 + (1 − b)·x)| = (1 − b)·d(q, B) ≤ d(q, B)`; likewise from `v3` on
//! `v0v2v3`. So `A`'s farthest point from `B` lies on `A`'s diagonal. Along it,
//! `q(t) = v0 + t(v2 − v0)`, `f(t) = d(q, v0v1v3)` is convex and 0 at `t = 0` (so
//! non-decreasing) and `g(t) = d(q, v1v2v3)` convex and 0 at `t = 1` (non-increasing):
//! `d(q, B) = min(f, g)` peaks where `f = g`: first tried where the distances to the two
//! triangles' planes cross (the answer when both closest points lie inside the faces), else
//! found by safeguarded regula falsi on `f − g`.
//! The bracket `[lo, hi]` certifies `max min(f, g) ≤ min(f(hi), g(lo))`, which is the value
//! returned once it is within 1e-6 of the best value seen (so the result is an upper bound,
//! tight to 1e-6 relative). The twist is the larger of the two directions (`A`'s diagonal to
//! `B`, `B`'s to `A`): the Hausdorff distance between the two splits. It is not the distance
//! between the diagonals' midpoints: the peak lies where the two distances cross, at the
//! midpoint only for a symmetric quad (the tests check this against dense sampling of both
//! surfaces). A planar convex quad gives 0; a planar concave ("arrowhead") quad does not,
//! since one of its splits covers area outside it.
//!
//! **Polygons of five corners or more** (an upper bound). Seen along the polygon's Newell
//! normal `n`, when the fan's triangles all turn the polygon's way (or are flat) and their
//! angles at the first corner add up to less than a turn, the fan is a triangulation of the polygon's
//! projection; so is any triangulation whose triangles do not overlap seen along `n` (what
//! ear clipping, Blender's and constrained Delaunay triangulators make). Both surfaces are then
//! graphs over the same region whose heights along `n` lie between the lowest and the highest
//! corner, so every point of one is within the corners' spread along `n`, `w`, of the point of
//! the other above or below it: the bound is `w` (0 for a planar polygon). Exact for a quad
//! whose split is nearly vertical (small twists), up to about 2× otherwise. When the fan
//! folds over itself (a polygon not star-shaped from its first corner), every point of a
//! triangle is within `longest side / √3` of one of its corners, all of which both
//! triangulations hold: the bound is then the largest distance between two corners over
//! `√3`.
//!
//! Values at or below the positions' own rounding (2⁻²³ of the polygon's largest coordinate,
//! about two f32 steps) are reported as 0: a planar polygon whose corners were rounded to f32
//! is not twisted.

use crate::Report;
use glam::DVec3;
use rayon::prelude::*;
use tessd_mesh::Mesh;

/// Relative accuracy of the quad twist (see the module's notes).
const RELATIVE_ACCURACY: f64 = 1e-6;
/// Most steps of the search along one diagonal (it converges in a few; this only guards
/// against pathological inputs such as NaN coordinates).
const MAX_STEPS: usize = 100;
/// Polygons with more corners than this bound their diameter by twice their radius about the
/// centroid instead of comparing every pair of corners (a looser, linear-time bound).
const PAIRWISE_CORNERS: usize = 256;

/// The twists of a mesh's polygons (faces of four corners or more), summarised for the
/// report: only the non-zero ones are kept, sorted, so that counting those above a limit is a
/// binary search.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Twists {
    /// The non-zero twists, ascending.
    sorted: Vec<f64>,
}

impl Twists {
    /// The twist of every face of `mesh` (triangles have none), in parallel over the faces. A
    /// mesh of triangles costs one pass over its face offsets.
    pub fn of(mesh: &Mesh) -> Twists {
        let offsets = &mesh.face_offsets;
        let mut sorted: Vec<f64> = (0..mesh.face_count())
            .into_par_iter()
            .filter(|&f| offsets[f + 1] - offsets[f] > 3)
            .map(|f| {
                let point = |v: &u32| glam::Vec3::from_array(mesh.positions[*v as usize]);
                match mesh.face(f) {
                    // Most polygons are quads: no allocation for them.
                    [a, b, c, d] => polygon_twist(&[a, b, c, d].map(|v| point(v).as_dvec3())),
                    face => {
                        let corners: Vec<DVec3> =
                            face.iter().map(|v| point(v).as_dvec3()).collect();
                        polygon_twist(&corners)
                    }
                }
            })
            .filter(|&t| t > 0.0)
            .collect();
        sorted.par_sort_unstable_by(f64::total_cmp);
        Twists { sorted }
    }

    /// The largest twist (0 when every polygon is planar or the mesh holds triangles only).
    pub fn max(&self) -> f64 {
        self.sorted.last().copied().unwrap_or(0.0)
    }

    /// How many polygons are twisted by more than `limit`.
    pub fn count_above(&self, limit: f64) -> u64 {
        (self.sorted.len() - self.sorted.partition_point(|&t| t <= limit)) as u64
    }
}

/// The largest distance between the fan triangulation of the polygon `corners` (the first
/// corner to every other edge, as tessd triangulates) and any other triangulation of it: exact
/// (to 1e-6 relative, rounded up) for a quad, an upper bound for five corners or more, 0 for a
/// triangle. See the module's notes for the derivation and the bound.
pub fn polygon_twist(corners: &[DVec3]) -> f64 {
    let n = corners.len();
    if n < 4 {
        return 0.0;
    }
    let twist = if n == 4 {
        quad_twist([corners[0], corners[1], corners[2], corners[3]])
    } else {
        polygon_bound(corners)
    };
    let scale = corners
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0, f64::max);
    if twist <= f64::from(f32::EPSILON) * scale {
        0.0
    } else {
        twist
    }
}

/// The Hausdorff distance between a quad's two splits (see the module's notes).
fn quad_twist(v: [DVec3; 4]) -> f64 {
    // The fan's diagonal v0v2 to the other split: v0v1v3 holds v0, v1v2v3 holds v2.
    let a = diagonal_gap(v[0], v[2], [v[0], v[1], v[3]], [v[1], v[2], v[3]]);
    // The other diagonal v1v3 to the fan: v0v1v2 holds v1, v0v2v3 holds v3.
    let b = diagonal_gap(v[1], v[3], [v[0], v[1], v[2]], [v[0], v[2], v[3]]);
    a.max(b)
}

/// The largest distance from the segment `pq` to the union of the triangles `tp` (which
/// holds `p`) and `tq` (which holds `q`): an upper bound tight to [`RELATIVE_ACCURACY`].
fn diagonal_gap(p: DVec3, q: DVec3, tp: [DVec3; 3], tq: [DVec3; 3]) -> f64 {
    let at = |t: f64| {
        let x = p + (q - p) * t;
        (
            x.distance(closest_on_triangle(x, tp)),
            x.distance(closest_on_triangle(x, tq)),
        )
    };
    let floor = 1e-12 * p.distance(q);
    // First guess: where the distances to the two triangles' planes cross (they grow linearly
    // from p and from q); right when both closest points lie inside the faces (or on their
    // shared edge). For a nearly planar quad that is where the diagonals cross (both ratios
    // tend to area(tp) / (area(tp) + area(tq))): on spot_quadrangulated every quad's twist
    // takes these two evaluations a diagonal and no search. If f = g there (to the accuracy), that is the peak: f(t*) ≤ f(t) for
    // t* ≤ t and g(t*) ≤ g(t) for t* ≥ t, so max(f, g) bounds it from above.
    let (h_q, h_p) = (plane_distance(q, tp), plane_distance(p, tq));
    let t1 = if h_p + h_q > 0.0 && (h_p + h_q).is_finite() {
        h_p / (h_p + h_q)
    } else {
        0.5
    };
    let (f1, g1) = at(t1);
    if (f1 - g1).abs() <= RELATIVE_ACCURACY * f1.max(g1) + floor {
        return f1.max(g1);
    }
    // Else the guess is one end of the bracket and 0 or 1 the other. h = f − g: h(lo) ≤ 0 ≤
    // h(hi), as f(0) = 0 (p is a corner of tp) and g(1) = 0.
    let ((mut lo, mut g_lo, mut h_lo), (mut hi, mut f_hi, mut h_hi)) = if f1 < g1 {
        let f_end = q.distance(closest_on_triangle(q, tp));
        ((t1, g1, f1 - g1), (1.0, f_end, f_end))
    } else {
        let g_end = p.distance(closest_on_triangle(p, tq));
        ((0.0, g_end, -g_end), (t1, f1, f1 - g1))
    };
    let mut best = f1.min(g1);
    // Which end moved last (Illinois: halve the other end's value when one end sticks).
    let mut side = 0i8;
    for step in 0..MAX_STEPS {
        let upper = f_hi.min(g_lo);
        if upper - best <= RELATIVE_ACCURACY * upper + floor {
            break;
        }
        // Regula falsi, with a bisection every third step so that the bracket always shrinks.
        let t = if step % 3 == 2 || h_hi <= h_lo {
            0.5 * (lo + hi)
        } else {
            lo + (hi - lo) * (-h_lo / (h_hi - h_lo))
        };
        let t = if t > lo && t < hi { t } else { 0.5 * (lo + hi) };
        if !(t > lo && t < hi) {
            break; // the bracket is as small as f64 allows
        }
        let (f, g) = at(t);
        best = best.max(f.min(g));
        let h = f - g;
        if h <= 0.0 {
            (lo, g_lo, h_lo) = (t, g, h);
            if side == -1 {
                h_hi *= 0.5;
            }
            side = -1;
        } else {
            (hi, f_hi, h_hi) = (t, f, h);
            if side == 1 {
                h_lo *= 0.5;
            }
            side = 1;
        }
    }
    f_hi.min(g_lo)
}

/// The distance from `x` to the plane of triangle `t` (infinite for a degenerate triangle).
fn plane_distance(x: DVec3, t: [DVec3; 3]) -> f64 {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    ((x - t[0]).dot(n)).abs() / n.length()
}

/// The bound for five corners or more (see the module's notes).
fn polygon_bound(c: &[DVec3]) -> f64 {
    let n = c.len();
    let centroid = c.iter().copied().sum::<DVec3>() / n as f64;
    let normal = crate::area_vector::polygon(n, |i| c[i] - centroid);
    if let Some(axis) = normal.try_normalize()
        && fan_is_flat(c, axis)
    {
        let (low, high) = c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                let s = (*p - centroid).dot(axis);
                (l.min(s), h.max(s))
            });
        return high - low;
    }
    let diameter = if n <= PAIRWISE_CORNERS {
        let mut d2 = 0f64;
        for (i, a) in c.iter().enumerate() {
            for b in &c[i + 1..] {
                d2 = d2.max(a.distance_squared(*b));
            }
        }
        d2.sqrt()
    } else {
        2.0 * c.iter().map(|p| p.distance(centroid)).fold(0.0, f64::max)
    };
    diameter / 3f64.sqrt()
}

/// Whether the fan of `c`, seen along `axis`, is a triangulation of the polygon's projection:
/// every fan triangle turns the polygon's way (or is flat: corners in line with the first,
/// to 1e-9 of a radian for rounding) and their angles at the first corner add up to less
/// than a full turn (so they do not overlap).
fn fan_is_flat(c: &[DVec3], axis: DVec3) -> bool {
    let flat = |p: DVec3| {
        let d = p - c[0];
        d - axis * d.dot(axis)
    };
    let mut angle = 0.0;
    for k in 1..c.len() - 1 {
        let (a, b) = (flat(c[k]), flat(c[k + 1]));
        let turn = a.cross(b).dot(axis);
        // (NaN coordinates fail too.)
        if turn.is_nan() || turn < -1e-9 * a.length() * b.length() {
            return false;
        }
        angle += turn.max(0.0).atan2(a.dot(b));
    }
    angle < std::f64::consts::TAU
}

/// The point of triangle `t` closest to `p` (Ericson, *Real-Time Collision Detection*,
/// §5.1.5); a degenerate triangle falls back to the closest of its edges.
fn closest_on_triangle(p: DVec3, t: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    let (e, f) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e >= 0.0 && f >= 0.0 && e + f > 0.0 {
        return b + (c - b) * (e / (e + f));
    }
    let den = va + vb + vc;
    if den > 0.0 && den.is_finite() {
        return a + ab * (vb / den) + ac * (vc / den);
    }
    [(a, b), (b, c), (c, a)]
        .into_iter()
        .map(|(s, e)| {
            let d = e - s;
            let t = if d.length_squared() > 0.0 {
                ((p - s).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            s + d * t
        })
        .min_by(|x, y| p.distance_squared(*x).total_cmp(&p.distance_squared(*y)))
        .unwrap_or(a)
}

impl Report {
    /// The note for [`Report::polygon_twist`]: `Some` when some input polygons are twisted by
    /// more than the tolerance (quality goal) or the surface error reached (complexity goal),
    /// naming the triangulation the bound holds for and how much farther another may lie.
    pub fn twist_note(&self) -> Option<String> {
        let twist = self.polygon_twist.filter(|_| self.twisted_polygons > 0)?;
        let (what, limit) = match (self.tolerance, self.surface_error) {
            (Some(t), _) => ("the tolerance", t),
            (None, Some(e)) => ("the surface error", e),
            (None, None) => return None,
        };
        let ratio = if limit > 0.0 {
            format!(" ({}× {what})", significant(twist / limit))
        } else {
            String::new()
        };
        let n = self.twisted_polygons;
        Some(format!(
            "the bound holds for tessd's fan triangulation of each polygon (its first corner to \
             every other edge); {n} polygon{} {} twisted by more than {what}, by up to {}{ratio}, \
             so another triangulation of {} (another diagonal, as MeshLab splits quads) may lie \
             up to that much farther from the output",
            if n == 1 { "" } else { "s" },
            if n == 1 { "is" } else { "are" },
            significant(twist),
            if n == 1 { "it" } else { "them" },
        ))
    }
}

/// `x` to three significant digits, without an exponent for ordinary magnitudes.
fn significant(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = 2 - x.abs().log10().floor() as i32;
    if (0..=12).contains(&digits) {
        format!("{x:.*}", digits as usize)
    } else if digits < 0 {
        format!("{x:.0}")
    } else {
        format!("{x:.2e}")
    }
}

#[cfg(test)]
#[path = "polygon_twist_tests.rs"]
mod tests;
