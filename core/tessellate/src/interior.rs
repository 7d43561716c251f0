//! Step 3: interior (u, v) sample points, a grid over the loops' (u, v) box whose steps follow
//! the surface's second derivatives: a step h along u keeps the chordal error h²|S_uu|/8 within
//! the tolerance and the normal's turn h|S_uu|/|S_u| within the angle (likewise in v). Points
//! too close to the boundary are dropped, so the constrained triangulation gets no slivers and
//! no point lands on a boundary segment (which would add a boundary vertex off the shared
//! edge's samples).

use crate::Options;
use crate::boundary::Polyline;
use std::collections::HashMap;
use tessd_brep::{DVec2, Face};

/// The most grid points per direction, and per face.
pub const MAX_PER_DIRECTION: usize = 512;
/// The most grid points per face.
pub const MAX_PER_FACE: usize = 200_000;

/// The (u, v) box of the loops: `[u0, u1, v0, v1]`.
pub fn uv_box(loops: &[Polyline]) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for q in loops.iter().flatten() {
        b[0] = b[0].min(q.uv[0]);
        b[1] = b[1].max(q.uv[0]);
        b[2] = b[2].min(q.uv[1]);
        b[3] = b[3].max(q.uv[1]);
    }
    b
}

/// What a face's triangulation needs to know about its surface over the loops' box, measured
/// once: the box, the [`Survey`] of the surface there and the Delaunay plane's scale.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// The loops' (u, v) box, `[u0, u1, v0, v1]`.
    pub bounds: [f64; 4],
    /// The surface's metric scale and curvature steps over the box.
    pub survey: Survey,
    /// [`delaunay_scale`] over the box.
    pub delaunay: [f64; 2],
}

/// The [`Plan`] of `face` with `loops`.
pub fn plan(face: &Face, loops: &[Polyline], options: &Options) -> Plan {
    let bounds = uv_box(loops);
    // A 4 × 4 sample first: enough for the many small faces (fillets, chamfers, thread ends)
    // that get a few grid cells at most, where a finer one costs more surface evaluations
    // than their triangles; larger grids look again, closer.
    let coarse = survey(face, bounds, 3, options);
    let cells = |k: usize| (bounds[2 * k + 1] - bounds[2 * k]) / coarse.curvature[k];
    let s = if cells(0).max(cells(1)) <= 4.0 {
        coarse
    } else {
        survey(face, bounds, 9, options)
    };
    Plan {
        bounds,
        delaunay: delaunay_scale(bounds, s.metric, s.curvature),
        survey: s,
    }
}

/// The scale factors of the constrained Delaunay triangulation's plane, from the box `b`, its
/// metric scale `s` and curvature steps `h`: the 3D metric, with the direction that bends less
/// compressed so that one curvature step has the same length in both directions (a step
/// spanning the face where a direction does not bend at all). Delaunay triangles, round in that
/// plane, then run along the flatter direction as the curvature allows, where an isotropic
/// metric fans long diagonals across the curved direction and refines them over and over: a
/// Ø10 cylinder at 0.01 mm gets 294 triangles this way (3142 isotropic; BRepMesh 292), a
/// crank arm's swept B-spline face (CrankArm.brep face 13) 5028 → 140. The anisotropy is
/// capped.
pub fn delaunay_scale(b: [f64; 4], s: [f64; 2], h: [f64; 2]) -> [f64; 2] {
    const MAX_ANISOTROPY: f64 = 100.0;
    let extent = ((b[1] - b[0]) * s[0]).max((b[3] - b[2]) * s[1]);
    // The 3D length of one curvature step in each direction, at most the face's extent (a
    // direction that does not bend, or that rounding gives a tiny curvature).
    let l = [h[0] * s[0], h[1] * s[1]].map(|x| if x.is_nan() { extent } else { x.min(extent) });
    let short = l[0].min(l[1]);
    if !(short > 0.0 && extent.is_finite()) {
        return s;
    }
    let ratio = l.map(|x| (x / short).clamp(1.0, MAX_ANISOTROPY));
    [s[0] / ratio[0], s[1] / ratio[1]]
}

