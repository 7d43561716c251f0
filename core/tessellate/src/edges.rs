//! Step 1: every shared edge discretised once, along its 3D curve, to the chordal tolerance
//! and angle. Each face using the edge reuses these samples — the same f64 points, hence the
//! same f32 positions — so neighbouring faces meet without cracks. The edges' end points are
//! first snapped together (the topological vertices), so that edges meeting at a vertex end on
//! the identical point; a degenerate edge (no curve: a sphere's pole) is that one point.

use crate::Options;
use std::collections::HashMap;
use tessd_brep::vector::Vector;
use tessd_brep::{Curve, Curve2, Curve3, Document, Face};

/// The discretisation of one shared edge.
#[derive(Clone, Debug, PartialEq)]
pub enum EdgeSamples {
    /// Parameters along the edge's curve, increasing from `range[0]` towards `range[1]` (or
    /// decreasing when the range is), with their 3D points (end points snapped).
    Curve {
        /// The curve parameters, in the edge's range order.
        params: Vec<f64>,
        /// The 3D points at those parameters.
        points: Vec<[f64; 3]>,
    },
    /// A degenerate edge: the single 3D point every sample of its trims maps to.
    Point([f64; 3]),
}

/// The samples of every edge, by edge id.
pub type EdgeTable = HashMap<u64, EdgeSamples>;

/// Samples `f` on `[t0, t1]` (either order) so that, between consecutive samples, the chord
/// stays within `tol` of the curve's midpoint and turns by less than `angle`; at least
/// `min_segments` segments. Returns the parameters, from `t0` to `t1`.
pub fn sample_chordal(
    f: &dyn Fn(f64) -> [f64; 3],
    t0: f64,
    t1: f64,
    min_segments: usize,
    tol: f64,
    angle: f64,
) -> Vec<f64> {
    let n = min_segments.max(1);
    let mut out = vec![t0];
    let mut a_p = f(t0);
    for k in 0..n {
        let a = t0 + (t1 - t0) * k as f64 / n as f64;
        let b = if k + 1 == n {
            t1
        } else {
            t0 + (t1 - t0) * (k + 1) as f64 / n as f64
        };
        let b_p = f(b);
        refine(f, (a, a_p), (b, b_p), tol, angle, 0, &mut out);
        a_p = b_p;
    }
    out
}

/// The fewest segments a curve starts from before chordal refinement: one per quarter turn
/// of a conic, two per polynomial piece of a B-spline (a cubic piece bends at most twice), one
/// for a line. Refinement tests the chord's midpoint and quarter points, so a floor this low
/// cannot hide a bend; where the coarse polylines of two curves cross in a face's (u, v),
/// [`crate::crossings`] splits them.
pub fn min_segments<P: Vector>(curve: &Curve<P>, t0: f64, t1: f64) -> usize {
    let span = (t1 - t0).abs();
    let n = match curve {
        Curve::Line { .. } => 1.0,
        Curve::Circle { .. } | Curve::Ellipse { .. } => (span / std::f64::consts::FRAC_PI_2).ceil(),
        Curve::Bspline(b) => match b.knot_vector() {
            Ok(kv) => (2 * kv.pieces(t0, t1)) as f64,
            Err(_) => 1.0,
        },
    };
    if n.is_finite() {
        n.clamp(1.0, 4096.0) as usize
    } else {
        1
    }
}

