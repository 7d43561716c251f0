//! Step 2: each face's loops as closed (u, v) polylines whose points carry their 3D position.
//! A trim on a shared edge reuses the edge's samples, each mapped into this face's (u, v) on
//! the trim's own pcurve. When the pcurve and the 3D curve share their parameter range, the
//! pcurve at the edge sample's own parameter is tried first (OCP's "same parameter"), and kept
//! when its surface point lies within [`SAME_PARAMETER_FRACTION`] × the tolerance of the
//! sample: checked per sample, because equal ranges do not make equal parametrisations (a
//! face converted to NURBS keeps the original edges but gets reparametrised pcurves, off by up
//! to 0.4 mm on an offset of a radius-5 cylinder). Otherwise, and whenever the ranges differ,
//! the sample is projected onto the pcurve (Gauss-Newton on |S(c(t)) − P|²). Trims without an
//! edge are sampled to the tolerance on their own; short ones (the exporter's gap closers) add
//! no point.

use crate::Options;
use crate::edges::{EdgeSamples, EdgeTable, min_segments, sample_chordal, snap_radius, trim_point};
use std::collections::HashMap;
use tessd_brep::{Curve2, DVec2, DVec3, Face, Trim};

/// A boundary point: its (u, v) on the face and its 3D position (for points of shared edges,
/// the edge's sample, exactly).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundaryPoint {
    /// (u, v) on this face.
    pub uv: DVec2,
    /// The 3D position.
    pub p: DVec3,
    /// Where the segment from this point to the next one comes from, so that it can be split
    /// (`None` on degenerate edges and the bounds rectangle).
    pub next: Option<Segment>,
}

/// What a boundary curve is sampled along: a shared edge (its 3D curve's parameter) or a
/// trim without an edge (the trim's own parameter; loop and trim index on its face).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Source {
    /// A shared edge, by id.
    Edge(u64),
    /// A trim without an edge: `(loop, trim)` on the face.
    Free(usize, usize),
}

/// One boundary segment's origin: the curve and the parameters of its two ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The curve sampled.
    pub source: Source,
    /// The parameters of the segment's start and end on that curve.
    pub t: [f64; 2],
}

/// A closed polyline (the last point connects back to the first).
pub type Polyline = Vec<BoundaryPoint>;

/// Extra sample parameters for a face's trims without an edge, by `(loop, trim)` (added where
/// boundary polylines crossed, see [`crate::crossings`]).
pub type FreeSplits = HashMap<(usize, usize), Vec<f64>>;

/// The loops of `face` as closed polylines, outer first; the `bounds` rectangle for a face
/// without loops. `extra` adds samples to trims without an edge.
pub fn face_loops(
    face: &Face,
    edges: &EdgeTable,
    extra: &FreeSplits,
    options: &Options,
) -> Vec<Polyline> {
    if face.loops.is_empty() {
        let [u0, u1, v0, v1] = face.bounds;
        let corners = [(u0, v0), (u1, v0), (u1, v1), (u0, v1)].map(DVec2::from);
        let mut out = Vec::new();
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            let len = (b - a).length();
            let trim = Trim {
                curve: Curve2::Line {
                    origin: a,
                    dir: (b - a) * (1.0 / len),
                },
                range: [0.0, len],
                edge: None,
            };
            let pts = free_trim(face, &trim, &[], None, options);
            out.extend_from_slice(&pts[..pts.len() - 1]);
        }
        return vec![out];
    }
    face.loops
        .iter()
        .enumerate()
        .map(|(li, lp)| {
            let mut out: Polyline = Vec::new();
            for (ti, trim) in lp.trims.iter().enumerate() {
                let pts = match trim.edge.and_then(|id| edges.get(&id).map(|s| (id, s))) {
                    Some((id, EdgeSamples::Curve { params, points })) => {
                        shared_trim(face, trim, id, params, points, options)
                    }
                    Some((_, EdgeSamples::Point(p))) => degenerate_trim(trim, *p),
                    None => {
                        let more = extra.get(&(li, ti)).map_or(&[][..], |v| v);
                        let source = Some(Source::Free(li, ti));
                        let pts = free_trim(face, trim, more, source, options);
                        let len: f64 = pts.windows(2).map(|w| (w[1].p - w[0].p).length()).sum();
                        if len < 2.0 * snap_radius(options) {
                            continue;
                        }
                        pts
                    }
                };
                out.extend_from_slice(&pts[..pts.len().saturating_sub(1)]);
            }
            dedup(out)
        })
        .filter(|p| p.len() >= 3)
        .collect()
}

/// Drops consecutive points with equal (u, v) (and the closing duplicate); the point kept
/// takes over the dropped one's outgoing segment.
fn dedup(pts: Polyline) -> Polyline {
    let mut out: Polyline = Vec::with_capacity(pts.len());
    for q in pts {
        match out.last_mut() {
            Some(l) if l.uv == q.uv => l.next = q.next,
            _ => out.push(q),
        }
    }
    while out.len() > 1 && out.first().map(|f| f.uv) == out.last().map(|l| l.uv) {
        let l = out.pop().expect("non-empty");
        out[0].next = out[0].next.or(l.next);
    }
    out
}

/// The boundary points at parameters `ts`, each with its segment to the next (from `source`).
fn with_segments(
    ts: &[f64],
    source: Option<Source>,
    point: impl Fn(usize, f64) -> BoundaryPoint,
) -> Vec<BoundaryPoint> {
    ts.iter()
        .enumerate()
        .map(|(k, &t)| BoundaryPoint {
            next: source
                .zip(ts.get(k + 1))
                .map(|(source, &t1)| Segment { source, t: [t, t1] }),
            ..point(k, t)
        })
        .collect()
}

