"""Independent checks of an exported `tessd-brep` v1 document against the OCP shape it came from.

The format's rules (docs/brep-format.md) are checked on the document alone, with a small
numpy-free evaluator written here from the format's own formulas (B-splines are rebuilt as OCP
`Geom(2d)_BSpline*` objects from the exported poles / knots, which also checks their counts).
Then the document is compared with OCP's own evaluation of the original shape:
- surfaces: S(u, v) of the document at random (u, v) in the face's bounds equals
  `BRepAdaptor_Surface.Value` at the same (u, v) (at (2π - u, v) for a cylinder / cone / sphere /
  torus on an indirect OCP frame, which the exporter mirrors; for a face that went through
  NurbsConvert: the point's distance to the original surface);
- trims: S(C(t)) of the document at samples of every trim equals OCP's 3D point of the trim's
  edge (`BRepAdaptor_Curve`) at t (the distance to the edge's curve where the trim's curve was
  re-parametrised by a converter)."""

from __future__ import annotations

import math
import random
from typing import Any, Dict, List, Optional, Sequence, Tuple

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib
from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface
from OCP.Geom2d import Geom2d_BSplineCurve
from OCP.GeomAbs import GeomAbs_BezierSurface, GeomAbs_BSplineSurface, GeomAbs_Cone, GeomAbs_Cylinder, GeomAbs_Sphere, GeomAbs_Torus
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve, GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS

# OCP 7.9 and 8.0 (build123d) both: the collections OCP 8.0 moved, the static methods' spelling
from tessd.brep.ocp_compat import (
    TColgp_Array1OfPnt,
    TColgp_Array1OfPnt2d,
    TColgp_Array2OfPnt,
    TColStd_Array1OfInteger,
    TColStd_Array1OfReal,
    TColStd_Array2OfReal,
    TopTools_IndexedMapOfShape,
)
from tessd.brep.ocp_compat import static as _s

TWO_PI = 2.0 * math.pi
SURFACE_TYPES = {"plane", "cylinder", "cone", "sphere", "torus", "revolution", "extrusion", "bspline"}
CURVE_TYPES = {"line", "circle", "ellipse", "bspline"}
UNITS = {"mm", "cm", "m", "in"}
TRIM_SAMPLES = 8
# (name, faces, edges, read ms, export ms, stats) of every export, printed by tests/brep/conftest.py
TIMINGS: List[Tuple[str, int, int, float, float, Any]] = []


# ------------------------------------------------------------------------------------------
# vectors


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def mul(a, k):
    return [x * k for x in a]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    return math.sqrt(dot(a, a))


def dist(a, b):
    return norm(sub(a, b))


# ------------------------------------------------------------------------------------------
# evaluation of the document's own geometry


