"""The FreeCAD walk: a `Part.Shape` → a `tessd-brep` v1 document (docs/brep-format.md), through
FreeCAD's own Part API, so that a FreeCAD macro or add-on exports without OCP. FreeCAD's Part is
OpenCASCADE underneath, and this walk mirrors ocp.py's step for step (the loops' assembly is
shared: document.py): the same shape gives the same document, up to the OCCT versions' rounding.

Written against FreeCAD 0.20 (Debian's `libfreecad-python3-0.20`, OCCT 7.6: the system Python
with /usr/lib/freecad-python3/lib on sys.path). FreeCAD's length unit is the millimetre.

How FreeCAD's Part API maps onto ocp.py's walk:
- faces are `shape.Faces` (TopExp::MapShapes order, ocp.py's face ids); edge ids follow each
  face's `Edges` in that order, one id per `isSame` edge (ocp.py's edge map, so the ids agree);
- each face is walked on a wrapper whose `Orientation` is set to Forward (its sub-shapes stay
  `isSame` with the shape's); `reversed` is the face's own orientation;
- a wire's edges come in connection order from `OrderedEdges` (BRepTools_WireExplorer, without
  the face: ocp.py gives it the face) and are re-chained in (u, v) where that order does not close
  there; pcurves from `face.curveOnSurface(edge)` (the seam's two by the edge's orientation);
- `face.Surface` has the location applied, as OCP's adaptor. Frames: X and Y from the surface's
  v-iso circle or line (exact, unlike its `Rotation`); a cylinder / cone / sphere / torus whose
  iso circle's axis (its gp_Ax2's) is against the surface's axis has an indirect (left-handed)
  gp_Ax3 and is mirrored as in ocp.py ((X, -Y), u → 2π - u);
- a surface without a format type (offset, ...) goes through `face.toNurbs()`
  (BRepBuilderAPI_NurbsConvert); its edges are matched with the original ones in explorer order
  (the edges keep their original 3D curves, as in ocp.py);
- edges carry `tolerance` (`edge.Tolerance`) and `vertex_tolerances` (`firstVertex(False)` /
  `lastVertex(False)`: the vertices at range[0] and range[1]), scaled to `units`.

Sewing is ocp.py's (`tessd.brep.export_shape` refuses `sew=True` for FreeCAD shapes): a FreeCAD
shape is exported as it is (`Part.Shape.sewShape` sews one in FreeCAD).
"""

from __future__ import annotations

import math
import os
import sys
from typing import Any, Dict, List, Optional, Tuple

from .document import (
    ExportError,
    Trim,
    check_units,
    edge_json,
    face_json,
    knot_span_range,
    new_document,
    note_edge_face,
    outer_first,
    same_parameter,
)

# Where Debian's freecad packages put FreeCAD's Python modules (FreeCAD.so, Part.so).
FREECAD_LIB = "/usr/lib/freecad-python3/lib"
# As ocp.py: curves without a same-parameter B-spline (hyperbolas, offsets) are approximated on
# their own parameter to this tolerance (absolute, the curve's units).
_APPROX_TOL = 1e-9
# A wire's order from OrderedEdges is kept where consecutive pcurves meet within this share of
# the face's parameter range (the gap bridges handle what is left); else it is re-chained.
_CHAIN_GAP = 1e-4


def _freecad() -> Tuple[Any, Any]:
    """FreeCAD's `FreeCAD` and `Part` modules (from $FREECAD_LIB or FREECAD_LIB where they are
    not on sys.path: outside FreeCAD's own Python)."""
    try:
        import FreeCAD
        import Part
    except ImportError:
        lib = os.environ.get("FREECAD_LIB", FREECAD_LIB)
        if lib not in sys.path:
            sys.path.append(lib)
        import FreeCAD  # the application first: Part needs it
        import Part
    return FreeCAD, Part


FreeCAD, Part = _freecad()
_V2 = FreeCAD.Base.Vector2d
_G2 = Part.Geom2d