/// The largest distance of the curve's points at the quarter points of `[a, b]` from the
/// chord `pa`–`pb` (the midpoint `pm` already evaluated).
fn chord_deviation(
    f: &dyn Fn(f64) -> [f64; 3],
    (a, pa): (f64, [f64; 3]),
    (b, pb): (f64, [f64; 3]),
    pm: [f64; 3],
) -> f64 {
    let d = pb.sub(pa);
    let len2 = d.dot(d);
    let off = |p: [f64; 3]| {
        let t = if len2 > 0.0 {
            (p.sub(pa).dot(d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        p.sub(pa.add(d.scale(t))).norm()
    };
    let q1 = f(a + 0.25 * (b - a));
    let q3 = f(a + 0.75 * (b - a));
    off(pm).max(off(q1)).max(off(q3))
}

/// Pushes the samples of `(a, b]`, splitting in two while the curve's chordal deviation (at
/// the midpoint and quarter points) or the turn between the half-chords is too large.
fn refine(
    f: &dyn Fn(f64) -> [f64; 3],
    (a, pa): (f64, [f64; 3]),
    (b, pb): (f64, [f64; 3]),
    tol: f64,
    angle: f64,
    depth: u32,
    out: &mut Vec<f64>,
) {
    let m = 0.5 * (a + b);
    let pm = f(m);
    let dev = chord_deviation(f, (a, pa), (b, pb), pm);
    let (d1, d2) = (pm.sub(pa), pb.sub(pm));
    let (l1, l2) = (d1.norm(), d2.norm());
    // The turn between the half-chords exceeds `angle` when its cosine is below cos(angle).
    let cos_turn = if l1 > 0.0 && l2 > 0.0 {
        d1.dot(d2) / (l1 * l2)
    } else {
        1.0
    };
    let turns = cos_turn < angle.min(std::f64::consts::PI).cos();
    let split = dev.is_finite() && (dev > tol || (turns && l1 + l2 > 1e-3 * tol));
    if depth < 24 && split {
        refine(f, (a, pa), (m, pm), tol, angle, depth + 1, out);
        refine(f, (m, pm), (b, pb), tol, angle, depth + 1, out);
    } else {
        out.push(b);
    }
}

/// Groups nearby points (within `radius`) into topological vertices.
#[derive(Default)]
pub struct VertexSnap {
    reps: Vec<[f64; 3]>,
    radius: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
}

impl VertexSnap {
    /// An empty set of vertices merging points within `radius`.
    pub fn new(radius: f64) -> VertexSnap {
        VertexSnap {
            reps: Vec::new(),
            radius: radius.max(f64::MIN_POSITIVE),
            cells: HashMap::new(),
        }
    }

    fn cell(&self, p: [f64; 3]) -> [i64; 3] {
        p.map(|c| (c / self.radius).floor() as i64)
    }

    /// The representative of the vertex within `radius` of `p`, if there is one.
    pub fn find(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        let c = self.cell(p);
        let mut best: Option<(f64, [f64; 3])> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                    for &i in self.cells.get(&key).into_iter().flatten() {
                        let d = self.reps[i].sub(p).norm();
                        if d <= self.radius && best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, self.reps[i]));
                        }
                    }
                }
            }
        }
        best.map(|(_, q)| q)
    }

    /// `p` snapped onto an existing vertex, or made a new one.
    pub fn snap(&mut self, p: [f64; 3]) -> [f64; 3] {
        if !p.is_finite() {
            return p;
        }
        if let Some(q) = self.find(p) {
            return q;
        }
        let key = self.cell(p);
        self.cells.entry(key).or_default().push(self.reps.len());
        self.reps.push(p);
        p
    }
}

/// The radius within which edge end points are one vertex: a small fraction of the tolerance.
pub fn snap_radius(options: &Options) -> f64 {
    0.05 * options.tolerance
}

/// The surface point of a trim's curve at `t`.
pub fn trim_point(face: &Face, curve: &Curve2, t: f64) -> [f64; 3] {
    let [u, v] = curve.point(t);
    face.surface.point(u, v)
}

/// Adds the sample at the middle of the segment between the parameters `ta` and `tb` of edge
/// `id` (consecutive samples, either order) on its 3D `curve`; false when there is no such
/// segment.
pub fn split_edge(table: &mut EdgeTable, id: u64, curve: &Curve3, ta: f64, tb: f64) -> bool {
    let Some(EdgeSamples::Curve { params, points }) = table.get_mut(&id) else {
        return false;
    };
    let Some(i) = params
        .windows(2)
        .position(|w| (w[0] == ta && w[1] == tb) || (w[0] == tb && w[1] == ta))
    else {
        return false;
    };
    let m = 0.5 * (ta + tb);
    if m == ta || m == tb {
        return false;
    }
    params.insert(i + 1, m);
    points.insert(i + 1, curve.point(m));
    true
}

/// Discretises every edge of `doc` once.
pub fn discretise(doc: &Document, options: &Options) -> EdgeTable {
    let mut table = EdgeTable::new();
    let Some(edges) = &doc.edges else {
        return table;
    };
    let mut snap = VertexSnap::new(snap_radius(options));
    for edge in edges {
        let Some(curve) = &edge.curve else { continue };
        let [t0, t1] = edge.range;
        let f = |t: f64| curve.point(t);
        let min = min_segments(curve, t0, t1).max(2);
        let params = sample_chordal(&f, t0, t1, min, options.tolerance, options.angle);
        let mut points: Vec<[f64; 3]> = params.iter().map(|&t| curve.point(t)).collect();
        let last = points.len() - 1;
        let length: f64 = points.windows(2).map(|w| w[1].sub(w[0]).norm()).sum();
        if length < 2.0 * snap.radius {
            // Shorter than the snapping: both ends would become one vertex and the middle
            // samples a needle out and back (a fold three triangles share; Pump_Nut's
            // 0.002 mm edge 18 at 0.1 mm). The edge is that vertex, as a degenerate one is.
            table.insert(edge.id, EdgeSamples::Point(snap.snap(points[0])));
            continue;
        }
        points[0] = snap.snap(points[0]);
        points[last] = snap.snap(points[last]);
        table.insert(edge.id, EdgeSamples::Curve { params, points });
    }
    // Degenerate edges: the vertex their trims' surface points collapse onto.
    for edge in edges.iter().filter(|e| e.curve.is_none()) {
        let start = doc.faces.iter().find_map(|face| {
            face.loops
                .iter()
                .flat_map(|l| &l.trims)
                .find(|t| t.edge == Some(edge.id))
                .map(|t| trim_point(face, &t.curve, t.range[0]))
        });
        if let Some(p) = start {
            let q = snap.find(p).unwrap_or(p);
            table.insert(edge.id, EdgeSamples::Point(q));
        }
    }
    table
}