class Evaluator:
    """S(u, v) and C(t) from the document's data alone (B-splines through rebuilt OCP objects)."""

    def __init__(self) -> None:
        self._cache: Dict[int, Any] = {}

    def _bspline_curve(self, c: Dict[str, Any]) -> Any:
        key = id(c)
        if key not in self._cache:
            dim = len(c["poles"][0])
            n = len(c["poles"])
            poles = (TColgp_Array1OfPnt if dim == 3 else TColgp_Array1OfPnt2d)(1, n)
            for i, p in enumerate(c["poles"]):
                poles.SetValue(i + 1, gp_Pnt(*p) if dim == 3 else gp_Pnt2d(*p))
            knots = TColStd_Array1OfReal(1, len(c["knots"]))
            mults = TColStd_Array1OfInteger(1, len(c["mults"]))
            for i, k in enumerate(c["knots"]):
                knots.SetValue(i + 1, k)
            for i, m in enumerate(c["mults"]):
                mults.SetValue(i + 1, m)
            cls = Geom_BSplineCurve if dim == 3 else Geom2d_BSplineCurve
            if c["weights"] is not None:
                w = TColStd_Array1OfReal(1, n)
                for i, x in enumerate(c["weights"]):
                    w.SetValue(i + 1, x)
                obj = cls(poles, w, knots, mults, c["degree"], c["periodic"])
            else:
                obj = cls(poles, knots, mults, c["degree"], c["periodic"])
            self._cache[key] = (obj, c)  # keep c alive: the key is its id
        return self._cache[key][0]

    def curve(self, c: Dict[str, Any], t: float) -> List[float]:
        ty = c["type"]
        if ty == "line":
            return add(c["origin"], mul(c["dir"], t))
        if ty == "circle":
            r = c["radius"]
            return add(c["center"], add(mul(c["x_dir"], r * math.cos(t)), mul(c["y_dir"], r * math.sin(t))))
        if ty == "ellipse":
            return add(c["center"], add(mul(c["x_dir"], c["major_radius"] * math.cos(t)),
                                        mul(c["y_dir"], c["minor_radius"] * math.sin(t))))
        if ty == "bspline":
            p = self._bspline_curve(c).Value(t)
            return [p.X(), p.Y(), p.Z()] if len(c["poles"][0]) == 3 else [p.X(), p.Y()]
        raise AssertionError(f"unknown curve type {ty}")

    def surface(self, s: Dict[str, Any], u: float, v: float) -> List[float]:
        ty = s["type"]
        if ty in ("plane", "cylinder", "cone", "sphere", "torus"):
            o, x, y = s["origin"], s["x_dir"], s["y_dir"]
            z = cross(x, y)
            radial = add(mul(x, math.cos(u)), mul(y, math.sin(u)))
            if ty == "plane":
                return add(o, add(mul(x, u), mul(y, v)))
            if ty == "cylinder":
                return add(o, add(mul(radial, s["radius"]), mul(z, v)))
            if ty == "cone":
                a = s["semi_angle"]
                return add(o, add(mul(radial, s["radius"] + v * math.sin(a)), mul(z, v * math.cos(a))))
            if ty == "sphere":
                r = s["radius"]
                return add(o, add(mul(radial, r * math.cos(v)), mul(z, r * math.sin(v))))
            R, r = s["major_radius"], s["minor_radius"]
            return add(o, add(mul(radial, R + r * math.cos(v)), mul(z, r * math.sin(v))))
        if ty == "revolution":
            p = sub(self.curve(s["curve"], v), s["axis_origin"])
            k = s["axis_dir"]
            c, sn = math.cos(u), math.sin(u)  # Rodrigues: rotation by u about k (right hand)
            rot = add(add(mul(p, c), mul(cross(k, p), sn)), mul(k, dot(k, p) * (1 - c)))
            return add(s["axis_origin"], rot)
        if ty == "extrusion":
            return add(self.curve(s["curve"], u), mul(s["direction"], v))
        if ty == "bspline":
            key = id(s)
            if key not in self._cache:
                nu, nv = len(s["poles"]), len(s["poles"][0])
                poles = TColgp_Array2OfPnt(1, nu, 1, nv)
                for i in range(nu):
                    for j in range(nv):
                        poles.SetValue(i + 1, j + 1, gp_Pnt(*s["poles"][i][j]))

                def arr(vals, cls):
                    a = cls(1, len(vals))
                    for i, x in enumerate(vals):
                        a.SetValue(i + 1, x)
                    return a

                ku, kv = arr(s["knots_u"], TColStd_Array1OfReal), arr(s["knots_v"], TColStd_Array1OfReal)
                mu, mv = arr(s["mults_u"], TColStd_Array1OfInteger), arr(s["mults_v"], TColStd_Array1OfInteger)
                if s["weights"] is not None:
                    w = TColStd_Array2OfReal(1, nu, 1, nv)
                    for i in range(nu):
                        for j in range(nv):
                            w.SetValue(i + 1, j + 1, s["weights"][i][j])
                    obj = Geom_BSplineSurface(poles, w, ku, kv, mu, mv, s["degree_u"], s["degree_v"],
                                              s["periodic_u"], s["periodic_v"])
                else:
                    obj = Geom_BSplineSurface(poles, ku, kv, mu, mv, s["degree_u"], s["degree_v"],
                                              s["periodic_u"], s["periodic_v"])
                self._cache[key] = (obj, s)
            p = self._cache[key][0].Value(u, v)
            return [p.X(), p.Y(), p.Z()]
        raise AssertionError(f"unknown surface type {ty}")


# ------------------------------------------------------------------------------------------
# the format's rules on the document alone


def _finite(x: Any, where: str) -> None:
    if isinstance(x, bool):
        return
    if isinstance(x, (int, float)):
        assert math.isfinite(x), f"{where}: non-finite number {x}"
    elif isinstance(x, list):
        for y in x:
            _finite(y, where)
    elif isinstance(x, dict):
        for k, y in x.items():
            _finite(y, f"{where}.{k}")


def _unit(v: Sequence[float], where: str) -> None:
    assert abs(norm(v) - 1.0) <= 1e-9, f"{where}: not a unit vector {v}"


