"""Checks of a `tessd-brep` document exported from a FreeCAD shape, with FreeCAD as the ground
truth (the system Python; tests/brep's brep_checks.py needs OCP, which is not there).

The document is evaluated independently: lines, circles, ellipses and the analytic surfaces from
the format's formulas (docs/brep-format.md), B-splines through FreeCAD's own `Part.BSpline*`
rebuilt from the exported poles / knots / multiplicities. Then, per face of the shape:
- S(u, v) at random (u, v) of the bounds equals `face.Surface.value` there (at 2π - u where the
  frame is left-handed, which is found here from the surface's own points, not the exporter's
  way); the document's normal (∂S/∂u × ∂S/∂v, negated when `reversed`) agrees with FreeCAD's
  `face.normalAt`;
- the loops are FreeCAD's wires (as many, and as many edge trims as boundary edges);
- S(C(t)) along every trim is on its edge (`edge.valueAt(t)` at the same t), and the trim's ends
  are the edge's vertices; gap bridges stay within the vertex tolerance;
- every edge lists the faces FreeCAD says it bounds (`ancestorsOfType`)."""

from __future__ import annotations

import math
import random
import time
from collections import Counter
from typing import Any, Dict, List, Optional, Sequence, Tuple

import FreeCAD
import Part

V = FreeCAD.Vector
V2 = FreeCAD.Base.Vector2d
TWO_PI = 2.0 * math.pi
ANALYTIC_PERIODIC = ("cylinder", "cone", "sphere", "torus")
# FreeCAD's surface classes → the format's type (anything else is converted to a B-spline).
SURFACE_TYPE = {"Plane": "plane", "Cylinder": "cylinder", "Cone": "cone", "Sphere": "sphere",
                "Toroid": "torus", "SurfaceOfRevolution": "revolution",
                "SurfaceOfExtrusion": "extrusion", "BSplineSurface": "bspline",
                "BezierSurface": "bspline"}
TRIM_SAMPLES = 8
# (name, faces, edges, read ms, export ms, stats), printed by conftest.py at the end
TIMINGS: List[Tuple[str, int, int, float, float, Dict[str, Any]]] = []


def vec(v: Any) -> List[float]:
    return [v.x, v.y, v.z]


def dist(a: Sequence[float], b: Sequence[float]) -> float:
    return math.dist(a, b)


# ------------------------------------------------------------------------------------------
# the document's own geometry: each analytic type as a point in its frame's coordinates


def _in_frame(origin, x, y, local):
    """origin + a·x + b·y (+ c·(x × y) in 3D) for local = (a, b[, c])."""
    if len(origin) == 2:
        return [origin[i] + local[0] * x[i] + local[1] * y[i] for i in range(2)]
    o, vx, vy = V(*origin), V(*x), V(*y)
    return vec(o + vx * local[0] + vy * local[1] + vx.cross(vy) * local[2])


_SURFACE_LOCAL = {  # (u, v) → coordinates in the surface's frame, the format's table
    "plane": lambda s, u, v: (u, v, 0.0),
    "cylinder": lambda s, u, v: (s["radius"] * math.cos(u), s["radius"] * math.sin(u), v),
    "cone": lambda s, u, v: ((s["radius"] + v * math.sin(s["semi_angle"])) * math.cos(u),
                             (s["radius"] + v * math.sin(s["semi_angle"])) * math.sin(u),
                             v * math.cos(s["semi_angle"])),
    "sphere": lambda s, u, v: (s["radius"] * math.cos(v) * math.cos(u),
                               s["radius"] * math.cos(v) * math.sin(u), s["radius"] * math.sin(v)),
    "torus": lambda s, u, v: ((s["major_radius"] + s["minor_radius"] * math.cos(v)) * math.cos(u),
                              (s["major_radius"] + s["minor_radius"] * math.cos(v)) * math.sin(u),
                              s["minor_radius"] * math.sin(v)),
}
_CURVE_LOCAL = {  # t → coordinates in the curve's axes (x_dir, y_dir)
    "circle": lambda c, t: (c["radius"] * math.cos(t), c["radius"] * math.sin(t), 0.0),
    "ellipse": lambda c, t: (c["major_radius"] * math.cos(t), c["minor_radius"] * math.sin(t), 0.0),
}