/// The surface sampled at `(n + 1) × (n + 1)` points over the box `b`: the metric scale
/// (the average |S_u|, |S_v|) and the curvature steps (the steps that the chordal tolerance
/// and the angle allow along each direction, infinite where the surface does not bend). The
/// second derivatives come from a forward difference at each sample,
/// `S_uu ≈ 2 (S(u + h) − S(u) − h S_u(u)) / h²` with `h` a thousandth of the box: local, so
/// a thread's helix sampled a whole number of turns apart does not look flat (differences
/// between the samples themselves would alias), and one point evaluation per direction.
pub fn survey(face: &Face, b: [f64; 4], n: usize, options: &Options) -> Survey {
    let n = n.max(1);
    let (wu, wv) = (b[1] - b[0], b[3] - b[2]);
    let mut sums = [0.0; 2];
    let mut count = 0.0;
    let mut profiles = [vec![f64::INFINITY; n + 1], vec![f64::INFINITY; n + 1]];
    for i in 0..=n {
        for j in 0..=n {
            let u = b[0] + wu * i as f64 / n as f64;
            let v = b[2] + wv * j as f64 / n as f64;
            let p0 = face.surface.eval(u, v);
            let (nu, nv) = (p0.du.length(), p0.dv.length());
            if nu.is_finite() && nv.is_finite() {
                sums[0] += nu;
                sums[1] += nv;
                count += 1.0;
            }
            for (dir, w) in [(0usize, wu), (1usize, wv)] {
                // Towards the box's inside, so that the stencil stays on the face.
                let h = if [i, j][dir] == n {
                    -1e-3 * w
                } else {
                    1e-3 * w
                };
                let (p1, first) = if dir == 0 {
                    (face.surface.point(u + h, v), p0.du)
                } else {
                    (face.surface.point(u, v + h), p0.dv)
                };
                let second = (p1 - p0.point - first * h) * (2.0 / (h * h));
                // Only the part across the tangent bends the iso-curve: the part along it is
                // the parametrisation speeding up (large on uneven rational B-splines), which
                // moves no point off the chord.
                let s1 = first.length();
                let along = if s1 > 0.0 {
                    second.dot(first) / (s1 * s1)
                } else {
                    0.0
                };
                let s2 = (second - first * along).length();
                if !(s2.is_finite() && s1.is_finite()) || s2 <= 1e-300 {
                    continue;
                }
                let chordal = (8.0 * options.tolerance / s2).sqrt();
                // The normal's turn matters only for triangles longer than 4 tolerances (as in
                // refinement): near a degenerate edge (|S_v| → 0) the turn per parameter step
                // grows without bound while the triangles there shrink to nothing in 3D.
                let angular = (options.angle * s1 / s2).max(4.0 * options.tolerance / s1);
                let h = chordal.min(if angular > 0.0 { angular } else { chordal });
                // u steps by row (j), v steps by column (i).
                let across = if dir == 0 { j } else { i };
                profiles[dir][across] = profiles[dir][across].min(h);
            }
        }
    }
    let metric = sums.map(|s| {
        let m = s / count;
        if m > 1e-300 && m.is_finite() { m } else { 1.0 }
    });
    let least = |p: &[f64]| p.iter().copied().fold(f64::INFINITY, f64::min);
    Survey {
        metric,
        curvature: [least(&profiles[0]), least(&profiles[1])],
        profiles,
    }
}