def _check_bspline_counts(degree: int, knots, mults, npoles: int, periodic: bool, where: str) -> None:
    assert degree >= 1, f"{where}: degree {degree}"
    assert all(b > a for a, b in zip(knots, knots[1:])), f"{where}: knots not increasing"
    assert len(knots) == len(mults), f"{where}: knots/mults counts"
    for i, m in enumerate(mults):
        end = (i == 0 or i == len(mults) - 1) and not periodic
        assert 1 <= m <= degree + (1 if end else 0), f"{where}: multiplicity {m} at knot {i}"
    want = sum(mults) - mults[-1] if periodic else sum(mults) - degree - 1
    assert npoles == want, f"{where}: {npoles} poles, want {want}"


def check_curve(c: Dict[str, Any], dim: int, where: str) -> None:
    assert c["type"] in CURVE_TYPES, f"{where}: unknown curve type {c['type']}"
    ty = c["type"]
    if ty == "line":
        assert len(c["origin"]) == dim and len(c["dir"]) == dim
        _unit(c["dir"], where)
    elif ty in ("circle", "ellipse"):
        for k in ("center", "x_dir", "y_dir"):
            assert len(c[k]) == dim, f"{where}: {k}"
        _unit(c["x_dir"], where)
        _unit(c["y_dir"], where)
        assert abs(dot(c["x_dir"], c["y_dir"])) <= 1e-9, f"{where}: x_dir, y_dir not orthogonal"
        if ty == "circle":
            assert c["radius"] > 0, f"{where}: radius"
        else:
            assert c["major_radius"] > 0 and c["minor_radius"] > 0, f"{where}: radii"
    else:
        assert all(len(p) == dim for p in c["poles"]), f"{where}: pole dimension"
        _check_bspline_counts(c["degree"], c["knots"], c["mults"], len(c["poles"]), c["periodic"], where)
        if c["weights"] is not None:
            assert len(c["weights"]) == len(c["poles"]) and min(c["weights"]) > 0, f"{where}: weights"


def check_surface(s: Dict[str, Any], where: str) -> None:
    ty = s["type"]
    assert ty in SURFACE_TYPES, f"{where}: unknown surface type {ty}"
    if ty in ("plane", "cylinder", "cone", "sphere", "torus"):
        _unit(s["x_dir"], where + " x_dir")
        _unit(s["y_dir"], where + " y_dir")
        assert abs(dot(s["x_dir"], s["y_dir"])) <= 1e-9, f"{where}: frame not orthogonal"
        for k in ("radius", "major_radius", "minor_radius"):
            if k in s:
                assert s[k] > 0, f"{where}: {k} {s[k]}"
        if ty == "cone":
            assert abs(s["semi_angle"]) < math.pi / 2
    elif ty == "revolution":
        _unit(s["axis_dir"], where)
        check_curve(s["curve"], 3, where + " curve")
    elif ty == "extrusion":
        _unit(s["direction"], where)
        check_curve(s["curve"], 3, where + " curve")
    else:
        nu, nv = len(s["poles"]), len(s["poles"][0])
        assert all(len(row) == nv for row in s["poles"])
        _check_bspline_counts(s["degree_u"], s["knots_u"], s["mults_u"], nu, s["periodic_u"], where + " u")
        _check_bspline_counts(s["degree_v"], s["knots_v"], s["mults_v"], nv, s["periodic_v"], where + " v")
        if s["weights"] is not None:
            assert len(s["weights"]) == nu and all(len(r) == nv for r in s["weights"])
            assert min(min(r) for r in s["weights"]) > 0, f"{where}: weights"


def signed_area(ev: Evaluator, loop: Dict[str, Any], samples: int = 24) -> float:
    pts = []
    for tr in loop["edges"]:
        t0, t1 = tr["range"]
        for k in range(samples):
            pts.append(ev.curve(tr["curve"], t0 + (t1 - t0) * k / samples))
    return 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(pts, pts[1:] + pts[:1]))