# --------------------------------------------------------------------------------------------
# curves


def _xyz(v: Any) -> List[float]:
    return [v.x, v.y, v.z]


def _pt(v: Any) -> List[float]:
    return [v.x, v.y, v.z] if hasattr(v, "z") else [v.x, v.y]


_LINES = (Part.Line, _G2.Line2d)
_SEGMENTS = (Part.LineSegment, _G2.Line2dSegment)
_CIRCLES = (Part.Circle, _G2.Circle2d)
_ELLIPSES = (Part.Ellipse, _G2.Ellipse2d)
_BSPLINES = (Part.BSplineCurve, _G2.BSplineCurve2d)
_BEZIERS = (Part.BezierCurve, _G2.BezierCurve2d)
_ARCS = {  # trimmed conics: the attribute holding the basis
    Part.ArcOfCircle: "Circle", Part.ArcOfEllipse: "Ellipse", Part.ArcOfHyperbola: "Hyperbola",
    Part.ArcOfParabola: "Parabola", _G2.ArcOfCircle2d: "Circle", _G2.ArcOfEllipse2d: "Ellipse",
    _G2.ArcOfHyperbola2d: "Hyperbola", _G2.ArcOfParabola2d: "Parabola",
}
# A conic without a format type → its trimmed arc (which FreeCAD can approximate).
_ARC_OF = {
    Part.Hyperbola: Part.ArcOfHyperbola, Part.Parabola: Part.ArcOfParabola,
    _G2.Hyperbola2d: _G2.ArcOfHyperbola2d, _G2.Parabola2d: _G2.ArcOfParabola2d,
}


def _curve_json(c: Any) -> Dict[str, Any]:
    """A line (segment) / circle / ellipse / B-spline (2D or 3D) as CURVE2D / CURVE3D."""
    if isinstance(c, _LINES):
        return {"type": "line", "origin": _pt(c.Location), "dir": _pt(c.Direction)}
    if isinstance(c, _SEGMENTS):
        # no access to the trimmed line itself: its point at 0 is the line's origin exactly
        return {"type": "line", "origin": _pt(c.value(0.0)), "dir": _pt(_tangent(c))}
    if isinstance(c, _CIRCLES):
        return {"type": "circle", "center": _pt(c.Location), "x_dir": _pt(c.XAxis),
                "y_dir": _pt(c.YAxis), "radius": c.Radius}
    if isinstance(c, _ELLIPSES):
        return {"type": "ellipse", "center": _pt(c.Location), "x_dir": _pt(c.XAxis),
                "y_dir": _pt(c.YAxis), "major_radius": c.MajorRadius, "minor_radius": c.MinorRadius}
    if isinstance(c, _BSPLINES):
        return {
            "type": "bspline",
            "degree": c.Degree,
            "poles": [_pt(p) for p in c.getPoles()],
            "weights": list(c.getWeights()) if c.isRational() else None,
            "knots": list(c.getKnots()),
            "mults": list(c.getMultiplicities()),
            "periodic": bool(c.isPeriodic()),
        }
    raise TypeError(f"not a format curve: {type(c).__name__}")


def _tangent(c: Any) -> Any:
    t = c.tangent(c.FirstParameter)
    return t[0] if isinstance(t, tuple) else t


def _exact_curve(c: Any) -> Optional[Any]:
    """The curve as a format type with the *same* parametrisation, or None if it has none
    (arcs are unwrapped, line segments kept; Béziers become the identical B-spline)."""
    basis = _ARCS.get(type(c))
    if basis is not None:
        c = getattr(c, basis)
    if isinstance(c, _LINES + _SEGMENTS + _CIRCLES + _ELLIPSES + _BSPLINES):
        return c
    if isinstance(c, _BEZIERS):
        return c.toBSpline()
    return None


