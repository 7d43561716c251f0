//! Step 3: interior (u, v) sample points, a grid over the loops' (u, v) box whose steps follow
//! the surface's second derivatives: a step h along u keeps the chordal error h²|S_uu|/8 within
//! the tolerance and the normal's turn h|S_uu|/|S_u| within the angle (likewise in v). Points
//! too close to the boundary are dropped, so the constrained triangulation gets no slivers and
//! no point lands on a boundary segment (which would add a boundary vertex off the shared
//! edge's samples).

use crate::Options;
use crate::boundary::Polyline;
use std::collections::HashMap;
use tessd_brep::Face;
use tessd_brep::vector::Vector;

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

/// The scale factors (average |S_u|, |S_v| over the box) that make (u, v) distances roughly
/// metric, for well-shaped triangles and distance tests in (u, v).
pub fn metric_scale(face: &Face, b: [f64; 4]) -> [f64; 2] {
    let (mut su, mut sv, mut n) = (0.0, 0.0, 0.0);
    for i in 0..5 {
        for j in 0..5 {
            let u = b[0] + (b[1] - b[0]) * (i as f64 + 0.5) / 5.0;
            let v = b[2] + (b[3] - b[2]) * (j as f64 + 0.5) / 5.0;
            let sp = face.surface.eval(u, v);
            let (a, c) = (sp.du.norm(), sp.dv.norm());
            if a.is_finite() && c.is_finite() {
                su += a;
                sv += c;
                n += 1.0;
            }
        }
    }
    let fix = |s: f64| if s > 1e-300 && s.is_finite() { s } else { 1.0 };
    if n == 0.0 {
        [1.0, 1.0]
    } else {
        [fix(su / n), fix(sv / n)]
    }
}

/// The scale factors of the constrained Delaunay triangulation's plane. Where the surface bends
/// in one direction only (cylinders, cones, extrusions: no curvature along the other), that
/// direction is compressed so that a curvature step and the face's extent have the same length:
/// Delaunay triangles, round in that plane, then run along the rulings and need no refinement,
/// where an isotropic (3D) metric fans long diagonals across the curved direction and refines
/// them over and over (a Ø10 cylinder at 0.01 mm: 3142 triangles, 294 this way, as many as
/// BRepMesh). Elsewhere the 3D metric of [`metric_scale`]; the anisotropy is capped.
pub fn delaunay_scale(face: &Face, b: [f64; 4], options: &Options) -> [f64; 2] {
    const MAX_ANISOTROPY: f64 = 100.0;
    let s = metric_scale(face, b);
    let h = curvature_steps(face, b, options);
    let extent = ((b[1] - b[0]) * s[0]).max((b[3] - b[2]) * s[1]);
    // The 3D length of one curvature step in each direction; a direction is flat where that
    // step spans the whole face (rounding gives a cylinder's rulings a tiny curvature).
    let l = [h[0] * s[0], h[1] * s[1]];
    let flat = |x: f64| x >= extent || x.is_nan();
    let (flat_u, flat_v) = (flat(l[0]), flat(l[1]));
    if flat_u == flat_v {
        return s;
    }
    let step = if flat_u { l[1] } else { l[0] };
    let ratio = (extent / step).clamp(1.0, MAX_ANISOTROPY);
    if !ratio.is_finite() {
        return s;
    }
    if flat_u {
        [s[0] / ratio, s[1]]
    } else {
        [s[0], s[1] / ratio]
    }
}

/// The grid steps `[du, dv]` the surface's curvature asks for over the box.
fn steps(face: &Face, b: [f64; 4], options: &Options) -> [f64; 2] {
    let h = curvature_steps(face, b, options);
    [h[0].min(b[1] - b[0]), h[1].min(b[3] - b[2])]
}

/// The parameter steps `[du, dv]` that the chordal tolerance and the angle allow along each
/// direction (infinite where the surface does not bend).
fn curvature_steps(face: &Face, b: [f64; 4], options: &Options) -> [f64; 2] {
    let (wu, wv) = (b[1] - b[0], b[3] - b[2]);
    let mut step = [f64::INFINITY, f64::INFINITY];
    let n = 9;
    for i in 0..=n {
        for j in 0..=n {
            let u = b[0] + wu * i as f64 / n as f64;
            let v = b[2] + wv * j as f64 / n as f64;
            for (dir, w) in [(0usize, wu), (1usize, wv)] {
                let h = 1e-3 * w;
                let at = |d: f64| {
                    if dir == 0 {
                        face.surface.eval(u + d, v)
                    } else {
                        face.surface.eval(u, v + d)
                    }
                };
                let (m, p0, p1) = (at(-h), at(0.0), at(h));
                let second = m
                    .point
                    .add(p1.point)
                    .sub(p0.point.scale(2.0))
                    .scale(1.0 / (h * h));
                let first = if dir == 0 { p0.du } else { p0.dv };
                let (s2, s1) = (second.norm(), first.norm());
                if !(s2.is_finite() && s1.is_finite()) || s2 <= 1e-300 {
                    continue;
                }
                let chordal = (8.0 * options.tolerance / s2).sqrt();
                let angular = options.angle * s1 / s2;
                let h = chordal.min(if angular > 0.0 { angular } else { chordal });
                step[dir] = step[dir].min(h);
            }
        }
    }
    step
}

/// The interior sample points of a face, in (u, v).
pub fn grid(face: &Face, loops: &[Polyline], options: &Options) -> Vec<[f64; 2]> {
    let b = uv_box(loops);
    if !(b[1] > b[0] && b[3] > b[2]) {
        return Vec::new();
    }
    let [hu, hv] = steps(face, b, options);
    let mut nu = ((b[1] - b[0]) / hu)
        .ceil()
        .clamp(1.0, MAX_PER_DIRECTION as f64) as usize;
    let mut nv = ((b[3] - b[2]) / hv)
        .ceil()
        .clamp(1.0, MAX_PER_DIRECTION as f64) as usize;
    while nu * nv > MAX_PER_FACE {
        nu = (nu * 3 / 4).max(1);
        nv = (nv * 3 / 4).max(1);
    }
    if nu <= 1 && nv <= 1 {
        return Vec::new();
    }
    let scale = metric_scale(face, b);
    let (du, dv) = ((b[1] - b[0]) / nu as f64, (b[3] - b[2]) / nv as f64);
    // Keep-away distance in scaled (u, v): a fraction of the smaller scaled step.
    let keep = 0.4 * (du * scale[0]).min(dv * scale[1]);
    let near = SegmentIndex::new(loops, scale, keep.max(1e-300));
    let mut out = Vec::new();
    for i in 1..nu {
        for j in 1..nv {
            let uv = [b[0] + du * i as f64, b[2] + dv * j as f64];
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
    segments: Vec<([f64; 2], [f64; 2])>,
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

    fn scaled(&self, uv: [f64; 2]) -> [f64; 2] {
        [uv[0] * self.scale[0], uv[1] * self.scale[1]]
    }

    fn cell(&self, p: [f64; 2]) -> [i64; 2] {
        [
            (p[0] / self.keep).floor() as i64,
            (p[1] / self.keep).floor() as i64,
        ]
    }

    /// Whether a boundary segment passes within `keep` of `uv`.
    fn within(&self, uv: [f64; 2]) -> bool {
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

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    a.add(b.sub(a).scale(t))
}

/// The distance from `p` to the segment `ab`.
pub fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = b.sub(a);
    let len2 = ab.dot(ab);
    let t = if len2 > 0.0 {
        (p.sub(a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.sub(lerp(a, b, t)).norm()
}