def check_document(doc: Dict[str, Any], ev: Evaluator) -> Dict[str, float]:
    """The format's validation rules (docs/brep-format.md). Returns stats."""
    assert doc["format"] == "tessd-brep" and doc["version"] == 1
    assert doc["units"] in UNITS
    _finite(doc, "document")
    edge_ids = {e["id"] for e in doc.get("edges", [])}
    assert len(edge_ids) == len(doc.get("edges", [])), "duplicate edge ids"
    face_ids = [f["id"] for f in doc["faces"]]
    assert len(set(face_ids)) == len(face_ids), "duplicate face ids"
    worst_gap = 0.0
    for e in doc.get("edges", []):
        if e["curve"] is not None:
            check_curve(e["curve"], 3, f"edge {e['id']}")
        assert set(e["faces"]) <= set(face_ids), f"edge {e['id']}: unknown face"
    for f in doc["faces"]:
        where = f"face {f['id']}"
        check_surface(f["surface"], where)
        u0, u1, v0, v1 = f["bounds"]
        assert u1 >= u0 and v1 >= v0, f"{where}: bounds {f['bounds']}"
        size = math.hypot(u1 - u0, v1 - v0)
        assert size > 0, f"{where}: empty bounds"
        for li, loop in enumerate(f["loops"]):
            lw = f"{where} loop {li}"
            trims = loop["edges"]
            assert trims, f"{lw}: no trims"
            for ti, tr in enumerate(trims):
                tw = f"{lw} trim {ti}"
                check_curve(tr["curve"], 2, tw)
                if tr.get("edge") is not None:
                    assert tr["edge"] in edge_ids, f"{tw}: edge {tr['edge']} unknown"
                t0, t1 = tr["range"]
                c = tr["curve"]
                if c["type"] == "bspline" and not c["periodic"]:
                    lo, hi = c["knots"][0], c["knots"][-1]
                    assert lo <= min(t0, t1) and max(t0, t1) <= hi, f"{tw}: range {tr['range']} outside knots [{lo}, {hi}]"
                for k in range(TRIM_SAMPLES + 1):
                    u, v = ev.curve(c, t0 + (t1 - t0) * k / TRIM_SAMPLES)
                    tol = 1e-9 * size
                    assert u0 - tol <= u <= u1 + tol and v0 - tol <= v <= v1 + tol, \
                        f"{tw}: ({u}, {v}) outside bounds {f['bounds']}"
            for ti, tr in enumerate(trims):
                nxt = trims[(ti + 1) % len(trims)]
                a = ev.curve(tr["curve"], tr["range"][1])
                b = ev.curve(nxt["curve"], nxt["range"][0])
                gap = dist(a, b) / size
                worst_gap = max(worst_gap, gap)
                assert gap <= 1e-7, f"{lw}: gap {gap * size:.3g} ({gap:.3g} of the bounds) between trims {ti} and {(ti + 1) % len(trims)}"
            area = signed_area(ev, loop)
            if li == 0:
                assert area > 0, f"{lw}: outer loop clockwise (area {area})"
            else:
                assert area < 0, f"{lw}: hole counter-clockwise (area {area})"
    return {"worst_gap": worst_gap}


# ------------------------------------------------------------------------------------------
# against OCP


def shape_size(shape: Any) -> float:
    box = Bnd_Box()
    _s(BRepBndLib, "Add")(shape, box)
    lo, hi = box.CornerMin(), box.CornerMax()  # (OCP 8.0 cannot return Get()'s Bnd_Box::Limits)
    return dist(_pt(lo), _pt(hi))


def ocp_maps(shape: Any) -> Tuple[Any, Any]:
    faces = TopTools_IndexedMapOfShape()
    _s(TopExp, "MapShapes")(shape, TopAbs_FACE, faces)
    edges = TopTools_IndexedMapOfShape()
    for i in range(1, faces.Extent() + 1):
        _s(TopExp, "MapShapes")(faces.FindKey(i), TopAbs_EDGE, edges)
    return faces, edges


_face = _s(TopoDS, "Face")
_edge = _s(TopoDS, "Edge")


