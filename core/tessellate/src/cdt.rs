//! Step 4: the constrained Delaunay triangulation (`spade`) of a face's boundary polylines and
//! interior points, in (u, v) scaled to be roughly metric. Triangles inside the trims are those
//! an odd number of boundary segments away from the outside (a flood fill from the convex hull
//! flipping at each constraint edge: the loops' even-odd rule). Then refinement: inside
//! triangles whose centroid, or whose interior edges' midpoints, lie further than the tolerance
//! from the surface (or whose normal turns more than the angle from the surface's) get that
//! point inserted, a few passes over.

use crate::Options;
use crate::boundary::Polyline;
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{ConstrainedDelaunayTriangulation, HasPosition, Point2, Triangulation};
use std::collections::HashSet;
use tessd_brep::Face;
use tessd_brep::vector::{Vector, cross};

/// A triangulation vertex: scaled (u, v) for spade, the true (u, v) and the 3D position.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    pos: Point2<f64>,
    uv: [f64; 2],
    p: [f64; 3],
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

/// Triangulates one face.
pub fn triangulate(
    face: &Face,
    loops: &[Polyline],
    interior: &[[f64; 2]],
    scale: [f64; 2],
    metric: [f64; 2],
    options: &Options,
) -> FaceTriangles {
    let mut cdt = Cdt::new();
    let mk = |uv: [f64; 2], p: [f64; 3]| Vertex {
        pos: Point2::new(uv[0] * scale[0], uv[1] * scale[1]),
        uv,
        p,
    };
    let surface_vertex = |pos: Point2<f64>| {
        let uv = [pos.x / scale[0], pos.y / scale[1]];
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
    let mut refined = 0;
    let mut inside = classify(&cdt);
    let mut checked = Checked::default();
    for _ in 0..PASSES {
        if cdt.num_vertices() >= MAX_VERTICES {
            break;
        }
        let wanted = refinement_points(face, &cdt, &inside, metric, options, &mut checked);
        if wanted.is_empty() {
            break;
        }
        for uv in wanted {
            if cdt.num_vertices() >= MAX_VERTICES {
                break;
            }
            if cdt.insert(mk(uv, face.surface.point(uv[0], uv[1]))).is_ok() {
                refined += 1;
            }
        }
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
                out.points.push(v.data().p);
                out.uvs.push(v.data().uv);
            }
            tri[k] = index[i];
        }
        out.triangles.push(tri);
    }
    out
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
fn near_constraint(f: &FaceRef<'_>, uv: [f64; 2], metric: [f64; 2]) -> bool {
    let at = |uv: [f64; 2]| Point2::new(uv[0] * metric[0], uv[1] * metric[1]);
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
    triangles: HashSet<[usize; 3]>,
    edges: HashSet<(usize, usize)>,
}

/// The (u, v) points that the inside triangles want inserted.
fn refinement_points(
    face: &Face,
    cdt: &Cdt,
    inside: &[bool],
    metric: [f64; 2],
    options: &Options,
    checked: &mut Checked,
) -> Vec<[f64; 2]> {
    let mut out = Vec::new();
    let tol = options.tolerance;
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
        let edges_ok = triangle_points(face, &f, metric, options, tol, checked, &mut out);
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
    metric: [f64; 2],
    options: &Options,
    tol: f64,
    checked: &mut Checked,
    out: &mut Vec<[f64; 2]>,
) -> bool {
    let [a, b, c] = f.vertices().map(|v| *v.data());
    let cuv = a.uv.add(b.uv).add(c.uv).scale(1.0 / 3.0);
    let cp = a.p.add(b.p).add(c.p).scale(1.0 / 3.0);
    let sp = face.surface.eval(cuv[0], cuv[1]);
    if !sp.point.is_finite() {
        return true;
    }
    let n = cross(b.p.sub(a.p), c.p.sub(a.p));
    let area2 = n.norm();
    // Slivers and collapsed triangles (poles) have no reliable normal or centroid.
    let edge_max = [a.p.sub(b.p), b.p.sub(c.p), c.p.sub(a.p)]
        .iter()
        .map(|d| d.norm())
        .fold(0.0, f64::max);
    if area2 <= 1e-12 * edge_max * edge_max || edge_max <= 1e-3 * tol {
        return true;
    }
    let mut want = sp.point.sub(cp).norm() > tol;
    if !want && let Some(sn) = sp.normal() {
        let cosang = (n.dot(sn) / area2).abs().clamp(0.0, 1.0);
        want = cosang.acos() > options.angle && edge_max > 4.0 * tol;
    }
    if want {
        if !near_constraint(f, cuv, metric) {
            out.push(cuv);
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
        let muv = p.uv.add(q.uv).scale(0.5);
        let mp = p.p.add(q.p).scale(0.5);
        let s = face.surface.point(muv[0], muv[1]);
        if s.is_finite() && s.sub(mp).norm() > tol && !near_constraint(f, muv, metric) {
            out.push(muv);
            all = false;
        } else {
            checked.edges.insert((i, j));
        }
    }
    all
}
