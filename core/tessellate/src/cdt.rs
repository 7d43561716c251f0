//! Step 4: the constrained Delaunay triangulation (`spade`) of a face's boundary polylines and
//! interior points, in (u, v) scaled to be roughly metric. Triangles inside the trims are those
//! an odd number of boundary segments away from the outside (a flood fill from the convex hull
//! flipping at each constraint edge: the loops' even-odd rule). Then refinement: inside
//! triangles whose centroid, or whose interior edges' midpoints, lie further than the tolerance
//! from the surface (or whose normal turns more than the angle from the surface's) get that
//! point inserted, a few passes over.

use crate::Options;
use crate::boundary::Polyline;
use crate::interior::Plan;
use rustc_hash::FxHashSet;
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{ConstrainedDelaunayTriangulation, HasPosition, Point2, Triangulation};
use tessd_brep::{DVec2, DVec3, Face};

/// A triangulation vertex: scaled (u, v) for spade, the true (u, v) and the 3D position.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    pos: Point2<f64>,
    uv: DVec2,
    p: DVec3,
}

impl HasPosition for Vertex {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

type Cdt = ConstrainedDelaunayTriangulation<Vertex>;

/// The triangles of one face: 3D positions, (u, v) per vertex, and triangles (counter-clockwise
/// in (u, v)).
#[derive(Clone, Debug, Default)]
pub struct FaceTriangles {
    /// 3D positions.
    pub points: Vec<[f64; 3]>,
    /// (u, v) of each position.
    pub uvs: Vec<[f64; 2]>,
    /// Vertex indices, counter-clockwise in (u, v).
    pub triangles: Vec<[u32; 3]>,
    /// Refinement points inserted.
    pub refined: usize,
}

/// The most refinement passes, and the most vertices a face may reach by refinement.
const PASSES: usize = 16;
const MAX_VERTICES: usize = 400_000;
/// Refinement points inserted between two asks whether to go on: a face can take seconds at
/// a fine tolerance, and a cancelled job should not wait for it (~1 ms of insertions).
const INSERTS_PER_CHECK: usize = 1024;

/// Triangulates one face; `None` once `keep_going` says stop (asked before each refinement
/// pass and every [`INSERTS_PER_CHECK`] insertions).
pub fn triangulate(
    face: &Face,
    loops: &[Polyline],
    interior: &[DVec2],
    plan: &Plan,
    options: &Options,
    keep_going: &dyn Fn() -> bool,
) -> Option<FaceTriangles> {
    let scale = plan.delaunay;
    let b = plan.bounds;
    let shake = JITTER * ((b[1] - b[0]) * scale[0]).max((b[3] - b[2]) * scale[1]);
    let shake = if shake.is_finite() { shake } else { 0.0 };
    let mk = |uv: DVec2, p: DVec3| {
        let [jx, jy] = jitter(uv);
        Vertex {
            pos: Point2::new(uv[0] * scale[0] + shake * jx, uv[1] * scale[1] + shake * jy),
            uv,
            p,
        }
    };
    let mut cdt = bulk_load(loops, interior, face, &mk)
        .unwrap_or_else(|| insert_one_by_one(loops, interior, face, scale, &mk));
    let mut refined = 0;
    let mut inside = classify(&cdt);
    let mut checked = Checked::default();
    let limits = Limits::new(plan, options);
    for _ in 0..PASSES {
        if cdt.num_vertices() >= MAX_VERTICES {
            break;
        }
        if !keep_going() {
            return None;
        }
        let wanted = refinement_points(face, &cdt, &inside, &limits, &mut checked);
        if wanted.is_empty() {
            break;
        }
        for (k, (uv, hint)) in wanted.into_iter().enumerate() {
            if cdt.num_vertices() >= MAX_VERTICES {
                break;
            }
            if k % INSERTS_PER_CHECK == INSERTS_PER_CHECK - 1 && !keep_going() {
                return None;
            }
            let v = mk(uv, face.surface.point(uv[0], uv[1]));
            // The point lies in (or beside) the triangle it came from: start the search there.
            if cdt.insert_with_hint(v, hint).is_ok() {
                refined += 1;
            }
        }
        // The inserted points were meant to land in inside triangles only, so that the new
        // triangles would all be inside; fuzzing found documents (a mutated cylinder, loops
        // that still cross) where some land outside, and appending them as inside kept
        // triangles outside the trim. Classifying again is one walk over the triangles, as
        // the refinement pass itself is.
        inside = classify(&cdt);
    }
    let mut out = FaceTriangles {
        refined,
        ..FaceTriangles::default()
    };
    let mut index = vec![u32::MAX; cdt.num_vertices()];
    for f in cdt.inner_faces() {
        if !inside[f.fix().index()] {
            continue;
        }
        let vs = f.vertices();
        let mut tri = [0u32; 3];
        for (k, v) in vs.iter().enumerate() {
            let i = v.fix().index();
            if index[i] == u32::MAX {
                index[i] = out.points.len() as u32;
                out.points.push(v.data().p.to_array());
                out.uvs.push(v.data().uv.to_array());
            }
            tri[k] = index[i];
        }
        out.triangles.push(tri);
    }
    Some(out)
}

/// The size of the displacement of every point in the Delaunay plane, relative to the face's
/// extent there. Sampled circles are cocircular, grids and straight edges collinear, and
/// spade's exact predicates settle such ties with multi-word arithmetic (half of a holed
/// plate's time); a displacement far above rounding and far below any sample spacing makes
/// every test decide in plain f64. Only the Delaunay plane moves: each vertex keeps its true
/// (u, v) and 3D point.
const JITTER: f64 = 1e-10;

/// A displacement in [−1, 1]² that depends on the point alone (equal points stay equal:
/// loops meeting at a vertex still meet), from a hash of its coordinates' bits.
fn jitter(uv: DVec2) -> [f64; 2] {
    let mut h = uv[0].to_bits() ^ uv[1].to_bits().rotate_left(29) ^ 0x9e37_79b9_7f4a_7c15;
    // SplitMix64's finaliser.
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    let unit = |x: u64| (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
    [unit(h), unit(h.rotate_left(32))]
}

/// The triangulation of the loops and interior points loaded at once (spade's bulk loading, a
/// few times faster than inserting point by point); `None` when constraint edges conflict
/// (cross or overlap) and would be dropped.
fn bulk_load(
    loops: &[Polyline],
    interior: &[DVec2],
    face: &Face,
    mk: &dyn Fn(DVec2, DVec3) -> Vertex,
) -> Option<Cdt> {
    let count = loops.iter().map(Vec::len).sum::<usize>() + interior.len();
    let mut vertices = Vec::with_capacity(count);
    let mut edges = Vec::with_capacity(count);
    for lp in loops {
        let base = vertices.len();
        vertices.extend(lp.iter().map(|b| mk(b.uv, b.p)));
        edges.extend((0..lp.len()).map(|k| [base + k, base + (k + 1) % lp.len()]));
    }
    vertices.extend(
        interior
            .iter()
            .map(|&uv| mk(uv, face.surface.point(uv[0], uv[1]))),
    );
    if vertices
        .iter()
        .any(|v| !(v.pos.x.is_finite() && v.pos.y.is_finite()))
    {
        return None;
    }
    let mut conflicts = 0;
    let cdt = Cdt::try_bulk_load_cdt(vertices, edges, |_| conflicts += 1).ok()?;
    (conflicts == 0).then_some(cdt)
}

/// The triangulation built point by point: the fallback where loops conflict, each crossing
/// split at a new surface point (an open edge in the welded mesh, but a face that stays whole).
fn insert_one_by_one(
    loops: &[Polyline],
    interior: &[DVec2],
    face: &Face,
    scale: [f64; 2],
    mk: &dyn Fn(DVec2, DVec3) -> Vertex,
) -> Cdt {
    let mut cdt = Cdt::new();
    let surface_vertex = |pos: Point2<f64>| {
        let uv = DVec2::new(pos.x / scale[0], pos.y / scale[1]);
        Vertex {
            pos,
            uv,
            p: face.surface.point(uv[0], uv[1]),
        }
    };
    for lp in loops {
        let handles: Vec<Option<FixedVertexHandle>> =
            lp.iter().map(|b| cdt.insert(mk(b.uv, b.p)).ok()).collect();
        for k in 0..handles.len() {
            if let (Some(a), Some(b)) = (handles[k], handles[(k + 1) % handles.len()])
                && a != b
            {
                cdt.add_constraint_and_split(a, b, surface_vertex);
            }
        }
    }
    for &uv in interior {
        let _ = cdt.insert(mk(uv, face.surface.point(uv[0], uv[1])));
    }
    cdt
}

/// For each face of the triangulation (by index), whether it lies inside the trims.
fn classify(cdt: &Cdt) -> Vec<bool> {
    let n = cdt.all_faces().len();
    let mut inside = vec![false; n];
    let mut seen = vec![false; n];
    let mut stack: Vec<(FixedFaceHandle<InnerTag>, bool)> = Vec::new();
    for e in cdt.convex_hull() {
        // Hull edges run with the outer face on their left; the inner face is across.
        let inner = e.rev().face();
        if let Some(f) = inner.as_inner() {
            stack.push((f.fix(), e.is_constraint_edge()));
        }
    }
    while let Some((f, parity)) = stack.pop() {
        let i = f.index();
        if seen[i] {
            continue;
        }
        seen[i] = true;
        inside[i] = parity;
        for e in cdt.face(f).adjacent_edges() {
            let across = e.rev().face();
            if let Some(g) = across.as_inner()
                && !seen[g.fix().index()]
            {
                stack.push((g.fix(), parity ^ e.is_constraint_edge()));
            }
        }
    }
    inside
}

type FaceRef<'a> = spade::handles::FaceHandle<'a, InnerTag, Vertex, (), spade::CdtEdge<()>, ()>;

/// A candidate point closer than this fraction of a constraint edge's length to that edge (in
/// the 3D metric) is not inserted.
const NEAR: f64 = 0.25;

/// Whether the point `uv` lies within [`NEAR`] of one of `f`'s constraint edges, measured with
/// the 3D `metric` (the Delaunay plane may be squeezed along rulings, where every point is
/// near the long boundary rows). Such a
/// point is a fin in the making: the edge's samples are fixed (neighbouring faces share them),
/// so the point cannot split it, and the sliver between them — flat in (u, v), upright in 3D
/// where the edge is a straight pcurve on a curved surface (a helix on a cylinder) — adds area
/// that covers no surface (7 % on the thread of OCCT's bottle).
fn near_constraint(f: &FaceRef<'_>, uv: DVec2, metric: [f64; 2]) -> bool {
    let at = |uv: DVec2| Point2::new(uv[0] * metric[0], uv[1] * metric[1]);
    let p = at(uv);
    f.adjacent_edges().iter().any(|e| {
        if !e.is_constraint_edge() {
            return false;
        }
        let (a, b) = (at(e.from().data().uv), at(e.to().data().uv));
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let len2 = dx * dx + dy * dy;
        let t = (((p.x - a.x) * dx + (p.y - a.y) * dy) / len2).clamp(0.0, 1.0);
        let (ex, ey) = (a.x + t * dx - p.x, a.y + t * dy - p.y);
        ex * ex + ey * ey < NEAR * NEAR * len2
    })
}

/// Triangles and edges that passed every test, by their vertices: they stand unchanged from
/// pass to pass unless a point lands in them, so they are not evaluated again (the surface
/// evaluations of the tests are most of the tessellator's time).
#[derive(Default)]
struct Checked {
    triangles: FxHashSet<[usize; 3]>,
    edges: FxHashSet<(usize, usize)>,
}

/// What refinement tests a face's triangles against.
struct Limits {
    /// The chordal tolerance.
    tol: f64,
    /// The cosine of the angle.
    cos_angle: f64,
    /// The shortest longest-edge of a triangle that is split for its normal: a quarter of the
    /// 3D length of the face's shortest curvature step (and at least 4 tolerances). The grid's
    /// steps already keep the surface's turn within the angle; a triangle smaller than that
    /// which still fails sits on something splitting cannot resolve — the fixed samples of a
    /// boundary where the surface twists across it, a degenerate edge's fan — and without the
    /// floor a thin fillet strip (CrankArm face 40 at angle 0.05) was split 400 000 times.
    angle_floor: f64,
    /// The (u, v) scale of 3D distances, for [`near_constraint`].
    metric: [f64; 2],
}

impl Limits {
    fn new(plan: &Plan, options: &Options) -> Limits {
        let step = [0, 1]
            .map(|k| plan.survey.curvature[k] * plan.survey.metric[k])
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        let floor = if step.is_finite() { 0.25 * step } else { 0.0 };
        Limits {
            tol: options.tolerance,
            cos_angle: options.angle.cos(),
            angle_floor: floor.max(4.0 * options.tolerance),
            metric: plan.survey.metric,
        }
    }
}

/// The (u, v) points that the inside triangles want inserted.
fn refinement_points(
    face: &Face,
    cdt: &Cdt,
    inside: &[bool],
    limits: &Limits,
    checked: &mut Checked,
) -> Vec<(DVec2, FixedVertexHandle)> {
    let mut out = Vec::new();
    for f in cdt.inner_faces() {
        if !inside[f.fix().index()] {
            continue;
        }
        let mut key = f.vertices().map(|v| v.fix().index());
        key.sort_unstable();
        if checked.triangles.contains(&key) {
            continue;
        }
        let before = out.len();
        let edges_ok = triangle_points(face, &f, limits, checked, &mut out);
        if edges_ok && out.len() == before {
            checked.triangles.insert(key);
        }
    }
    out
}

/// The points one triangle wants (pushed onto `out`); false when an edge was not checked.
fn triangle_points(
    face: &Face,
    f: &FaceRef<'_>,
    limits: &Limits,
    checked: &mut Checked,
    out: &mut Vec<(DVec2, FixedVertexHandle)>,
) -> bool {
    let (tol, metric) = (limits.tol, limits.metric);
    let [a, b, c] = f.vertices().map(|v| *v.data());
    let cuv = (a.uv + b.uv + c.uv) * (1.0 / 3.0);
    let cp = (a.p + b.p + c.p) * (1.0 / 3.0);
    let sp = face.surface.eval(cuv[0], cuv[1]);
    if !sp.point.is_finite() {
        return true;
    }
    let n = (b.p - a.p).cross(c.p - a.p);
    let area2 = n.length();
    // Slivers and collapsed triangles (poles) have no reliable normal or centroid.
    let edge_max = [a.p - b.p, b.p - c.p, c.p - a.p]
        .iter()
        .map(|d| d.length())
        .fold(0.0, f64::max);
    if area2 <= 1e-12 * edge_max * edge_max || edge_max <= 1e-3 * tol {
        return true;
    }
    let mut want = (sp.point - cp).length() > tol;
    if !want && let Some(sn) = sp.normal() {
        let cosang = (n.dot(sn) / area2).abs().clamp(0.0, 1.0);
        want = cosang < limits.cos_angle && edge_max > limits.angle_floor;
    }
    if want {
        if !near_constraint(f, cuv, metric) {
            out.push((cuv, f.vertices()[0].fix()));
        }
        return true;
    }
    let mut all = true;
    for e in f.adjacent_edges() {
        if e.is_constraint_edge() {
            continue;
        }
        let (i, j) = (e.from().fix().index(), e.to().fix().index());
        // Each interior edge once: from its lower-index end.
        if i > j || checked.edges.contains(&(i, j)) {
            continue;
        }
        let [p, q] = [e.from(), e.to()].map(|v| *v.data());
        let muv = (p.uv + q.uv) * 0.5;
        let mp = (p.p + q.p) * 0.5;
        let s = face.surface.point(muv[0], muv[1]);
        if s.is_finite() && (s - mp).length() > tol && !near_constraint(f, muv, metric) {
            out.push((muv, e.from().fix()));
            all = false;
        } else {
            checked.edges.insert((i, j));
        }
    }
    all
}