/// A trim without a shared edge, sampled on its own along S(c(t)), plus the parameters
/// `more`; its segments come from `source` (`None`: they cannot be split).
fn free_trim(
    face: &Face,
    trim: &Trim,
    more: &[f64],
    source: Option<Source>,
    options: &Options,
) -> Vec<BoundaryPoint> {
    let [t0, t1] = trim.range;
    let f = |t: f64| trim_point(face, &trim.curve, t);
    let min = min_segments(&trim.curve, t0, t1);
    let mut ts = sample_chordal(&f, t0, t1, min, options.tolerance, options.angle);
    if !more.is_empty() {
        ts.extend_from_slice(more);
        let sign = if t1 >= t0 { 1.0 } else { -1.0 };
        ts.sort_by(|a, b| (sign * a).total_cmp(&(sign * b)));
        ts.dedup();
    }
    with_segments(&ts, source, |_, t| {
        let uv = trim.curve.point(t);
        BoundaryPoint {
            uv,
            p: face.surface.point(uv[0], uv[1]),
            next: None,
        }
    })
}

/// A trim on a degenerate edge: (u, v) samples along the trim (enough for well-shaped
/// triangles in (u, v)), every one at the edge's single point.
fn degenerate_trim(trim: &Trim, p: DVec3) -> Vec<BoundaryPoint> {
    let [t0, t1] = trim.range;
    let n = trim.curve.segments(t0, t1).max(16);
    (0..=n)
        .map(|k| {
            let t = if k == n {
                t1
            } else {
                t0 + (t1 - t0) * k as f64 / n as f64
            };
            BoundaryPoint {
                uv: trim.curve.point(t),
                p,
                next: None,
            }
        })
        .collect()
}

/// How close (in tolerances) the surface point of a pcurve at an edge sample's own parameter
/// must be to the sample for that parameter to be used as is. A tenth of the tolerance spends
/// at most that much of the chordal budget on a (u, v) that is slightly off; anything farther
/// is projected, which is always right, only slower.
pub const SAME_PARAMETER_FRACTION: f64 = 0.1;

/// A trim on a shared edge: the edge's samples in the trim's walking order, each with its
/// (u, v) on this face.
fn shared_trim(
    face: &Face,
    trim: &Trim,
    id: u64,
    params: &[f64],
    points: &[DVec3],
    options: &Options,
) -> Vec<BoundaryPoint> {
    let [t0, t1] = trim.range;
    let (e0, e1) = (params[0], params[params.len() - 1]);
    let span = (e1 - e0).abs().max((t1 - t0).abs());
    let same = ((t0.min(t1) - e0.min(e1)).abs() < 1e-9 * span)
        && ((t0.max(t1) - e0.max(e1)).abs() < 1e-9 * span);
    // Whether the trim walks the edge in its own direction: by the ranges when the pcurve
    // shares the edge's parameter, else by which end (or, for a closed edge, which way from
    // its start) the trim's surface points follow.
    let forward = if same {
        (t1 - t0) * (e1 - e0) > 0.0
    } else {
        let last = points.len() - 1;
        let start = trim_point(face, &trim.curve, t0);
        let (d0, d1) = (
            (start - points[0]).length(),
            (start - points[last]).length(),
        );
        if (d0 - d1).abs() > 1e-9 * (d0 + d1) && points[0] != points[last] {
            d0 < d1
        } else {
            let near = trim_point(face, &trim.curve, t0 + 0.01 * (t1 - t0));
            let a = points[1.min(last)];
            let b = points[last.saturating_sub(1)];
            (near - a).length() <= (near - b).length()
        }
    };
    let order: Vec<usize> = if forward {
        (0..params.len()).collect()
    } else {
        (0..params.len()).rev().collect()
    };
    let n = order.len();
    let edge_ts: Vec<f64> = order.iter().map(|&i| params[i]).collect();
    let near = SAME_PARAMETER_FRACTION * options.tolerance;
    with_segments(&edge_ts, Some(Source::Edge(id)), |k, _| {
        let i = order[k];
        if k == 0 || k + 1 == n {
            let t = if k == 0 { t0 } else { t1 };
            return BoundaryPoint {
                uv: trim.curve.point(t),
                p: points[i],
                next: None,
            };
        }
        if same {
            let uv = trim.curve.point(params[i]);
            if (face.surface.point(uv.x, uv.y) - points[i]).length() <= near {
                return BoundaryPoint {
                    uv,
                    p: points[i],
                    next: None,
                };
            }
        }
        // The parameter map by the ranges (the identity when they are equal) as the guess.
        let guess = if forward {
            t0 + (t1 - t0) * (params[i] - e0) / (e1 - e0)
        } else {
            t0 + (t1 - t0) * (e1 - params[i]) / (e1 - e0)
        };
        let t = project(face, &trim.curve, points[i], guess, t0, t1);
        BoundaryPoint {
            uv: trim.curve.point(t),
            p: points[i],
            next: None,
        }
    })
}

/// The parameter of the pcurve whose surface point is nearest `p`, from `guess`, within the
/// trim's range.
fn project(face: &Face, curve: &Curve2, p: DVec3, guess: f64, t0: f64, t1: f64) -> f64 {
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let mut t = guess.clamp(lo, hi);
    for _ in 0..12 {
        let (uv, duv) = curve.eval(t);
        let sp = face.surface.eval(uv.x, uv.y);
        let j = sp.du * duv.x + sp.dv * duv.y;
        let r = sp.point - p;
        let jj = j.dot(j);
        if jj.is_nan() || jj <= 0.0 {
            break;
        }
        let step = r.dot(j) / jj;
        let next = (t - step).clamp(lo, hi);
        if (next - t).abs() <= 1e-14 * (hi - lo).max(1.0) {
            t = next;
            break;
        }
        t = next;
    }
    t
}
