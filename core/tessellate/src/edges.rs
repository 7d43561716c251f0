//! Step 1: every shared edge discretised once, along its 3D curve, to the chordal tolerance
//! and angle. Each face using the edge reuses these samples — the same f64 points, hence the
//! same f32 positions — so neighbouring faces meet without cracks. The edges' end points are
//! first snapped together (the topological vertices), so that edges meeting at a vertex end on
//! the identical point; a degenerate edge (no curve: a sphere's pole) is that one point.

use crate::Options;
use std::collections::HashMap;
use tessd_brep::vector::Point;
use tessd_brep::{Curve, Curve2, Curve3, DVec3, Document, Face};

/// The discretisation of one shared edge.
#[derive(Clone, Debug, PartialEq)]
pub enum EdgeSamples {
    /// Parameters along the edge's curve, increasing from `range[0]` towards `range[1]` (or
    /// decreasing when the range is), with their 3D points (end points snapped).
    Curve {
        /// The curve parameters, in the edge's range order.
        params: Vec<f64>,
        /// The 3D points at those parameters.
        points: Vec<DVec3>,
    },
    /// A degenerate edge: the single 3D point every sample of its trims maps to.
    Point(DVec3),
}

/// The samples of every edge, by edge id.
pub type EdgeTable = HashMap<u64, EdgeSamples>;

/// The most samples one curve gets: [`sample_chordal`] halves each starting segment at most
/// as often as keeps the whole curve within this. A real edge is far below it (a 1 m circle
/// at 1 µm takes ~2 300); what reaches it is a curve the tolerance cannot be met on at any
/// sampling — a trim running 10¹⁶ radians round a cylinder, a part so far from the origin
/// that its points are f64 noise at the tolerance — which, found by fuzzing, took 4 096 ×
/// 2²⁴ evaluations (hours, and the memory to hold them) before this bound. Such a curve now
/// stops at about this count, short of the tolerance.
pub const MAX_CURVE_SAMPLES: usize = 1 << 14;

/// The deepest halving of a segment (2²⁴ pieces), whatever the budget.
const MAX_DEPTH: u32 = 24;

/// Samples `f` on `[t0, t1]` (either order) so that, between consecutive samples, the chord
/// stays within `tol` of the curve's midpoint and turns by less than `angle`; at least
/// `min_segments` segments, at most about [`MAX_CURVE_SAMPLES`]. Returns the parameters, from
/// `t0` to `t1`.
pub fn sample_chordal(
    f: &dyn Fn(f64) -> DVec3,
    t0: f64,
    t1: f64,
    min_segments: usize,
    tol: f64,
    angle: f64,
) -> Vec<f64> {
    let n = min_segments.max(1);
    // Each starting segment may be halved `max_depth` times: n · 2^max_depth ≤ the budget.
    let max_depth = (MAX_CURVE_SAMPLES / n).max(1).ilog2().min(MAX_DEPTH);
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
        refine(f, (a, a_p), (b, b_p), tol, angle, max_depth, &mut out);
        a_p = b_p;
    }
    out
}