class Evaluator:
    """S(u, v) and C(t) from the document's data alone: the analytic types from the format's
    formulas, B-splines rebuilt in FreeCAD, revolutions turned by FreeCAD's `Rotation` (which
    checks the format's sense of rotation: counter-clockwise about `axis_dir`)."""

    def __init__(self) -> None:
        self._cache: Dict[int, Any] = {}

    def _rebuilt(self, d: Dict[str, Any]) -> Any:
        key = id(d)
        if key not in self._cache:
            if "degree" in d:  # a curve
                dim = len(d["poles"][0])
                obj = Part.BSplineCurve() if dim == 3 else Part.Geom2d.BSplineCurve2d()
                args = [[V(*p) if dim == 3 else V2(*p) for p in d["poles"]], d["mults"],
                        d["knots"], d["periodic"], d["degree"]]
            else:
                obj = Part.BSplineSurface()
                args = [[[V(*p) for p in row] for row in d["poles"]], d["mults_u"], d["mults_v"],
                        d["knots_u"], d["knots_v"], d["periodic_u"], d["periodic_v"],
                        d["degree_u"], d["degree_v"]]
            if d["weights"] is not None:
                args.append(d["weights"])
            obj.buildFromPolesMultsKnots(*args)
            self._cache[key] = (obj, d)  # keep d alive: the key is its id
        return self._cache[key][0]

    def curve(self, c: Dict[str, Any], t: float) -> List[float]:
        kind = c["type"]
        if kind in _CURVE_LOCAL:
            return _in_frame(c["center"], c["x_dir"], c["y_dir"], _CURVE_LOCAL[kind](c, t))
        if kind == "line":
            return [o + t * d for o, d in zip(c["origin"], c["dir"])]
        assert kind == "bspline", f"unknown curve type {kind}"
        p = self._rebuilt(c).value(t)
        return [p.x, p.y, p.z] if len(c["poles"][0]) == 3 else [p.x, p.y]

    def surface(self, s: Dict[str, Any], u: float, v: float) -> List[float]:
        kind = s["type"]
        if kind in _SURFACE_LOCAL:
            return _in_frame(s["origin"], s["x_dir"], s["y_dir"], _SURFACE_LOCAL[kind](s, u, v))
        if kind == "revolution":
            o = V(*s["axis_origin"])
            turn = FreeCAD.Rotation(V(*s["axis_dir"]), math.degrees(u))
            return vec(o + turn.multVec(V(*self.curve(s["curve"], v)) - o))
        if kind == "extrusion":
            return vec(V(*self.curve(s["curve"], u)) + V(*s["direction"]) * v)
        assert kind == "bspline", f"unknown surface type {kind}"
        return vec(self._rebuilt(s).value(u, v))

    def normal(self, s: Dict[str, Any], u: float, v: float, h: float) -> Optional[Any]:
        """The unit ∂S/∂u × ∂S/∂v by central differences (step h in the parameters), a Vector;
        None where S is degenerate (a pole, an apex)."""
        du = V(*self.surface(s, u + h, v)) - V(*self.surface(s, u - h, v))
        dv = V(*self.surface(s, u, v + h)) - V(*self.surface(s, u, v - h))
        n = du.cross(dv)
        if n.Length <= 1e-6 * du.Length * dv.Length:
            return None
        return n * (1.0 / n.Length)


# ------------------------------------------------------------------------------------------
# FreeCAD's side


def face_edges(shape: Any) -> List[Any]:
    """The shape's edges by topology, in the order the faces meet them (one per `isSame`
    class): the format's edge ids are 1 + the index here."""
    out: List[Any] = []
    for f in shape.Faces:
        for e in f.Edges:
            if not any(o.isSame(e) for o in out):
                out.append(e)
    return out