def _curve_on_range(c: Any, t0: float, t1: float) -> Tuple[Any, float, float]:
    """(curve, t0, t1) of a format type for `c` on [t0, t1] (t0 < t1), as ocp.py's: the same
    curve and range where it has an exact format type, else a B-spline (same parameter where
    one exists: parabolas exactly, hyperbolas approximated; else its own parameter)."""
    exact = _exact_curve(c)
    if exact is not None:
        if isinstance(exact, _BSPLINES):
            span = knot_span_range(t0, t1, exact.FirstParameter, exact.LastParameter,
                                   exact.isPeriodic())
            if span is not None:
                return exact, span[0], span[1]
            seg = exact.copy()  # a periodic trim over the knot span: its non-periodic segment
            seg.segment(t0, t1)
            return seg, seg.FirstParameter, seg.LastParameter
        return exact, t0, t1
    basis = _ARCS.get(type(c))
    if basis is not None:
        c = getattr(c, basis)
    try:
        bs = c.toBSpline(t0, t1)
    except Exception:  # FreeCAD's converter refuses some curves
        bs = None
    if bs is not None and _same_parameter(c, bs, t0, t1):
        return bs, t0, t1  # exact and same parameter (parabolas, offsets of lines...)
    arc = _ARC_OF.get(type(c))
    if arc is not None:  # hyperbolas: approximated on the same parameter, as ocp.py does
        try:
            a = arc(c, t0, t1).approximateBSpline(_APPROX_TOL, 200, 9, "C2")
        except Exception:
            a = None
        if a is not None and _same_parameter(c, a, t0, t1, tol=10 * _APPROX_TOL):
            return a, a.FirstParameter, a.LastParameter
    if bs is None:
        raise ExportError(f"no B-spline for a {type(c).__name__} on [{t0}, {t1}]")
    return bs, bs.FirstParameter, bs.LastParameter  # exact, another parameter


def _same_parameter(c: Any, bs: Any, t0: float, t1: float, tol: float = 1e-12) -> bool:
    return same_parameter(lambda t: _pt(c.value(t)), lambda t: _pt(bs.value(t)), t0, t1,
                          (bs.FirstParameter, bs.LastParameter), tol)


class _Pcurve:
    """A FreeCAD 2D curve as document.Trim wants it."""

    __slots__ = ("c", "_json")

    def __init__(self, c: Any) -> None:
        self.c, self._json = c, _curve_json(c)

    def uv(self, t: float) -> Tuple[float, float]:
        p = self.c.value(t)
        return p.x, p.y

    def json(self) -> Dict[str, Any]:
        return self._json


# --------------------------------------------------------------------------------------------
# surfaces


def _frame(origin: Any, x: Any, y: Any) -> Dict[str, Any]:
    return {"origin": _xyz(origin), "x_dir": _xyz(x), "y_dir": _xyz(y)}


def _bspline_surface_json(s: Any) -> Dict[str, Any]:
    rational = s.isURational() or s.isVRational()
    return {
        "type": "bspline",
        "degree_u": s.UDegree,
        "degree_v": s.VDegree,
        "poles": [[_xyz(p) for p in row] for row in s.getPoles()],
        "weights": [list(row) for row in s.getWeights()] if rational else None,
        "knots_u": list(s.getUKnots()),
        "mults_u": list(s.getUMultiplicities()),
        "knots_v": list(s.getVKnots()),
        "mults_v": list(s.getVMultiplicities()),
        "periodic_u": bool(s.isUPeriodic()),
        "periodic_v": bool(s.isVPeriodic()),
    }