/// The fewest segments a curve starts from before chordal refinement: one per quarter turn
/// of a conic, two per polynomial piece of a B-spline (a cubic piece bends at most twice), one
/// for a line. Refinement tests the chord's midpoint and quarter points, so a floor this low
/// cannot hide a bend; where the coarse polylines of two curves cross in a face's (u, v),
/// [`crate::crossings`] splits them. A conic's count allows for a full turn written to 15
/// digits (`tessd_brep::curve::conic_segments`): five starting segments where 2π gives four
/// would end, every segment halved alike, with 25 % more points on the edge.
pub fn min_segments<P: Point>(curve: &Curve<P>, t0: f64, t1: f64) -> usize {
    let span = (t1 - t0).abs();
    let n = match curve {
        Curve::Line { .. } => 1.0,
        Curve::Circle { .. } | Curve::Ellipse { .. } => {
            tessd_brep::curve::conic_segments(span, std::f64::consts::FRAC_PI_2)
        }
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
    f: &dyn Fn(f64) -> DVec3,
    (a, pa): (f64, DVec3),
    (b, pb): (f64, DVec3),
    pm: DVec3,
) -> f64 {
    let d = pb - pa;
    let len2 = d.dot(d);
    let off = |p: DVec3| {
        let t = if len2 > 0.0 {
            ((p - pa).dot(d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (pa + d * t)).length()
    };
    let q1 = f(a + 0.25 * (b - a));
    let q3 = f(a + 0.75 * (b - a));
    off(pm).max(off(q1)).max(off(q3))
}

/// Pushes the samples of `(a, b]`, splitting in two while the curve's chordal deviation (at
/// the midpoint and quarter points) or the turn between the half-chords is too large, at most
/// `depth` times more.
fn refine(
    f: &dyn Fn(f64) -> DVec3,
    (a, pa): (f64, DVec3),
    (b, pb): (f64, DVec3),
    tol: f64,
    angle: f64,
    depth: u32,
    out: &mut Vec<f64>,
) {
    let m = 0.5 * (a + b);
    let pm = f(m);
    let dev = chord_deviation(f, (a, pa), (b, pb), pm);
    let (d1, d2) = (pm - pa, pb - pm);
    let (l1, l2) = (d1.length(), d2.length());
    // The turn between the half-chords exceeds `angle` when its cosine is below cos(angle).
    let cos_turn = if l1 > 0.0 && l2 > 0.0 {
        d1.dot(d2) / (l1 * l2)
    } else {
        1.0
    };
    let turns = cos_turn < angle.min(std::f64::consts::PI).cos();
    let split = dev.is_finite() && (dev > tol || (turns && l1 + l2 > 1e-3 * tol));
    if depth > 0 && split {
        refine(f, (a, pa), (m, pm), tol, angle, depth - 1, out);
        refine(f, (m, pm), (b, pb), tol, angle, depth - 1, out);
    } else {
        out.push(b);
    }
}

/// Groups nearby points into topological vertices. Each point may carry a file tolerance
/// `f` (its vertex's, capped: [`file_radius`]); two points are one vertex when their distance
/// is within max(`base`, f₁ + f₂): OCP's vertex tolerance is a ball about the vertex point
/// that every edge end meeting there lies in, so two ends of one vertex may be up to twice it
/// apart (the vertex point itself is not in the format). Points without file tolerances merge
/// within `base`, as they always did. A vertex keeps the first point that made it and the
/// largest file tolerance of the points merged into it.
#[derive(Default)]
pub struct VertexSnap {
    reps: Vec<(DVec3, f64)>,
    base: f64,
    cell: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
}

/// How [`VertexSnap::snap_within`] placed a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Snapped {
    /// Not finite, or the first point of a new vertex.
    New,
    /// Onto an existing vertex, this far away.
    Merged(f64),
}

impl VertexSnap {
    /// An empty set of vertices merging points within `radius` (no file tolerances).
    pub fn new(radius: f64) -> VertexSnap {
        VertexSnap::with_file_tolerances(radius, 0.0)
    }

    /// An empty set of vertices merging points within `base`, or within the sum of their file
    /// tolerances, none above `largest` (the grid's cells are as large as the largest merge
    /// distance, 2 × `largest`; file tolerances passed to [`VertexSnap::snap_within`] are
    /// capped at `largest`).
    pub fn with_file_tolerances(base: f64, largest: f64) -> VertexSnap {
        let base = base.max(f64::MIN_POSITIVE);
        let largest = largest.max(0.0);
        VertexSnap {
            reps: Vec::new(),
            base,
            cell: base.max(2.0 * largest),
            cells: HashMap::new(),
        }
    }

    /// The largest merge distance (the cell size).
    pub fn radius(&self) -> f64 {
        self.cell
    }

    fn cell_of(&self, p: DVec3) -> [i64; 3] {
        p.to_array().map(|c| (c / self.cell).floor() as i64)
    }

    /// The index of the nearest vertex within max(`base`, its file tolerance + `f`) of `p`,
    /// and the distance.
    fn nearest(&self, p: DVec3, f: f64) -> Option<(usize, f64)> {
        let c = self.cell_of(p);
        let mut best: Option<(usize, f64)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                    for &i in self.cells.get(&key).into_iter().flatten() {
                        let (q, g) = self.reps[i];
                        let d = (q - p).length();
                        if d <= self.base.max(g + f) && best.is_none_or(|(_, bd)| d < bd) {
                            best = Some((i, d));
                        }
                    }
                }
            }
        }
        best
    }

    /// The representative of the vertex `p` (without a file tolerance of its own) merges
    /// onto, if there is one.
    pub fn find(&self, p: DVec3) -> Option<DVec3> {
        self.find_within(p, 0.0)
    }

    /// [`VertexSnap::find`] for a point with the file tolerance `f`.
    pub fn find_within(&self, p: DVec3, f: f64) -> Option<DVec3> {
        let f = f.clamp(0.0, 0.5 * self.cell);
        self.nearest(p, f).map(|(i, _)| self.reps[i].0)
    }

    /// `p` (without a file tolerance) snapped onto an existing vertex, or made a new one.
    pub fn snap(&mut self, p: DVec3) -> DVec3 {
        self.snap_within(p, 0.0).0
    }

    /// `p`, with the file tolerance `f`, snapped onto the nearest vertex it merges with, or
    /// made a new vertex; and how.
    pub fn snap_within(&mut self, p: DVec3, f: f64) -> (DVec3, Snapped) {
        if !p.is_finite() {
            return (p, Snapped::New);
        }
        let f = f.clamp(0.0, 0.5 * self.cell);
        if let Some((i, d)) = self.nearest(p, f) {
            let (q, g) = self.reps[i];
            self.reps[i].1 = g.max(f);
            return (q, Snapped::Merged(d));
        }
        let key = self.cell_of(p);
        self.cells.entry(key).or_default().push(self.reps.len());
        self.reps.push((p, f));
        (p, Snapped::New)
    }
}