def indirect_frame(surface: Any) -> bool:
    """Whether an elementary periodic surface's frame is left-handed, from its own points: X
    and Y point to S(0, v) and S(π/2, v) from the axis, and X × Y must be the axis."""
    v = 0.0
    if isinstance(surface, Part.Cone) and surface.Radius <= 0:
        v = 1.0 if surface.SemiAngle > 0 else -1.0
    x = surface.value(0.0, v) - surface.value(math.pi, v)
    y = surface.value(math.pi / 2, v) - surface.value(3 * math.pi / 2, v)
    return x.cross(y).dot(surface.Axis) < 0


def expected_type(face: Any) -> str:
    """The format type FreeCAD's own classes call for (revolutions / extrusions of curves with
    no format type, offsets, ... are converted to B-splines)."""
    try:
        s = face.Surface
    except Exception:
        return "bspline"
    name = type(s).__name__
    if name in ("SurfaceOfRevolution", "SurfaceOfExtrusion"):
        basis = type(s.BasisCurve).__name__
        if not any(k in basis for k in ("Line", "Circle", "Ellipse", "BSpline", "Bezier")):
            return "bspline"
    return SURFACE_TYPE.get(name, "bspline")


def shape_size(shape: Any) -> float:
    return shape.BoundBox.DiagonalLength


def boundary_edges(wire: Any) -> List[Any]:
    return [e for e in wire.childShapes() if e.Orientation not in ("Internal", "External")]


def check_against_freecad(doc: Dict[str, Any], shape: Any, ev: Optional[Evaluator] = None,
                          seed: int = 1) -> Dict[str, Any]:
    """Every check of the module docstring; returns the worst deviations (relative to the part
    size) and counts."""
    ev = ev or Evaluator()
    rng = random.Random(seed)
    size = shape_size(shape)
    faces = shape.Faces
    edges = face_edges(shape)
    assert [f["id"] for f in doc["faces"]] == list(range(1, len(faces) + 1))
    assert [e["id"] for e in doc["edges"]] == list(range(1, len(edges) + 1))
    stats: Dict[str, Any] = {"surface": 0.0, "trim": 0.0, "vertex": 0.0, "mirrored": 0,
                             "converted": 0, "bridges": 0, "seams": 0, "normals": 0}
    for f in doc["faces"]:
        where = f"face {f['id']}"
        face = faces[f["id"] - 1]
        s = f["surface"]
        surface = _try_surface(face)  # None: no Part class for it (converted)
        assert s["type"] == expected_type(face), \
            f"{where}: {s['type']} for FreeCAD's {type(surface).__name__}"
        converted = s["type"] == "bspline" and \
            type(surface).__name__ not in ("BSplineSurface", "BezierSurface")
        stats["converted"] += converted
        mirrored = f["reversed"] != (face.Orientation == "Reversed")
        if s["type"] in ANALYTIC_PERIODIC:
            assert mirrored == indirect_frame(surface), f"{where}: mirrored {mirrored}, FreeCAD's frame " \
                f"{'indirect' if indirect_frame(surface) else 'direct'}"
        else:
            assert not mirrored, f"{where}: a {s['type']} cannot be mirrored"
        stats["mirrored"] += mirrored
        u0, u1, v0, v1 = f["bounds"]
        bsize = math.hypot(u1 - u0, v1 - v0)
        for _ in range(12):
            u, v = u0 + (u1 - u0) * rng.random(), v0 + (v1 - v0) * rng.random()
            p = ev.surface(s, u, v)
            if converted and surface is None:
                d, uf = face.distToShape(Part.Vertex(V(*p)))[0], None
            elif converted:
                d = surface.projectPoint(V(*p), "LowerDistance")
                uf, vf = surface.parameter(V(*p))
            else:
                uf, vf = (TWO_PI - u if mirrored else u), v
                d = dist(p, vec(surface.value(uf, vf)))
            stats["surface"] = max(stats["surface"], d / size)
            assert d <= 1e-9 * size + (1e-6 * size if converted else 0), \
                f"{where} ({s['type']}): S({u}, {v}) off FreeCAD's surface by {d:.3g}"
            if uf is None:
                continue
            n = ev.normal(s, u, v, 1e-6 * bsize)
            theirs = face.normalAt(uf, vf)  # with the face's orientation
            if n is not None and theirs.Length > 0.5:
                cos = n.dot(theirs) * (-1 if f["reversed"] else 1)
                stats["normals"] += 1
                assert cos > 0.99, \
                    f"{where}: normal {n} against FreeCAD's {theirs} (reversed {f['reversed']})"
        _check_loops(f, face, edges, s, ev, size, stats, where)
    for e in doc["edges"]:
        edge = edges[e["id"] - 1]
        owners = sorted({i + 1 for a in shape.ancestorsOfType(edge, Part.Face)
                         for i, face in enumerate(faces) if face.isSame(a)})
        assert sorted(e["faces"]) == owners, f"edge {e['id']}: faces {e['faces']}, FreeCAD's {owners}"
        if edge.Degenerated:
            assert e["curve"] is None, f"edge {e['id']}: a curve for a degenerate edge"
        else:
            assert e["curve"] is not None, f"edge {e['id']}: no curve"
        _check_tolerances(doc, e, edge, ev, size)
    return stats