def _surface(face: Any) -> Tuple[Optional[Dict[str, Any]], bool]:
    """(SURFACE, mirror_u) for a forward face, or (None, False) when it needs toNurbs."""
    try:
        s = face.Surface  # location applied
    except Exception:  # "undefined surface type" (GeomAbs_OtherSurface: plate, ...)
        return None, False
    if isinstance(s, Part.Plane):
        # any handedness: S = O + uX + vY as stored (the iso lines carry X and Y exactly)
        return dict(type="plane", **_frame(s.Position, s.vIso(0.0).Direction,
                                           s.uIso(0.0).Direction)), False
    if isinstance(s, (Part.Cylinder, Part.Cone, Part.Sphere, Part.Toroid)):
        if isinstance(s, Part.Cylinder):
            extra: Dict[str, Any] = {"type": "cylinder", "radius": s.Radius}
        elif isinstance(s, Part.Cone):
            extra = {"type": "cone", "radius": s.Radius, "semi_angle": s.SemiAngle}
        elif isinstance(s, Part.Sphere):
            extra = {"type": "sphere", "radius": s.Radius}
        else:
            extra = {"type": "torus", "major_radius": s.MajorRadius, "minor_radius": s.MinorRadius}
        # The circle v = 0 lies in the frame's gp_Ax2 (X, the stored Y, and the axis turned
        # round where the gp_Ax3 is indirect): X and Y exactly as stored, and the handedness.
        iso = s.vIso(0.0)
        x, y = iso.XAxis, iso.YAxis
        mirror = iso.Axis.dot(s.Axis) < 0
        if mirror:  # the axis is -(X × Y): use (X, -Y) and u → 2π - u
            y = -y
        origin = s.Center
        return {"type": extra.pop("type"), **_frame(origin, x, y), **extra}, mirror
    while isinstance(s, Part.RectangularTrimmedSurface):
        s = s.BasisSurface
    if isinstance(s, Part.BSplineSurface):
        return _bspline_surface_json(s), False
    if isinstance(s, Part.BezierSurface):
        return _bspline_surface_json(s.toBSpline()), False
    if isinstance(s, Part.SurfaceOfRevolution):
        c = _exact_curve(s.BasisCurve)
        if c is not None:
            return {"type": "revolution", "axis_origin": _xyz(s.Location),
                    "axis_dir": _xyz(s.Direction), "curve": _curve_json(c)}, False
    if isinstance(s, Part.SurfaceOfExtrusion):
        c = _exact_curve(s.BasisCurve)
        if c is not None:
            return {"type": "extrusion", "direction": _xyz(s.Direction), "curve": _curve_json(c)}, False
    return None, False


# --------------------------------------------------------------------------------------------
# loops

_MIRROR_POINT = _V2(math.pi, 0.0)
_MIRROR_DIR = _V2(0.0, 1.0)
_NOT_BOUNDARY = ("Internal", "External")


def _trim(edge: Any, face: Any, mirror: bool, edge_id: Optional[int], where: str) -> Trim:
    got = face.curveOnSurface(edge)  # (2D curve, first, last); the seam's by orientation
    if not got:
        raise ExportError(f"{where}: edge {edge_id} has no pcurve on the face")
    c, first, last = got
    c, first, last = _curve_on_range(c, first, last)
    if mirror:
        c = c.copy()
        c.mirror(_MIRROR_POINT, _MIRROR_DIR)  # same kind, same parameter; u → 2π - u
    if edge.Orientation == "Reversed":
        first, last = last, first
    return Trim(_Pcurve(c), first, last, edge_id)


def _gap(a: Trim, b: Trim) -> float:
    p, q = a.curve.uv(a.t1), b.curve.uv(b.t0)
    return math.hypot(q[0] - p[0], q[1] - p[1])


def _chained(trims: List[Trim], size: float) -> List[Trim]:
    """The trims in connection order: as given where consecutive ones meet in (u, v), else
    chained from the first by the nearest start (a wire whose 3D order is ambiguous)."""
    n = len(trims)
    if n < 2 or all(_gap(trims[i], trims[(i + 1) % n]) <= _CHAIN_GAP * size for i in range(n)):
        return trims
    rest, out = trims[1:], [trims[0]]
    while rest:
        k = min(range(len(rest)), key=lambda i: _gap(out[-1], rest[i]))
        out.append(rest.pop(k))
    return out


