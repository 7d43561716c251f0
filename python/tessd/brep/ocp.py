"""The OCP (OpenCASCADE) walk: a `TopoDS_Shape` → a `tessd-brep` v1 document (docs/brep-format.md).

Runs on cadquery-ocp 7.9 (cadquery 2.8) and on OCP 8.0 (build123d 0.13) alike: the names that
8.0 moved or respelled (`TopTools_IndexedMapOfShape`, now in `OCP.collections`; the `TopoDS`
casts, `TopoDS.Face_s` → `TopoDS.Face`) are resolved in ocp_compat.py, the one place that knows
both. Nothing here uses `BRepTopAdaptor_FClass2d` (dropped in 8.0).

How the OCP model maps onto the format:
- faces are numbered by `TopExp::MapShapes(shape, FACE)` (1-based, FreeCAD's "FaceN"), edges by
  one map over the faces' edges (so `edges` lists only edges that bound a face);
- each face is walked as `face.Oriented(FORWARD)`: its loops then come out in the normalised
  orientation (outer counter-clockwise, holes clockwise) and `reversed` is the face's own
  orientation;
- plane / cylinder / cone / sphere / torus / revolution / extrusion / B-spline surfaces are
  written as they are; a Bézier surface (or curve) becomes the identical B-spline; anything else
  (offset surfaces, revolution/extrusion of an offset curve, ...) goes through
  `BRepBuilderAPI_NurbsConvert`, which re-computes the pcurves for the converted surface;
- a cylinder / cone / sphere / torus on an *indirect* (left-handed) `gp_Ax3` (common in STEP and
  mirrored parts) cannot be written with the format's right-handed frame and OCP's (u, v): for it
  the frame is (X, -Y) (right-handed, z = the axis) and u becomes 2π - u, i.e. every pcurve is
  mirrored about u = π (exact: lines, circles, ellipses and B-splines mirror into their own kind
  with the same parameter), its loops are re-reversed and `reversed` flips (the mirrored
  parametrisation has the opposite ∂S/∂u × ∂S/∂v). S(2π - u, v) is then OCP's S(u, v) exactly.

Faces converted to NURBS keep the edge ids and 3D curves of the original shape: the trims of a
converted face are the converted face's own (NurbsConvert re-computes every pcurve for the new
surface, on the converted edge's parameter), and each trim names the original edge it came from
(`ModifiedShape`). The converted face's edges' 3D curves are not exported: an edge shared with an
unconverted neighbour must keep one 3D curve in `edges`, and the original one is exact (a line or
a circle stays one), whereas NurbsConvert's B-spline copy of it is in another parameter (a
circle's rational B-spline does not run at constant speed). So a converted face's trim and its
edge may not be "same parameter" (the trim's t is the converted edge's, the edge's range the
original's): the reader must not assume they are, and decides it by sampling (docs/brep-format.md,
Edge). The neighbours' trims and the edge stay same parameter as OCP made them.

Edges carry OCP's tolerances (`BRep_Tool::Tolerance`, in the shape's units, which are the
document's): `tolerance` the edge's, `vertex_tolerances` its vertices' at `range[0]` and
`range[1]` (`TopExp::FirstVertex / LastVertex` of the edge without its orientation: the FORWARD
vertex sits at the curve's first parameter, which is `range[0]`). A reader merges what lies
within them (edges' ends at a vertex: real files' curves miss their vertices by up to these).

Sewing (`prepare`): IGES surface models, and STEP files written as loose faces or open shells,
arrive unsewn: every face has its own copy of each boundary edge, so every face boundary would be
discretised per face and crack. `export_topods(shape, sew=None)` sews
(`BRepBuilderAPI_Sewing`) when the shape has free edges (an edge bounding one face only, seams and
degenerate edges aside), not when it is closed; `sew=True / False` forces it. Face ids stay the
input's (each sewn face is matched to its original with `ModifiedSubShape`), so `face 17` is still the
file's 17th face; edge ids are the sewn shape's. When sewing joins nothing (an open shell that is
simply open, a single face) the input is exported as it is. The document's `sewing` object says
what was done (`tolerance`, `free_edges_before`, `free_edges_after`, `sewn_edges`, `faces`); see
`default_sew_tolerance` for the tolerance.

What needs no OCP (the loops' assembly from the trims, bounds, gap bridges, the document) is in
document.py, shared with freecad.py (FreeCAD's Part API: the same walk, the same document).
"""