def _check_tolerances(doc: Dict[str, Any], e: Dict[str, Any], edge: Any, ev: Evaluator, size: float) -> None:
    """The edge's `tolerance` and `vertex_tolerances` are FreeCAD's (in millimetres: a document
    in other units has them scaled, and `shape` may be a scaled copy, whose OCCT tolerances are
    clamped at 1e-7, so only the geometry is checked there): the vertex at each end of the range
    lies within its tolerance of the document's curve there."""
    where = f"edge {e['id']}"
    v = [edge.firstVertex(False), edge.lastVertex(False)]
    tol, vt = e["tolerance"], e["vertex_tolerances"]
    assert tol >= 0 and len(vt) == 2 and min(vt) >= 0, f"{where}: {tol}, {vt}"
    if doc["units"] == "mm":
        assert tol == edge.Tolerance and vt == [x.Tolerance for x in v], f"{where}: {tol}, {vt}"
    if e["curve"] is not None:
        for k in range(2):
            d = dist(ev.curve(e["curve"], e["range"][k]), vec(v[k].Point))
            assert d <= vt[k] + 1e-9 * size, \
                f"{where}: the vertex of range[{k}] is {d:.3g} from the curve's end (tolerance {vt[k]:.3g})"


def _try_surface(face: Any) -> Any:
    try:
        return face.Surface
    except Exception:
        return None