/// The radius within which edge end points are one vertex: a small fraction of the tolerance.
pub fn snap_radius(options: &Options) -> f64 {
    0.05 * options.tolerance
}

/// How many chordal tolerances a file's vertex tolerance may count for at most when merging
/// edge ends. Real files' vertex tolerances (1e-3 to 1e-2 mm) are below it at any tolerance
/// a part is tessellated to; a hostile or broken one (1e9) can then merge only features
/// smaller than 2 × 10 tolerances, which the mesh cannot show anyway, never a whole part.
pub const VERTEX_TOLERANCE_CAP: f64 = 10.0;

/// The file tolerance an edge end counts with: its vertex's `vertex` tolerance, capped at
/// [`VERTEX_TOLERANCE_CAP`] × the tolerance; 0 without one (or a non-finite one).
pub fn file_radius(vertex: Option<f64>, options: &Options) -> f64 {
    match vertex {
        Some(t) if t.is_finite() && t > 0.0 => t.min(VERTEX_TOLERANCE_CAP * options.tolerance),
        _ => 0.0,
    }
}

/// The surface point of a trim's curve at `t`.
pub fn trim_point(face: &Face, curve: &Curve2, t: f64) -> DVec3 {
    let uv = curve.point(t);
    face.surface.point(uv.x, uv.y)
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

/// What merging the edges' end points did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MergeStats {
    /// Edge ends merged onto a vertex farther than [`snap_radius`]: only the file's vertex
    /// tolerances merged them.
    pub by_file_tolerance: usize,
    /// The largest distance such an end moved.
    pub largest_distance: f64,
}

/// Discretises every edge of `doc` once.
pub fn discretise(doc: &Document, options: &Options) -> EdgeTable {
    discretise_with_stats(doc, options).0
}