/// What [`survey`] measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Survey {
    /// The average |S_u|, |S_v|: scale factors that make (u, v) distances roughly metric, for
    /// distance tests in (u, v).
    pub metric: [f64; 2],
    /// The parameter steps `[du, dv]` that the chordal tolerance and the angle allow along
    /// each direction (infinite where the surface does not bend): the least of `profiles`.
    pub curvature: [f64; 2],
    /// The curvature steps across the box: `profiles[0][j]` the u step the survey's row `j`
    /// (at the `j`-th of its evenly spaced v) asks for, `profiles[1][i]` the v step of its
    /// column `i` (a sphere's u step grows towards the poles, where its rows shrink).
    pub profiles: [Vec<f64>; 2],
}

/// The grid steps `[du, dv]` over the plan's box. A grid cell's diagonal, the longest edge of
/// its two triangles, deviates from the surface at its midpoint by about
/// `(|S_uu| du² + |S_vv| dv²) / 8` (a quadratic's interpolation error; the twist term left
/// out), while each curvature step alone spends the whole tolerance on its own direction
/// (`|S_uu| h² / 8 = tol`). So where both directions bend, both steps shrink by √2 (each term
/// half the tolerance); where one direction spans the box in one cell, the other keeps what
/// that cell leaves. A grid that already meets the tolerance leaves refinement little to do
/// (a sphere's cells otherwise all split once more: twice the points, inserted one by one).
pub fn grid_steps(plan: &Plan) -> [f64; 2] {
    let b = plan.bounds;
    let extent = [b[1] - b[0], b[3] - b[2]];
    let h = plan.survey.curvature;
    // The share of the tolerance a direction spends: all of it with grid lines across it,
    // (extent / step)² when a single cell spans it.
    let share = |k: usize| {
        if h[k] < extent[k] {
            1.0
        } else {
            (extent[k] / h[k]).powi(2)
        }
    };
    let (su, sv) = (share(0), share(1));
    let (fu, fv) = if su >= 1.0 && sv >= 1.0 {
        (0.5, 0.5)
    } else if su >= 1.0 {
        (1.0 - sv.min(0.5), sv)
    } else {
        (su, 1.0 - su.min(0.5))
    };
    [
        (h[0] * fu.sqrt()).min(extent[0]),
        (h[1] * fv.sqrt()).min(extent[1]),
    ]
}