def _wire_edges(wire: Any) -> List[Any]:
    """The wire's boundary edges (INTERNAL / EXTERNAL ones are no boundary) with their
    orientation in the face, in the explorer's order (OrderedEdges) where it chains them all,
    else as stored."""
    stored = [e for e in wire.childShapes() if e.Orientation not in _NOT_BOUNDARY]
    chained = [e for e in wire.OrderedEdges if e.Orientation not in _NOT_BOUNDARY]
    return chained if len(chained) == len(stored) else stored


class _EdgeIds:
    """Edge ids by topology: 1, 2, ... in the order met, one per `isSame` class."""

    def __init__(self) -> None:
        self.buckets: Dict[int, List[Tuple[Any, int]]] = {}
        self.edges: List[Any] = []

    def add(self, e: Any) -> int:
        found = self.find(e)
        if found is not None:
            return found
        self.edges.append(e)
        self.buckets.setdefault(e.hashCode(), []).append((e, len(self.edges)))
        return len(self.edges)

    def find(self, e: Any) -> Optional[int]:
        for other, i in self.buckets.get(e.hashCode(), ()):
            if other.isSame(e):
                return i
        return None


def _explored_edges(face: Any) -> List[Any]:
    return [e for w in face.Wires for e in w.childShapes()]


def _export_face(face: Any, fid: int, ids: _EdgeIds, edge_faces: Dict[int, List[int]]) -> Dict[str, Any]:
    where = f"face {fid}"
    reversed_ = face.Orientation == "Reversed"
    face.Orientation = "Forward"  # this wrapper only: the shape's face is untouched
    surf, mirror = _surface(face)

    work = face
    renamed: Optional[List[Tuple[Any, int]]] = None  # edge of `work` → edge id
    if surf is None:  # no exact format type: the face's NURBS conversion (pcurves included)
        converted = face.toNurbs()
        work = converted.Faces[0]
        work.Orientation = "Forward"
        old, new = _explored_edges(face), _explored_edges(work)
        if len(old) != len(new):
            raise ExportError(f"{where}: toNurbs changed the face's edges ({len(old)} → {len(new)})")
        renamed = [(n, ids.find(o)) for n, o in zip(new, old)]
        surf, mirror = _surface(work)
        if surf is None:
            raise ExportError(f"{where}: toNurbs gave no B-spline surface")

    def edge_id(e: Any) -> Optional[int]:
        if renamed is None:
            return ids.find(e)
        return next((i for n, i in renamed if n.isSame(e)), None)

    outer = work.OuterWire
    wires = outer_first(work.Wires, lambda w: not outer.isNull() and w.isSame(outer))

    u0, u1, v0, v1 = work.ParameterRange
    size = math.hypot(u1 - u0, v1 - v0) if all(map(math.isfinite, (u0, u1, v0, v1))) else math.inf
    wire_trims: List[List[Trim]] = []
    for li, w in enumerate(wires):
        trims = []
        for e in _wire_edges(w):
            eid = edge_id(e)
            trims.append(_trim(e, work, mirror, eid, f"{where} loop {li}"))
            note_edge_face(edge_faces, eid, fid)
        wire_trims.append(_chained(trims, size))
    return face_json(fid, reversed_, mirror, surf, wire_trims, (u0, u1, v0, v1), where)


def _export_edge(edge: Any, eid: int, faces: List[int], tolerances: Tuple[float, Optional[List[float]]]) -> Dict[str, Any]:
    first, last = edge.ParameterRange
    curve = None
    if not edge.Degenerated:
        try:
            c = edge.Curve  # location applied
        except Exception:  # "undefined curve type": no 3D curve (a curve on surface only)
            c = None
        if c is not None:
            c, first, last = _curve_on_range(c, first, last)
            curve = _curve_json(c)
    return edge_json(eid, curve, first, last, faces, tolerance=tolerances[0],
                     vertex_tolerances=tolerances[1])