from __future__ import annotations

import math
import os
from typing import Any, Dict, List, NamedTuple, Optional, Sequence, Tuple

from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert, BRepBuilderAPI_Sewing
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.Geom import (
    Geom_BezierCurve,
    Geom_BezierSurface,
    Geom_BSplineCurve,
    Geom_BSplineSurface,
    Geom_Circle,
    Geom_Ellipse,
    Geom_Line,
    Geom_RectangularTrimmedSurface,
    Geom_SurfaceOfLinearExtrusion,
    Geom_SurfaceOfRevolution,
    Geom_TrimmedCurve,
)
from OCP.Geom2d import (
    Geom2d_BezierCurve,
    Geom2d_BSplineCurve,
    Geom2d_Circle,
    Geom2d_Ellipse,
    Geom2d_Line,
    Geom2d_TrimmedCurve,
)
from OCP.Geom2dConvert import Geom2dConvert, Geom2dConvert_ApproxCurve
from OCP.GeomAbs import (
    GeomAbs_C2,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_Torus,
)
from OCP.GeomConvert import GeomConvert, GeomConvert_ApproxCurve
from OCP.gp import gp_Ax2d, gp_Dir2d, gp_Pnt2d
from OCP.TopAbs import (
    TopAbs_EDGE,
    TopAbs_EXTERNAL,
    TopAbs_FACE,
    TopAbs_FORWARD,
    TopAbs_INTERNAL,
    TopAbs_REVERSED,
    TopAbs_VERTEX,
    TopAbs_WIRE,
)
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Compound, TopoDS_Shape