/// The interior sample points of a face, in (u, v): rows of points, evenly spaced at the
/// [`grid_steps`] across them and, along each row, at the step the curvature there asks for
/// ([`Survey::profiles`], the finer of the two survey rows around it) — or columns, whichever
/// gives fewer points. On a tensor grid a sphere's cells shrink to slivers towards its poles,
/// where its u step could grow as the rows shorten (a fillet's R3 sphere octant at 0.01 mm:
/// 544 → 472 triangles).
pub fn grid(loops: &[Polyline], plan: &Plan) -> Vec<DVec2> {
    let b = plan.bounds;
    if !(b[1] > b[0] && b[3] > b[2]) {
        return Vec::new();
    }
    let extent = [b[1] - b[0], b[3] - b[2]];
    let steps = grid_steps(plan);
    // Lines across direction `across`, evenly spaced; along each, the count its own step asks
    // for. `dir` is the direction along the lines.
    let layout = |dir: usize| -> Vec<(f64, usize)> {
        let across = 1 - dir;
        let lines = (extent[across] / steps[across])
            .ceil()
            .clamp(1.0, MAX_PER_DIRECTION as f64) as usize;
        // The grid step along `dir` is the curvature step times the tolerance share.
        let share = steps[dir] / plan.survey.curvature[dir];
        let share = if share.is_finite() && share > 0.0 {
            share.min(1.0)
        } else {
            1.0
        };
        let profile = &plan.survey.profiles[dir];
        let m = profile.len().saturating_sub(1).max(1);
        (1..lines)
            .map(|k| {
                let t = k as f64 / lines as f64;
                // The survey samples on both sides of this line.
                let x = t * m as f64;
                let (lo, hi) = (x.floor() as usize, (x.ceil() as usize).min(m));
                let h = profile[lo].min(profile[hi]) * share;
                let h = if h.is_nan() {
                    steps[dir]
                } else {
                    h.max(steps[dir])
                };
                let n = (extent[dir] / h)
                    .ceil()
                    .clamp(1.0, MAX_PER_DIRECTION as f64);
                (b[2 * across] + t * extent[across], n as usize)
            })
            .collect()
    };
    let (rows, cols) = (layout(0), layout(1));
    let total = |l: &[(f64, usize)]| l.iter().map(|&(_, n)| n.saturating_sub(1)).sum::<usize>();
    let (dir, lines) = if total(&rows) <= total(&cols) {
        (0, rows)
    } else {
        (1, cols)
    };
    let count = total(&lines);
    if count == 0 {
        return Vec::new();
    }
    // Thin out evenly where a face would get too many.
    let thin = (count as f64 / MAX_PER_FACE as f64).sqrt().max(1.0);
    let scale = plan.survey.metric;
    let spacing_across = extent[1 - dir] / (lines.len() + 1) as f64 * thin;
    let finest = lines
        .iter()
        .map(|&(_, n)| extent[dir] / n as f64 * thin)
        .fold(f64::INFINITY, f64::min);
    // Keep-away distance in scaled (u, v): a fraction of the smallest scaled step.
    let keep = 0.4 * (finest * scale[dir]).min(spacing_across * scale[1 - dir]);
    let near = SegmentIndex::new(loops, scale, keep.max(1e-300));
    let mut out = Vec::new();
    let stride = thin.ceil() as usize;
    for (k, &(at, n)) in lines.iter().enumerate() {
        if k % stride != 0 {
            continue;
        }
        let n = ((n as f64 / thin).ceil() as usize).max(1);
        for i in 1..n {
            let along = b[2 * dir] + extent[dir] * i as f64 / n as f64;
            let uv = if dir == 0 {
                DVec2::new(along, at)
            } else {
                DVec2::new(at, along)
            };
            if !near.within(uv) {
                out.push(uv);
            }
        }
    }
    out
}

/// The boundary segments bucketed on a grid of cell `keep`, in scaled (u, v).
struct SegmentIndex {
    scale: [f64; 2],
    keep: f64,
    segments: Vec<(DVec2, DVec2)>,
    cells: HashMap<[i64; 2], Vec<usize>>,
}

impl SegmentIndex {
    fn new(loops: &[Polyline], scale: [f64; 2], keep: f64) -> SegmentIndex {
        let mut index = SegmentIndex {
            scale,
            keep,
            segments: Vec::new(),
            cells: HashMap::new(),
        };
        for lp in loops {
            for k in 0..lp.len() {
                let a = index.scaled(lp[k].uv);
                let b = index.scaled(lp[(k + 1) % lp.len()].uv);
                let s = index.segments.len();
                index.segments.push((a, b));
                let (c0, c1) = (index.cell(a), index.cell(b));
                // Cells along the segment's box (segments are short compared with the cells
                // in the common case; long ones cover their whole box, capped).
                let (x0, x1) = (c0[0].min(c1[0]), c0[0].max(c1[0]));
                let (y0, y1) = (c0[1].min(c1[1]), c0[1].max(c1[1]));
                if (x1 - x0 + 1) * (y1 - y0 + 1) > 4096 {
                    // A long diagonal segment: walk it instead.
                    let n = ((x1 - x0).max(y1 - y0) + 1) as usize * 2;
                    for t in 0..=n {
                        let p = lerp(a, b, t as f64 / n as f64);
                        index.cells.entry(index.cell(p)).or_default().push(s);
                    }
                } else {
                    for x in x0..=x1 {
                        for y in y0..=y1 {
                            index.cells.entry([x, y]).or_default().push(s);
                        }
                    }
                }
            }
        }
        index
    }

    fn scaled(&self, uv: DVec2) -> DVec2 {
        DVec2::new(uv.x * self.scale[0], uv.y * self.scale[1])
    }