def compare_with_ocp(doc: Dict[str, Any], shape: Any, ev: Evaluator, seed: int = 1) -> Dict[str, float]:
    """Surfaces and trims of the document against OCP's evaluation of `shape`. Returns the worst
    deviations relative to the part size."""
    rng = random.Random(seed)
    size = shape_size(shape)
    fmap, emap = ocp_maps(shape)
    assert len(doc["faces"]) == fmap.Extent(), f"{len(doc['faces'])} faces exported, OCP has {fmap.Extent()}"
    stats = {"surface": 0.0, "trim_at_t": 0.0, "trim_projected": 0.0, "trim_vs_tol": 0.0,
             "converted_faces": 0, "mirrored_faces": 0, "bridges": 0, "pcurve": 0.0}
    edge_adaptors: Dict[int, Any] = {}
    for f in doc["faces"]:
        where = f"face {f['id']}"
        face = _face(fmap.FindKey(f["id"]))
        ad = BRepAdaptor_Surface(face, False)
        ty = ad.GetType()
        s = f["surface"]
        mirrored = False
        if ty in (GeomAbs_Cylinder, GeomAbs_Cone, GeomAbs_Sphere, GeomAbs_Torus):
            pos = {GeomAbs_Cylinder: ad.Cylinder, GeomAbs_Cone: ad.Cone, GeomAbs_Sphere: ad.Sphere,
                   GeomAbs_Torus: ad.Torus}[ty]().Position()
            mirrored = not pos.Direct()
        stats["mirrored_faces"] += mirrored
        # A face exported with its own parametrisation: same family as OCP's.
        converted = s["type"] == "bspline" and ty not in (GeomAbs_BSplineSurface, GeomAbs_BezierSurface)
        stats["converted_faces"] += converted
        u0, u1, v0, v1 = f["bounds"]
        bsize = math.hypot(u1 - u0, v1 - v0)
        geom = _s(BRep_Tool, "Surface")(face)
        for _ in range(12):
            u, v = u0 + (u1 - u0) * rng.random(), v0 + (v1 - v0) * rng.random()
            p = ev.surface(s, u, v)
            if converted:
                proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*p), geom)
                d = proj.LowerDistance() if proj.NbPoints() else float("inf")
            else:
                q = ad.Value(TWO_PI - u if mirrored else u, v)
                d = dist(p, [q.X(), q.Y(), q.Z()])
            stats["surface"] = max(stats["surface"], d / size)
            assert d <= 1e-6 * size, f"{where} ({s['type']}{', mirrored' if mirrored else ''}" \
                f"{', converted' if converted else ''}): S({u}, {v}) off OCP's surface by {d:.3g}"
        for li, loop in enumerate(f["loops"]):
            for ti, tr in enumerate(loop["edges"]):
                tw = f"{where} loop {li} trim {ti}"
                eid = tr.get("edge")
                if eid is None:
                    # the exporter's bridge across a gap between two pcurves: a short line
                    # whose 3D extent stays within the face's vertex tolerance
                    assert tr["curve"]["type"] == "line", f"{tw}: no edge id"
                    a = ev.surface(s, *ev.curve(tr["curve"], tr["range"][0]))
                    b = ev.surface(s, *ev.curve(tr["curve"], tr["range"][1]))
                    vtol = _vertex_tolerance(face)
                    assert dist(a, b) <= max(1e-6 * size, 2.001 * vtol), \
                        f"{tw}: bridge of {dist(a, b):.3g} in 3D (vertex tolerance {vtol:.3g})"
                    stats["bridges"] += 1
                    continue
                edge = _edge(emap.FindKey(eid))
                if _s(BRep_Tool, "Degenerated")(edge):
                    continue
                if eid not in edge_adaptors:
                    edge_adaptors[eid] = (BRepAdaptor_Curve(edge), _s(BRep_Tool, "Range")(edge),
                                          _s(BRep_Tool, "Tolerance")(edge), _s(BRep_Tool, "Curve")(edge, 0.0, 0.0))
                ca, (e0, e1), etol, c3d = edge_adaptors[eid]
                if not converted:
                    # the exported pcurve is OCP's (mirrored where the frame is): at the same t
                    d2 = _pcurve_deviation(ev, tr, edge, face, mirrored)
                    stats["pcurve"] = max(stats["pcurve"], d2 / bsize)
                    assert d2 <= 1e-9 * bsize + 1e-8, f"{tw} (edge {eid}): pcurve off OCP's by {d2:.3g}"
                t0, t1 = tr["range"]
                same_param = abs(min(t0, t1) - e0) <= 1e-9 * (1 + abs(e0)) and \
                    abs(max(t0, t1) - e1) <= 1e-9 * (1 + abs(e1))
                tol = max(1e-6 * size, 1.001 * etol)
                for k in range(TRIM_SAMPLES + 1):
                    t = t0 + (t1 - t0) * k / TRIM_SAMPLES
                    u, v = ev.curve(tr["curve"], t)
                    p = ev.surface(s, u, v)
                    if same_param:
                        q = ca.Value(t)
                        d = dist(p, [q.X(), q.Y(), q.Z()])
                        stats["trim_at_t"] = max(stats["trim_at_t"], d / size)
                    else:
                        proj = GeomAPI_ProjectPointOnCurve(gp_Pnt(*p), c3d, e0, e1)
                        d = proj.LowerDistance() if proj.NbPoints() else min(
                            dist(p, _pt(ca.Value(e0))), dist(p, _pt(ca.Value(e1))))
                        stats["trim_projected"] = max(stats["trim_projected"], d / size)
                    stats["trim_vs_tol"] = max(stats["trim_vs_tol"], d / tol)
                    assert d <= tol, f"{tw} (edge {eid}, t={t}): S(C(t)) is {d:.3g} from the edge " \
                        f"(allowed {tol:.3g}: max(1e-6 × size, edge tolerance {etol:.3g}))"
    stats["vertex_gap"] = check_tolerances(doc, emap, ev, size)
    return stats