def _check_loops(f: Dict[str, Any], face: Any, edges: List[Any], s: Dict[str, Any], ev: Evaluator,
                 size: float, stats: Dict[str, Any], where: str) -> None:
    wires = [w for w in face.Wires if boundary_edges(w)]
    assert len(f["loops"]) == len(wires), f"{where}: {len(f['loops'])} loops, FreeCAD {len(wires)} wires"
    mine = sorted(sum(1 for t in lp["edges"] if t["edge"] is not None) for lp in f["loops"])
    theirs = sorted(len(boundary_edges(w)) for w in wires)
    assert mine == theirs, f"{where}: edge trims per loop {mine}, FreeCAD's edges per wire {theirs}"
    vtol = max((v.Tolerance for v in face.Vertexes), default=0.0)
    for li, loop in enumerate(f["loops"]):
        ids = [t["edge"] for t in loop["edges"] if t["edge"] is not None]
        stats["seams"] += sum(1 for i in set(ids) if ids.count(i) == 2)
        for ti, tr in enumerate(loop["edges"]):
            tw = f"{where} loop {li} trim {ti}"
            t0, t1 = tr["range"]
            if tr["edge"] is None:
                assert tr["curve"]["type"] == "line", f"{tw}: no edge id"
                a, b = ev.surface(s, *ev.curve(tr["curve"], t0)), ev.surface(s, *ev.curve(tr["curve"], t1))
                assert dist(a, b) <= max(1e-6 * size, 2.001 * vtol), f"{tw}: bridge of {dist(a, b):.3g}"
                stats["bridges"] += 1
                continue
            edge = edges[tr["edge"] - 1]
            pts = [ev.surface(s, *ev.curve(tr["curve"], t0 + (t1 - t0) * k / TRIM_SAMPLES))
                   for k in range(TRIM_SAMPLES + 1)]
            if edge.Degenerated:  # a pole: every point is the vertex
                q = vec(edge.Vertexes[0].Point)
                tol = max(1e-6 * size, 1.001 * edge.Vertexes[0].Tolerance)
                assert max(dist(p, q) for p in pts) <= tol, f"{tw}: degenerate trim off its vertex"
                continue
            e0, e1 = edge.ParameterRange
            etol = max(1e-6 * size, 1.001 * edge.Tolerance)
            same_param = abs(min(t0, t1) - e0) <= 1e-9 * (1 + abs(e0)) and \
                abs(max(t0, t1) - e1) <= 1e-9 * (1 + abs(e1))
            for k, p in enumerate(pts):
                if same_param:
                    d = dist(p, vec(edge.valueAt(t0 + (t1 - t0) * k / TRIM_SAMPLES)))
                else:
                    d = edge.distToShape(Part.Vertex(V(*p)))[0]
                stats["trim"] = max(stats["trim"], d / size)
                assert d <= etol, \
                    f"{tw} (edge {tr['edge']}): S(C(t)) {d:.3g} from the edge (allowed {etol:.3g})"
            # the trim's ends are the edge's vertices (its start the first one, walked forward)
            first, last = edge.firstVertex(), edge.lastVertex()
            lo, hi = (pts[0], pts[-1]) if t0 < t1 else (pts[-1], pts[0])
            for p, vx in ((lo, first), (hi, last)):
                d = dist(p, vec(vx.Point))
                stats["vertex"] = max(stats["vertex"], d / size)
                assert d <= max(1e-6 * size, 1.001 * (vx.Tolerance + edge.Tolerance)), \
                    f"{tw} (edge {tr['edge']}): an end {d:.3g} from its vertex"


def surface_counts(shape: Any) -> Counter:
    return Counter(expected_type(f) for f in shape.Faces)


# ------------------------------------------------------------------------------------------
# the cases: the shared files and the FreeCAD-built parts, each read and exported once


def shared_files() -> List[str]:
    import locate

    d = locate.shared_data() / "brep"
    return sorted(p.name for p in d.glob("*") if p.suffix.lower() in
                  (".step", ".stp", ".iges", ".igs", ".brep", ".brp")) if d.is_dir() else []


_EXPORTED: Dict[str, Tuple[Any, Dict[str, Any], float, float]] = {}


def exported(name: str) -> Tuple[Any, Dict[str, Any]]:
    """(shape, document) of a shared file (by file name) or a built part (fc_parts.PARTS),
    read / built and exported once per run."""
    return exported_timed(name)[:2]


def exported_timed(name: str) -> Tuple[Any, Dict[str, Any], float, float]:
    """exported()'s (shape, document) with the read (or build) and export times in ms."""
    if name not in _EXPORTED:
        import locate
        from fc_parts import PARTS
        from tessd.brep import export_shape
        from tessd.brep import freecad as brep_freecad

        t0 = time.perf_counter()
        shape = PARTS[name]() if name in PARTS else \
            brep_freecad.read_file(str(locate.shared_data() / "brep" / name))
        t1 = time.perf_counter()
        doc = export_shape(shape, source=name)
        t2 = time.perf_counter()
        _EXPORTED[name] = (shape, doc, 1000 * (t1 - t0), 1000 * (t2 - t1))
    return _EXPORTED[name]