    fn cell(&self, p: DVec2) -> [i64; 2] {
        [
            (p[0] / self.keep).floor() as i64,
            (p[1] / self.keep).floor() as i64,
        ]
    }

    /// Whether a boundary segment passes within `keep` of `uv`.
    fn within(&self, uv: DVec2) -> bool {
        let p = self.scaled(uv);
        let c = self.cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for &s in self
                    .cells
                    .get(&[c[0] + dx, c[1] + dy])
                    .into_iter()
                    .flatten()
                {
                    let (a, b) = self.segments[s];
                    if segment_distance(p, a, b) < self.keep {
                        return true;
                    }
                }
            }
        }
        false
    }
}

fn lerp(a: DVec2, b: DVec2, t: f64) -> DVec2 {
    a + (b - a) * t
}

/// The distance from `p` to the segment `ab`.
pub fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let len2 = ab.dot(ab);
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - lerp(a, b, t)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face(surface: &str) -> Face {
        let json = format!(
            r#"{{"format": "tessd-brep", "version": 1, "units": "mm",
                "faces": [{{"id": 0, "surface": {surface}, "bounds": [0, 1, 0, 1]}}]}}"#
        );
        tessd_brep::Document::from_json(&json)
            .unwrap()
            .faces
            .remove(0)
    }

    #[test]
    fn a_plane_parametrised_unevenly_does_not_bend() {
        // Poles on straight lines, unevenly spaced: S_uu is large, all of it along S_u.
        let f = face(
            r#"{"type": "bspline", "degree_u": 2, "degree_v": 1,
                "poles": [[[0, 0, 0], [0, 1, 0]], [[0.05, 0, 0], [0.05, 1, 0]],
                          [[1, 0, 0], [1, 1, 0]]],
                "knots_u": [0, 1], "mults_u": [3, 3], "knots_v": [0, 1], "mults_v": [2, 2]}"#,
        );
        let s = survey(&f, [0.0, 1.0, 0.0, 1.0], 9, &Options::new(1e-4));
        assert!(s.curvature[0] > 1e3 && s.curvature[1] > 1e3, "{s:?}");
    }

    #[test]
    fn a_cylinder_bends_one_way() {
        let f = face(
            r#"{"type": "cylinder", "origin": [0, 0, 0], "x_dir": [1, 0, 0],
                "y_dir": [0, 1, 0], "radius": 2}"#,
        );
        let tol = 1e-3;
        let s = survey(&f, [0.0, 1.0, 0.0, 1.0], 9, &Options::new(tol));
        // h² r / 8 = tol along u; nothing along v.
        let expect = (8.0 * tol / 2.0f64).sqrt();
        assert!((s.curvature[0] - expect).abs() < 1e-3 * expect, "{s:?}");
        assert!(s.curvature[1].is_infinite(), "{s:?}");
        assert_eq!(s.metric, [2.0, 1.0]);
    }

    #[test]
    fn both_directions_bending_share_the_tolerance() {
        let plan = |curvature: [f64; 2]| Plan {
            bounds: [0.0, 1.0, 0.0, 1.0],
            survey: Survey {
                metric: [1.0, 1.0],
                curvature,
                profiles: [vec![curvature[0]; 2], vec![curvature[1]; 2]],
            },
            delaunay: [1.0, 1.0],
        };
        let h = 0.01;
        let both = grid_steps(&plan([h, h]));
        assert!((both[0] - h / 2f64.sqrt()).abs() < 1e-12, "{both:?}");
        assert!((both[1] - h / 2f64.sqrt()).abs() < 1e-12, "{both:?}");
        // One direction flat: the other keeps its whole step.
        let one = grid_steps(&plan([h, f64::INFINITY]));
        assert!((one[0] - h).abs() < 1e-12 && one[1] == 1.0, "{one:?}");
    }
}