from .document import (  # FORMAT, VERSION, UNITS, ExportError: also this module's names
    FORMAT,  # noqa: F401
    UNITS,  # noqa: F401
    VERSION,  # noqa: F401
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
from .ocp_compat import TopTools_IndexedMapOfShape
from .ocp_compat import static as _static

# The mirror that turns OCP's u into 2π - u (the axis u = π).
_MIRROR_U = gp_Ax2d(gp_Pnt2d(math.pi, 0.0), gp_Dir2d(0.0, 1.0))
# Approximation tolerance (absolute, in the curve's units) for curves whose exact B-spline would
# change the parameter (hyperbolas) or that have none (offset curves): they are approximated on
# their own parameter instead.
_APPROX_TOL = 1e-9


_face = _static(TopoDS, "Face")
_edge = _static(TopoDS, "Edge")
_wire = _static(TopoDS, "Wire")
_map_shapes = _static(TopExp, "MapShapes")
_surface_of = _static(BRep_Tool, "Surface")
_curve_of = _static(BRep_Tool, "Curve")
_pcurve_of = _static(BRep_Tool, "CurveOnSurface")
_range_of = _static(BRep_Tool, "Range")
_degenerated = _static(BRep_Tool, "Degenerated")
_tolerance = _static(BRep_Tool, "Tolerance")
_first_vertex = _static(TopExp, "FirstVertex")
_last_vertex = _static(TopExp, "LastVertex")
_vertex = _static(TopoDS, "Vertex")
_add_to_box = _static(BRepBndLib, "Add")
_uv_bounds = _static(BRepTools, "UVBounds")
_outer_wire = _static(BRepTools, "OuterWire")
_curve2d_to_bspline = _static(Geom2dConvert, "CurveToBSplineCurve")
_curve_to_bspline = _static(GeomConvert, "CurveToBSplineCurve")
_surface_to_bspline = _static(GeomConvert, "SurfaceToBSplineSurface")


# --------------------------------------------------------------------------------------------
# small conversions


def _xyz(p: Any) -> List[float]:
    return [p.X(), p.Y(), p.Z()]


def _xy(p: Any) -> List[float]:
    return [p.X(), p.Y()]


def _neg(v: Sequence[float]) -> List[float]:
    return [-x for x in v]


def _bspline_curve_json(c: Any, dim: int) -> Dict[str, Any]:
    pt = _xyz if dim == 3 else _xy
    n = c.NbPoles()
    rational = c.IsRational()
    return {
        "type": "bspline",
        "degree": c.Degree(),
        "poles": [pt(c.Pole(i)) for i in range(1, n + 1)],
        "weights": [c.Weight(i) for i in range(1, n + 1)] if rational else None,
        "knots": [c.Knot(i) for i in range(1, c.NbKnots() + 1)],
        "mults": [c.Multiplicity(i) for i in range(1, c.NbKnots() + 1)],
        "periodic": bool(c.IsPeriodic()),
    }


def _curve_json(c: Any, dim: int) -> Dict[str, Any]:
    """A line / circle / ellipse / B-spline (2D or 3D) as CURVE2D / CURVE3D."""
    pt = _xyz if dim == 3 else _xy
    if isinstance(c, (Geom_Line, Geom2d_Line)):
        ax = c.Position()  # gp_Ax1 / gp_Ax2d
        return {"type": "line", "origin": pt(ax.Location()), "dir": pt(ax.Direction())}
    if isinstance(c, (Geom_Circle, Geom2d_Circle)):
        pos = c.Position()
        return {"type": "circle", "center": pt(pos.Location()), "x_dir": pt(pos.XDirection()),
                "y_dir": pt(pos.YDirection()), "radius": c.Radius()}
    if isinstance(c, (Geom_Ellipse, Geom2d_Ellipse)):
        pos = c.Position()
        return {"type": "ellipse", "center": pt(pos.Location()), "x_dir": pt(pos.XDirection()),
                "y_dir": pt(pos.YDirection()), "major_radius": c.MajorRadius(),
                "minor_radius": c.MinorRadius()}
    if isinstance(c, (Geom_BSplineCurve, Geom2d_BSplineCurve)):
        return _bspline_curve_json(c, dim)
    raise TypeError(f"not a format curve: {type(c).__name__}")


def _exact_curve(c: Any, dim: int) -> Optional[Any]:
    """The curve as a format type with the *same* parametrisation, or None if it has none
    (trimmed curves are unwrapped; Béziers become the identical B-spline)."""
    trimmed = Geom_TrimmedCurve if dim == 3 else Geom2d_TrimmedCurve
    while isinstance(c, trimmed):
        c = c.BasisCurve()
    if dim == 3:
        if isinstance(c, (Geom_Line, Geom_Circle, Geom_Ellipse, Geom_BSplineCurve)):
            return c
        if isinstance(c, Geom_BezierCurve):
            return _curve_to_bspline(c)
    else:
        if isinstance(c, (Geom2d_Line, Geom2d_Circle, Geom2d_Ellipse, Geom2d_BSplineCurve)):
            return c
        if isinstance(c, Geom2d_BezierCurve):
            return _curve2d_to_bspline(c)
    return None


def _curve_on_range(c: Any, t0: float, t1: float, dim: int) -> Tuple[Any, float, float]:
    """(curve, t0, t1) of a format type for `c` on [t0, t1] (t0 < t1): the same curve and range
    where it has an exact format type, else the B-spline of OCP's converters on that range (its
    own parameter range; parabolas, hyperbolas, offset curves)."""
    exact = _exact_curve(c, dim)
    if exact is not None:
        if isinstance(exact, (Geom_BSplineCurve, Geom2d_BSplineCurve)):
            span = knot_span_range(t0, t1, exact.FirstParameter(), exact.LastParameter(),
                                   exact.IsPeriodic())
            if span is not None:
                return exact, span[0], span[1]
            # A periodic trim running over the knot span: its non-periodic segment.
            seg = (_curve_to_bspline if dim == 3 else _curve2d_to_bspline)(
                (Geom_TrimmedCurve if dim == 3 else Geom2d_TrimmedCurve)(exact, t0, t1))
            return seg, seg.FirstParameter(), seg.LastParameter()
        return exact, t0, t1
    trimmed = (Geom_TrimmedCurve if dim == 3 else Geom2d_TrimmedCurve)(c, t0, t1)
    try:
        bs = (_curve_to_bspline if dim == 3 else _curve2d_to_bspline)(trimmed)
    except Exception:  # offset curves in older OCCT
        bs = None
    if bs is not None and _same_parameter(trimmed, bs, t0, t1):
        return bs, t0, t1  # exact and same parameter (parabolas, Béziers, offsets of lines...)
    # Hyperbolas have no rational form in their own parameter: approximate on the same parameter
    # (so that the trim's t stays the edge's t, as OCP's SameParameter edges have it).
    approx = (GeomConvert_ApproxCurve if dim == 3 else Geom2dConvert_ApproxCurve)(
        trimmed, _APPROX_TOL, GeomAbs_C2, 200, 9)
    if approx.HasResult() and approx.MaxError() <= _APPROX_TOL:
        a = approx.Curve()
        if _same_parameter(trimmed, a, t0, t1, tol=10 * _APPROX_TOL):
            return a, a.FirstParameter(), a.LastParameter()
    if bs is None:
        raise ExportError(f"no B-spline for a {type(c).__name__} on [{t0}, {t1}]")
    return bs, bs.FirstParameter(), bs.LastParameter()  # exact, another parameter


def _same_parameter(c: Any, bs: Any, t0: float, t1: float, tol: float = 1e-12) -> bool:
    """Whether `bs` is `c` on [t0, t1] point for point at the same parameter (sampled)."""
    return same_parameter(lambda t: _xyz_any(c.Value(t)), lambda t: _xyz_any(bs.Value(t)), t0, t1,
                          (bs.FirstParameter(), bs.LastParameter()), tol)


def _xyz_any(p: Any) -> List[float]:
    return [p.X(), p.Y(), p.Z()] if hasattr(p, "Z") else [p.X(), p.Y()]


def _frame(origin: Any, x: Sequence[float], y: Sequence[float]) -> Dict[str, Any]:
    return {"origin": _xyz(origin), "x_dir": list(x), "y_dir": list(y)}


def _bspline_surface_json(s: Any) -> Dict[str, Any]:
    nu, nv = s.NbUPoles(), s.NbVPoles()
    rational = s.IsURational() or s.IsVRational()
    return {
        "type": "bspline",
        "degree_u": s.UDegree(),
        "degree_v": s.VDegree(),
        "poles": [[_xyz(s.Pole(i, j)) for j in range(1, nv + 1)] for i in range(1, nu + 1)],
        "weights": ([[s.Weight(i, j) for j in range(1, nv + 1)] for i in range(1, nu + 1)]
                    if rational else None),
        "knots_u": [s.UKnot(i) for i in range(1, s.NbUKnots() + 1)],
        "mults_u": [s.UMultiplicity(i) for i in range(1, s.NbUKnots() + 1)],
        "knots_v": [s.VKnot(i) for i in range(1, s.NbVKnots() + 1)],
        "mults_v": [s.VMultiplicity(i) for i in range(1, s.NbVKnots() + 1)],
        "periodic_u": bool(s.IsUPeriodic()),
        "periodic_v": bool(s.IsVPeriodic()),
    }


# --------------------------------------------------------------------------------------------
# surfaces


def _surface(face: Any) -> Tuple[Optional[Dict[str, Any]], bool]:
    """(SURFACE, mirror_u) for a forward face, or (None, False) when it needs NurbsConvert."""
    ad = BRepAdaptor_Surface(face, False)  # location applied
    t = ad.GetType()
    if t == GeomAbs_Plane:
        pos = ad.Plane().Position()  # any handedness: S = O + uX + vY, normal X × Y as in OCP
        return dict(type="plane", **_frame(pos.Location(), _xyz(pos.XDirection()),
                                           _xyz(pos.YDirection()))), False
    if t in (GeomAbs_Cylinder, GeomAbs_Cone, GeomAbs_Sphere, GeomAbs_Torus):
        if t == GeomAbs_Cylinder:
            g = ad.Cylinder()
            extra: Dict[str, Any] = {"type": "cylinder", "radius": g.Radius()}
        elif t == GeomAbs_Cone:
            g = ad.Cone()
            extra = {"type": "cone", "radius": g.RefRadius(), "semi_angle": g.SemiAngle()}
        elif t == GeomAbs_Sphere:
            g = ad.Sphere()
            extra = {"type": "sphere", "radius": g.Radius()}
        else:
            g = ad.Torus()
            extra = {"type": "torus", "major_radius": g.MajorRadius(),
                     "minor_radius": g.MinorRadius()}
        pos = g.Position()
        x, y = _xyz(pos.XDirection()), _xyz(pos.YDirection())
        mirror = not pos.Direct()
        if mirror:  # OCP's axis is -(X × Y): use (X, -Y) and u → 2π - u
            y = _neg(y)
        surf = {"type": extra.pop("type"), **_frame(pos.Location(), x, y), **extra}
        return surf, mirror

    geom = _surface_of(face)  # a transformed copy when the face has a location
    while isinstance(geom, Geom_RectangularTrimmedSurface):
        geom = geom.BasisSurface()
    if isinstance(geom, Geom_BSplineSurface):
        return _bspline_surface_json(geom), False
    if isinstance(geom, Geom_BezierSurface):
        return _bspline_surface_json(_surface_to_bspline(geom)), False
    if isinstance(geom, Geom_SurfaceOfRevolution):
        c = _exact_curve(geom.BasisCurve(), 3)
        if c is not None:
            ax = geom.Axis()
            return {"type": "revolution", "axis_origin": _xyz(ax.Location()),
                    "axis_dir": _xyz(ax.Direction()), "curve": _curve_json(c, 3)}, False
    if isinstance(geom, Geom_SurfaceOfLinearExtrusion):
        c = _exact_curve(geom.BasisCurve(), 3)
        if c is not None:
            return {"type": "extrusion", "direction": _xyz(geom.Direction()),
                    "curve": _curve_json(c, 3)}, False
    return None, False


# --------------------------------------------------------------------------------------------
# loops


def _wire_edges(wire: Any, face: Any) -> List[Any]:
    """The wire's boundary edges in connection order (BRepTools_WireExplorer), with their
    orientation in the face; INTERNAL / EXTERNAL edges are no boundary and are left out. Falls
    back to the stored order when the explorer cannot chain every edge (unsewn data)."""
    stored = []
    exp = TopExp_Explorer(wire, TopAbs_EDGE)
    while exp.More():
        e = _edge(exp.Current())
        if e.Orientation() not in (TopAbs_INTERNAL, TopAbs_EXTERNAL):
            stored.append(e)
        exp.Next()
    chained = []
    we = BRepTools_WireExplorer(wire, face)
    while we.More():
        e = _edge(we.Current())
        if e.Orientation() not in (TopAbs_INTERNAL, TopAbs_EXTERNAL):
            chained.append(e)
        we.Next()
    return chained if len(chained) == len(stored) else stored


class _Pcurve:
    """An OCP 2D curve as document.Trim wants it."""

    __slots__ = ("c",)

    def __init__(self, c: Any) -> None:
        self.c = c

    def uv(self, t: float) -> Tuple[float, float]:
        p = self.c.Value(t)
        return p.X(), p.Y()

    def json(self) -> Dict[str, Any]:
        return _curve_json(self.c, 2)


def _trim(edge: Any, face: Any, mirror: bool, edge_id: Optional[int], where: str) -> Trim:
    c = _pcurve_of(edge, face, 0.0, 0.0)  # OCP returns only the curve...
    if c is None:
        raise ExportError(f"{where}: edge {edge_id} has no pcurve on the face")
    first, last = _range_of(edge, face)  # ...its range comes from here
    c, first, last = _curve_on_range(c, first, last, 2)
    if mirror:
        c = c.Mirrored(_MIRROR_U)  # same kind, same parameter; u → 2π - u
    if edge.Orientation() == TopAbs_REVERSED:
        first, last = last, first
    return Trim(_Pcurve(c), first, last, edge_id)


# --------------------------------------------------------------------------------------------
# the walk


def export_topods(shape: Any, units: str = "mm", source: Optional[str] = None,
                  sew: Optional[bool] = None, sew_tolerance: Optional[float] = None) -> Dict[str, Any]:
    """A `tessd-brep` v1 document (a dict ready for `json.dump`) from a `TopoDS_Shape`.

    `sew`: None (the default) sews a shape with free edges (unsewn IGES / STEP faces, open
    shells) and leaves a closed one alone; True / False force it. `sew_tolerance`: the sewing
    tolerance in the shape's units (default `default_sew_tolerance`). See `prepare`."""
    check_units(units)
    if shape is None or shape.IsNull():
        raise ExportError("empty shape")
    return export_prepared(prepare(shape, sew=sew, sew_tolerance=sew_tolerance), units, source)


class Prepared(NamedTuple):
    """The shape whose faces and edges the document numbers (the input, or the sewn faces in
    the input's face order, as a compound) and the `sewing` report (None when not sewn)."""

    shape: Any
    sewing: Optional[Dict[str, Any]]


def export_prepared(prepared: Prepared, units: str = "mm", source: Optional[str] = None) -> Dict[str, Any]:
    """The document of a `prepare`d shape (its `sewing` report included)."""
    check_units(units)
    shape = prepared.shape
    face_map = TopTools_IndexedMapOfShape()
    _map_shapes(shape, TopAbs_FACE, face_map)
    edge_map = TopTools_IndexedMapOfShape()
    for i in range(1, face_map.Extent() + 1):
        _map_shapes(face_map.FindKey(i), TopAbs_EDGE, edge_map)
    edge_faces: Dict[int, List[int]] = {}

    faces = []
    for fid in range(1, face_map.Extent() + 1):
        faces.append(_export_face(_face(face_map.FindKey(fid)), fid, edge_map, edge_faces))

    edges = []
    for eid in range(1, edge_map.Extent() + 1):
        edges.append(_export_edge(_edge(edge_map.FindKey(eid)), eid, edge_faces.get(eid, [])))

    return new_document(units, source, faces, edges, sewing=prepared.sewing)


def document_face(face: Any) -> Tuple[Any, Optional[Dict[str, Any]], bool, Any]:
    """The forward face whose (u, v) the exported document uses, its SURFACE, whether u is
    mirrored (u_doc = 2π − u_ocp) and the `BRepBuilderAPI_NurbsConvert` that made it (None when
    the face has an exact format type and is used as it is). Shared with the tests that compare
    our (u, v) answers with OCP's on the same face."""
    ff = _face(face.Oriented(TopAbs_FORWARD))
    surf, mirror = _surface(ff)
    if surf is not None:
        return ff, surf, mirror, None
    # No exact format type: OCP's NURBS conversion of the face (pcurves included).
    conv = BRepBuilderAPI_NurbsConvert(ff, True)
    work = _face(_face(conv.Shape()).Oriented(TopAbs_FORWARD))
    surf, mirror = _surface(work)
    return work, surf, mirror, conv


def _export_face(face: Any, fid: int, edge_map: Any, edge_faces: Dict[int, List[int]]) -> Dict[str, Any]:
    where = f"face {fid}"
    reversed_ = face.Orientation() == TopAbs_REVERSED
    ff = _face(face.Oriented(TopAbs_FORWARD))
    work, surf, mirror, conv = document_face(face)
    # OCP edge of `work` → edge id (ids are the original shape's edges).
    renamed: Optional[List[Tuple[Any, int]]] = None
    if conv is not None:
        renamed = []
        exp = TopExp_Explorer(ff, TopAbs_EDGE)
        while exp.More():
            orig = exp.Current()
            renamed.append((conv.ModifiedShape(orig), edge_map.FindIndex(orig)))
            exp.Next()
    if surf is None:
        raise ExportError(f"{where}: NurbsConvert gave no B-spline surface")

    def edge_id(e: Any) -> Optional[int]:
        if renamed is None:
            i = edge_map.FindIndex(e)
            return i if i > 0 else None
        return next((i for new, i in renamed if new.IsSame(e)), None)

    outer = _outer_wire(work)
    explored = []
    exp = TopExp_Explorer(work, TopAbs_WIRE)
    while exp.More():
        explored.append(_wire(exp.Current()))
        exp.Next()
    wires = outer_first(explored, lambda w: not outer.IsNull() and w.IsSame(outer))

    wire_trims: List[List[Trim]] = []
    for li, w in enumerate(wires):
        trims = []
        for e in _wire_edges(w, work):
            eid = edge_id(e)
            trims.append(_trim(e, work, mirror, eid, f"{where} loop {li}"))
            note_edge_face(edge_faces, eid, fid)
        wire_trims.append(trims)
    return face_json(fid, reversed_, mirror, surf, wire_trims, _uv_bounds(work), where)


def _export_edge(edge: Any, eid: int, faces: List[int]) -> Dict[str, Any]:
    first, last = _range_of(edge)
    curve = None
    if not _degenerated(edge):
        c = _curve_of(edge, 0.0, 0.0)  # location applied; OCP returns only the curve
        if c is not None:
            c, first, last = _curve_on_range(c, first, last, 3)
            curve = _curve_json(c, 3)
    return edge_json(eid, curve, first, last, faces, tolerance=_tolerance(edge),
                     vertex_tolerances=_vertex_tolerances(edge))


def _vertex_tolerances(edge: Any) -> Optional[List[float]]:
    """[t0, t1]: the tolerances of the edge's vertices at the start and the end of its range.
    `TopExp::FirstVertex(edge, CumOri = false)` is the vertex oriented FORWARD in the edge,
    which OCCT puts at the curve's first parameter whatever the edge's own orientation; the
    range is always written first < last (ranges are never reversed by `_curve_on_range`).
    None for an edge without both vertices (an infinite one)."""
    v0, v1 = _first_vertex(edge, False), _last_vertex(edge, False)
    if v0.IsNull() or v1.IsNull():
        return None
    return [_tolerance(v0), _tolerance(v1)]


# --------------------------------------------------------------------------------------------
# sewing

# The default sewing tolerance's floor and cap, as fractions of the bounding-box diagonal.
SEW_FLOOR = 1e-6
SEW_CAP = 1e-3


def _faces(shape: Any) -> List[Any]:
    m = TopTools_IndexedMapOfShape()
    _map_shapes(shape, TopAbs_FACE, m)
    return [_face(m.FindKey(i)) for i in range(1, m.Extent() + 1)]


def free_edges(faces: Sequence[Any]) -> List[Any]:
    """The free edges of a set of faces: boundary edges (FORWARD / REVERSED in their wire) that
    bound one face only, once (a seam of a periodic face bounds it twice: not free), that are
    not degenerate (a sphere's pole bounds one face and is no gap)."""
    index = TopTools_IndexedMapOfShape()
    uses: Dict[int, List[int]] = {}
    for fi, f in enumerate(faces):
        exp = TopExp_Explorer(f, TopAbs_EDGE)
        while exp.More():
            e = exp.Current()
            if e.Orientation() in (TopAbs_FORWARD, TopAbs_REVERSED):
                uses.setdefault(index.Add(e), []).append(fi)
            exp.Next()
    return [_edge(index.FindKey(i)) for i, fs in uses.items()
            if len(fs) == 1 and not _degenerated(_edge(index.FindKey(i)))]


def _diagonal(shape: Any) -> float:
    box = Bnd_Box()
    _add_to_box(shape, box)
    if box.IsVoid():
        return 0.0
    return box.CornerMin().Distance(box.CornerMax())


def _largest_tolerance(shape: Any) -> float:
    tol = 0.0
    for kind, cast in ((TopAbs_EDGE, _edge), (TopAbs_VERTEX, _vertex)):
        exp = TopExp_Explorer(shape, kind)
        while exp.More():
            tol = max(tol, _tolerance(cast(exp.Current())))
            exp.Next()
    return tol


def default_sew_tolerance(shape: Any) -> float:
    """The sewing tolerance used when none is given: the largest edge or vertex tolerance of the
    shape, at least SEW_FLOOR (1e-6) × its bounding-box diagonal, at most SEW_CAP (1e-3) × it.

    Why: sewing joins two free edges that lie within the tolerance of each other. The gaps
    between neighbouring faces of unsewn data are the sending system's precision, which the
    reader records in the tolerances (IGES's resolution, what ShapeFix had to allow for): the
    largest of them is the widest gap the data itself admits (hammer.iges: 0.37, where 1e-6 ×
    its 41 m diagonal leaves edges unsewn). The floor covers data whose recorded tolerances are
    OCCT's 1e-7 while its coordinates, large, only meet to their last digits; the cap keeps one
    bad tolerance from sewing across features (any two free edges closer than the tolerance are
    joined: a slot 0.5 mm wide would close at 0.5)."""
    diagonal = _diagonal(shape)
    tol = max(_largest_tolerance(shape), SEW_FLOOR * diagonal)
    if diagonal > 0:
        tol = min(tol, SEW_CAP * diagonal)
    if not tol > 0:
        raise ExportError("cannot choose a sewing tolerance for a shape without extent: give one")
    return tol


def prepare(shape: Any, sew: Optional[bool] = None, sew_tolerance: Optional[float] = None) -> Prepared:
    """The shape to export and its sewing report. `sew` None: sewn when it has free edges
    (IGES surface models, loose STEP faces, open shells), not when closed; True / False: as
    asked. A sewn shape is exported as the compound of its faces in the input's face order (face
    ids stay the input's); when sewing joins nothing, the input itself."""
    if sew_tolerance is not None and not (isinstance(sew_tolerance, (int, float))
                                          and math.isfinite(sew_tolerance) and sew_tolerance > 0):
        raise ValueError(f"sew_tolerance must be a positive length, not {sew_tolerance!r}")
    faces = _faces(shape)
    before = len(free_edges(faces))
    if sew is None:
        sew = before > 0
    if not sew or not faces:
        return Prepared(shape, None)
    tol = sew_tolerance if sew_tolerance is not None else default_sew_tolerance(shape)
    sewing = BRepBuilderAPI_Sewing(tol)
    sewing.Add(shape)
    sewing.Perform()
    sewn = sewing.SewedShape()
    report = {"tolerance": tol, "free_edges_before": before, "free_edges_after": before,
              "sewn_edges": 0, "faces": len(faces)}
    if sewn is None or sewn.IsNull():
        return Prepared(shape, report)
    sewn_map = TopTools_IndexedMapOfShape()
    _map_shapes(sewn, TopAbs_FACE, sewn_map)
    comp = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(comp)
    out = []
    for f in faces:
        i = 0
        # (`ModifiedSubShape`: the sewn version of a sub-shape of what was added; `Modified`
        # only answers for the added shapes themselves.)
        for candidate in (sewing.ModifiedSubShape(f), sewing.Modified(f), f):
            if candidate is not None and not candidate.IsNull():
                i = sewn_map.FindIndex(candidate)
                if i:
                    break
        # A face sewing dropped (degenerate) stays as it was, unsewn.
        g = _face(sewn_map.FindKey(i)) if i else f
        out.append(g)
        builder.Add(comp, g)
    after = len(free_edges(out))
    if after >= before:
        return Prepared(shape, report)  # nothing joined: the input as it is
    report.update(free_edges_after=after, sewn_edges=sewing.NbContigousEdges(), faces=len(out))
    return Prepared(comp, report)


# --------------------------------------------------------------------------------------------
# inputs


def to_topods(shape: Any) -> Any:
    """A `TopoDS_Shape` from OCP itself, a cadquery / build123d `Shape` (`.wrapped`), or a
    cadquery `Workplane` (its objects' shapes, as one compound)."""
    if isinstance(shape, TopoDS_Shape):
        return shape
    wrapped = getattr(shape, "wrapped", None)
    if isinstance(wrapped, TopoDS_Shape):
        return wrapped
    vals = getattr(shape, "vals", None)
    if callable(vals):  # cadquery Workplane
        shapes = [to_topods(v) for v in vals() if isinstance(getattr(v, "wrapped", None), TopoDS_Shape)]
        if len(shapes) == 1:
            return shapes[0]
        comp = TopoDS_Compound()
        b = BRep_Builder()
        b.MakeCompound(comp)
        for s in shapes:
            b.Add(comp, s)
        return comp
    raise TypeError(f"not an OCP shape: {type(shape).__name__}")


_XSTEP_UNITS = {"mm": "MM", "cm": "CM", "m": "M", "in": "INCH"}


def read_file(path: str, units: str = "mm") -> Any:
    """A `TopoDS_Shape` from a STEP (.step/.stp), IGES (.iges/.igs) or OpenCASCADE (.brep/.brp)
    file. STEP and IGES are converted to `units`; a .brep file has no unit (taken as `units`).
    IGES surface models stay unsewn here (a compound of faces): `export_topods` sews them."""
    ext = os.path.splitext(path)[1].lower()
    if not os.path.isfile(path):
        raise FileNotFoundError(path)
    if ext in (".step", ".stp", ".iges", ".igs"):
        from OCP.IFSelect import IFSelect_RetDone
        from OCP.Interface import Interface_Static

        if ext in (".step", ".stp"):
            from OCP.STEPControl import STEPControl_Reader

            reader = STEPControl_Reader()
        else:
            from OCP.IGESControl import IGESControl_Reader

            reader = IGESControl_Reader()
        # The reader's target unit (set after the reader exists: creating it initialises the
        # static parameters).
        # (The parameter is process-wide: put the previous value back afterwards.)
        previous = _static(Interface_Static, "CVal")("xstep.cascade.unit")
        _static(Interface_Static, "SetCVal")("xstep.cascade.unit", _XSTEP_UNITS[units])
        try:
            if reader.ReadFile(path) != IFSelect_RetDone:
                raise ExportError(f"{path}: not readable as {ext[1:].upper()}")
            reader.TransferRoots()
            shape = reader.OneShape()
        finally:
            if previous:
                _static(Interface_Static, "SetCVal")("xstep.cascade.unit", previous)
    elif ext in (".brep", ".brp"):
        shape = TopoDS_Shape()
        if not _static(BRepTools, "Read")(shape, path, BRep_Builder()):
            raise ExportError(f"{path}: not readable as an OpenCASCADE .brep file")
    else:
        raise ExportError(f"{path}: unknown extension {ext!r} (expected .step/.stp, .iges/.igs, .brep/.brp)")
    if shape is None or shape.IsNull():
        raise ExportError(f"{path}: no shape in the file")
    return shape