/// [`discretise`], with what merging the end points through file tolerances did.
pub fn discretise_with_stats(doc: &Document, options: &Options) -> (EdgeTable, MergeStats) {
    let mut table = EdgeTable::new();
    let mut stats = MergeStats::default();
    let Some(edges) = &doc.edges else {
        return (table, stats);
    };
    let base = snap_radius(options);
    // First every edge's samples and its ends' file tolerances, so that the grid's cells can
    // be as large as the largest merge distance.
    struct Sampled {
        id: u64,
        params: Vec<f64>,
        points: Vec<DVec3>,
        length: f64,
        radii: [f64; 2],
    }
    let mut sampled = Vec::new();
    for edge in edges {
        let Some(curve) = &edge.curve else { continue };
        let [t0, t1] = edge.range;
        let f = |t: f64| curve.point(t);
        let min = min_segments(curve, t0, t1).max(2);
        let params = sample_chordal(&f, t0, t1, min, options.tolerance, options.angle);
        let points: Vec<DVec3> = params.iter().map(|&t| curve.point(t)).collect();
        let length: f64 = points.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        let vt = edge.vertex_tolerances;
        let radii = [0, 1].map(|k| file_radius(vt.map(|v| v[k]), options));
        sampled.push(Sampled {
            id: edge.id,
            params,
            points,
            length,
            radii,
        });
    }
    let largest = sampled.iter().flat_map(|s| s.radii).fold(0.0, f64::max);
    let mut snap = VertexSnap::with_file_tolerances(base, largest);
    let mut count = |how: Snapped| {
        // Beyond the chordal radius only a file tolerance can have merged it.
        if let Snapped::Merged(d) = how
            && d > base
        {
            stats.by_file_tolerance += 1;
            stats.largest_distance = stats.largest_distance.max(d);
        }
    };
    for Sampled {
        id,
        params,
        mut points,
        length,
        radii,
    } in sampled
    {
        let last = points.len() - 1;
        if length < 2.0 * base {
            // Shorter than the snapping: both ends would become one vertex and the middle
            // samples a needle out and back (a fold three triangles share; Pump_Nut's
            // 0.002 mm edge 18 at 0.1 mm). The edge is that vertex, as a degenerate one is.
            let (q, how) = snap.snap_within(points[0], radii[0]);
            count(how);
            table.insert(id, EdgeSamples::Point(q));
            continue;
        }
        let open = (points[0] - points[last]).length() > base;
        let (a, how_a) = snap.snap_within(points[0], radii[0]);
        let (b, how_b) = snap.snap_within(points[last], radii[1]);
        count(how_a);
        count(how_b);
        if open && a == b && length < radii[0] + radii[1] {
            // An open edge no longer than the distance its vertex tolerances merge, both ends
            // on one vertex: the same needle, for the same reason, so the edge is that vertex.
            table.insert(id, EdgeSamples::Point(a));
            continue;
        }
        points[0] = a;
        points[last] = b;
        table.insert(id, EdgeSamples::Curve { params, points });
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
            let f = file_radius(edge.vertex_tolerances.map(|v| v[0]), options);
            let q = snap.find_within(p, f).unwrap_or(p);
            table.insert(edge.id, EdgeSamples::Point(q));
        }
    }
    (table, stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::approx_constant)] // the very digits OCCT writes for 2π, and one turn above
    fn a_full_turn_written_to_15_digits_starts_from_four_segments() {
        let circle: Curve3 = Curve::Circle {
            center: DVec3::ZERO,
            x_dir: DVec3::X,
            y_dir: DVec3::Y,
            radius: 5.0,
        };
        assert_eq!(min_segments(&circle, 0.0, std::f64::consts::TAU), 4);
        assert_eq!(min_segments(&circle, 0.0, 6.28318530717959), 4);
        assert_eq!(min_segments(&circle, 0.0, 6.2832), 5);
    }
}