def check_tolerances(doc: Dict[str, Any], emap: Any, ev: Evaluator, size: float) -> float:
    """Every edge's `tolerance` is OCP's `BRep_Tool::Tolerance` of it, its `vertex_tolerances`
    those of the vertices at range[0] and range[1]: OCP's vertex points lie within them of the
    document's curve at those ends (which end is which is checked on the geometry, not by
    asking OCP the same question twice). Returns the largest end-to-vertex distance relative to
    its vertex tolerance."""
    worst = 0.0
    for e in doc.get("edges", []):
        where = f"edge {e['id']}"
        edge = _edge(emap.FindKey(e["id"]))
        assert e["tolerance"] == _s(BRep_Tool, "Tolerance")(edge), f"{where}: tolerance {e['tolerance']}"
        vt = e["vertex_tolerances"]
        assert len(vt) == 2 and min(vt) >= 0, f"{where}: vertex_tolerances {vt}"
        v = [_s(TopExp, "FirstVertex")(edge, False), _s(TopExp, "LastVertex")(edge, False)]
        assert sorted(vt) == sorted(_s(BRep_Tool, "Tolerance")(x) for x in v), f"{where}: {vt}"
        if e["curve"] is None:
            continue
        ends = [ev.curve(e["curve"], t) for t in e["range"]]
        for k in range(2):
            # the vertex that the document puts at this end, and the other one
            mine = _pt(_s(BRep_Tool, "Pnt")(v[k]))
            d = dist(ends[k], mine)
            worst = max(worst, d / max(vt[k], 1e-300))
            assert d <= vt[k] + 1e-9 * size, \
                f"{where}: the vertex of range[{k}] is {d:.3g} from the curve's end (tolerance {vt[k]:.3g})"
            if dist(_pt(_s(BRep_Tool, "Pnt")(v[0])), _pt(_s(BRep_Tool, "Pnt")(v[1]))) > vt[0] + vt[1]:
                other = _pt(_s(BRep_Tool, "Pnt")(v[1 - k]))
                assert dist(ends[k], other) > vt[1 - k], f"{where}: vertex_tolerances swapped"
    return worst


def _pt(p: Any) -> List[float]:
    return [p.X(), p.Y(), p.Z()]


def _vertex_tolerance(face: Any) -> float:
    from OCP.TopAbs import TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer

    tol = 0.0
    exp = TopExp_Explorer(face, TopAbs_VERTEX)
    while exp.More():
        tol = max(tol, _s(BRep_Tool, "Tolerance")(_s(TopoDS, "Vertex")(exp.Current())))
        exp.Next()
    return tol


def _pcurve_deviation(ev: Evaluator, tr: Dict[str, Any], edge: Any, face: Any, mirrored: bool) -> float:
    """max over samples of |C(t) - OCP's pcurve(t)| (u mirrored to 2π - u where the exporter
    mirrors); a seam edge has two pcurves on the face: the nearer one."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d
    from OCP.TopAbs import TopAbs_FORWARD, TopAbs_REVERSED

    t0, t1 = tr["range"]
    best = float("inf")
    for ori in (TopAbs_FORWARD, TopAbs_REVERSED):
        pc = BRepAdaptor_Curve2d(_edge(edge.Oriented(ori)), _face(face.Oriented(TopAbs_FORWARD)))
        worst = 0.0
        for k in range(TRIM_SAMPLES + 1):
            t = t0 + (t1 - t0) * k / TRIM_SAMPLES
            u, v = ev.curve(tr["curve"], t)
            q = pc.Value(t)
            worst = max(worst, math.hypot((TWO_PI - u if mirrored else u) - q.X(), v - q.Y()))
        best = min(best, worst)
    return best