def _tolerances(edge: Any, scale: float) -> Tuple[float, Optional[List[float]]]:
    """(the edge's tolerance, [its vertices' at range[0], range[1]]) × `scale`, as ocp.py
    writes them: `firstVertex(False)` is TopExp::FirstVertex without the edge's orientation,
    the vertex at the curve's first parameter."""
    try:
        v0, v1 = edge.firstVertex(False), edge.lastVertex(False)
        vertices: Optional[List[float]] = [v0.Tolerance * scale, v1.Tolerance * scale]
    except Exception:  # an edge without vertices (infinite)
        vertices = None
    return edge.Tolerance * scale, vertices


# --------------------------------------------------------------------------------------------
# the walk

_SCALE = {"mm": 1.0, "cm": 0.1, "m": 0.001, "in": 1.0 / 25.4}


def to_shape(obj: Any) -> Any:
    """A `Part.Shape` from itself or from a FreeCAD document object (its `.Shape`)."""
    if isinstance(obj, Part.Shape):
        return obj
    shape = getattr(obj, "Shape", None)
    if isinstance(shape, Part.Shape):
        return shape
    raise TypeError(f"not a FreeCAD Part.Shape: {type(obj).__name__}")


def export_shape(shape: Any, units: str = "mm", source: Optional[str] = None) -> Dict[str, Any]:
    """A `tessd-brep` v1 document (a dict ready for `json.dump`) from a FreeCAD `Part.Shape`
    (or a document object's shape). FreeCAD works in millimetres: another `units` scales the
    shape into that unit first."""
    check_units(units)
    shape = to_shape(shape)
    if shape.isNull():
        raise ExportError("empty shape (a null Part.Shape)")
    scale = _SCALE[units]
    # Tolerances are taken on the unscaled shape and scaled here: OCCT keeps every tolerance of
    # a scaled copy at 1e-7 or more, so the copy's are not the scaled ones. The same walk over
    # both shapes meets the same edges in the same order.
    tolerance_edges = _edge_ids(shape).edges
    if units != "mm":
        shape = shape.scaled(scale)
    shape_faces = shape.Faces
    ids = _edge_ids(shape)
    if len(ids.edges) != len(tolerance_edges):
        raise ExportError(f"scaling to {units} changed the shape's edges "
                          f"({len(tolerance_edges)} → {len(ids.edges)})")
    edge_faces: Dict[int, List[int]] = {}
    faces = [_export_face(f, fid, ids, edge_faces) for fid, f in enumerate(shape_faces, start=1)]
    edges = [_export_edge(e, eid, edge_faces.get(eid, []), _tolerances(t, scale))
             for eid, (e, t) in enumerate(zip(ids.edges, tolerance_edges), start=1)]
    return new_document(units, source, faces, edges)


def _edge_ids(shape: Any) -> _EdgeIds:
    """The shape's edges numbered as ocp.py numbers them (each face's edges in face order)."""
    ids = _EdgeIds()
    for f in shape.Faces:
        for e in f.Edges:
            ids.add(e)
    return ids


def read_file(path: str) -> Any:
    """A `Part.Shape` from a STEP (.step/.stp), IGES (.iges/.igs) or OpenCASCADE (.brep/.brp)
    file, read by FreeCAD (in millimetres)."""
    ext = os.path.splitext(path)[1].lower()
    if not os.path.isfile(path):
        raise FileNotFoundError(path)
    if ext not in (".step", ".stp", ".iges", ".igs", ".brep", ".brp"):
        raise ExportError(f"{path}: unknown extension {ext!r} (expected .step/.stp, .iges/.igs, .brep/.brp)")
    shape = Part.Shape()
    try:
        shape.read(path)
    except Exception as e:  # Part.OCCError
        raise ExportError(f"{path}: not readable by FreeCAD: {e}") from e
    if shape.isNull():
        raise ExportError(f"{path}: no shape in the file")
    return shape


def export_file(path: str, units: str = "mm", source: Optional[str] = None) -> Dict[str, Any]:
    """The document for a STEP / IGES / .brep file read by FreeCAD."""
    return export_shape(read_file(path), units=units,
                        source=os.path.basename(path) if source is None else source)


__all__ = ["ExportError", "export_shape", "export_file", "read_file", "to_shape"]
