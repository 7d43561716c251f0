"""Test parts built with OCP alone (no cadquery, no build123d), so that tests/brep runs under
OCP 7.9 (cadquery 2.8's venv, .venv-cad) and OCP 8.0 (build123d 0.13's, .venv-b123d) alike:
the names OCP 8.0 moved come from tessd.brep.ocp_compat, the APIs used exist in both.

`PARTS`: the exporter's cases (planes and holes, fillets, revolutions, tori, lofts, islands,
mirrored frames, extrusions, located shapes, an offset surface); the geometry is the one the
cadquery versions of these parts had (same sizes and placements), which the tests assert on.

`FILE_FIXTURES` (tests/brep/test_file_fixtures.py): the cases of real STEP and IGES files that
the exporter and the daemon must get right, made by OCP itself and, where a file is the point,
written by OCP's STEP / IGES writers and read back through `tessd.brep.ocp.read_file`:
revolved and extruded B-spline profiles, an offset solid (offset surfaces, which go through
NurbsConvert, meeting faces that do not), a mirrored part through STEP, a STEP part whose edges
miss their vertices by up to 1e-3 mm (loose tolerances), and unsewn IGES shells (each face
written as a surface of its own)."""

from __future__ import annotations

import math
import os
from typing import Any, Callable, Dict, List, Sequence

from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakePolygon,
    BRepBuilderAPI_MakeWire,
    BRepBuilderAPI_Transform,
)
from OCP.BRepFilletAPI import BRepFilletAPI_MakeChamfer, BRepFilletAPI_MakeFillet
from OCP.BRepOffsetAPI import BRepOffsetAPI_MakeOffsetShape, BRepOffsetAPI_ThruSections
from OCP.BRepPrimAPI import (
    BRepPrimAPI_MakeBox,
    BRepPrimAPI_MakeCylinder,
    BRepPrimAPI_MakePrism,
    BRepPrimAPI_MakeRevol,
    BRepPrimAPI_MakeSphere,
)
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_BSplineCurve, Geom_OffsetSurface
from OCP.gp import gp_Ax1, gp_Ax2, gp_Circ, gp_Dir, gp_Elips, gp_Pnt, gp_Trsf, gp_Vec
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

from tessd.brep import ocp as brep_ocp
from tessd.brep.ocp_compat import (
    TColgp_Array1OfPnt,
    TColStd_Array1OfInteger,
    TColStd_Array1OfReal,
    TopTools_IndexedMapOfShape,
)
from tessd.brep.ocp_compat import static as _s

_face = _s(TopoDS, "Face")
_edge = _s(TopoDS, "Edge")
_vertex = _s(TopoDS, "Vertex")


# ------------------------------------------------------------------------------------------
# small builders


def box(dx: float, dy: float, dz: float) -> Any:
    """A box centred on the origin (as cadquery's `box`)."""
    return BRepPrimAPI_MakeBox(gp_Pnt(-dx / 2, -dy / 2, -dz / 2), dx, dy, dz).Shape()


def cylinder(r: float, h: float, base=(0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)) -> Any:
    return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(*base), gp_Dir(*axis)), r, h).Shape()


def cut(shape: Any, *tools: Any) -> Any:
    for tool in tools:
        op = BRepAlgoAPI_Cut(shape, tool)
        assert op.IsDone(), "boolean cut failed"
        shape = op.Shape()
    return shape


def fuse(shape: Any, *tools: Any) -> Any:
    for tool in tools:
        op = BRepAlgoAPI_Fuse(shape, tool)
        assert op.IsDone(), "boolean fuse failed"
        shape = op.Shape()
    return shape


def sub_shapes(shape: Any, kind: Any) -> List[Any]:
    """The distinct sub-shapes of one kind (TopExp::MapShapes order)."""
    m = TopTools_IndexedMapOfShape()
    _s(TopExp, "MapShapes")(shape, kind, m)
    return [m.FindKey(i) for i in range(1, m.Extent() + 1)]


def bspline(points: Sequence[Sequence[float]], degree: int = 3) -> Any:
    """The clamped, uniform B-spline curve with these poles (3D)."""
    n = len(points)
    poles = TColgp_Array1OfPnt(1, n)
    for i, p in enumerate(points):
        poles.SetValue(i + 1, gp_Pnt(*p))
    inner = n - degree - 1
    knots = TColStd_Array1OfReal(1, inner + 2)
    mults = TColStd_Array1OfInteger(1, inner + 2)
    for i in range(inner + 2):
        knots.SetValue(i + 1, i / (inner + 1))
        mults.SetValue(i + 1, degree + 1 if i in (0, inner + 1) else 1)
    return Geom_BSplineCurve(poles, knots, mults, degree, False)


def wire(*edges: Any) -> Any:
    mk = BRepBuilderAPI_MakeWire()
    for e in edges:
        mk.Add(e)
    assert mk.IsDone(), "wire not closed / connected"
    return mk.Wire()


def segment(a: Sequence[float], b: Sequence[float]) -> Any:
    return BRepBuilderAPI_MakeEdge(gp_Pnt(*a), gp_Pnt(*b)).Edge()


def spline_edge(points: Sequence[Sequence[float]]) -> Any:
    return BRepBuilderAPI_MakeEdge(bspline(points)).Edge()


def planar_face(w: Any) -> Any:
    mk = BRepBuilderAPI_MakeFace(w, True)
    assert mk.IsDone(), "no planar face on the wire"
    return mk.Face()


def revolve(face: Any, angle: float = 2 * math.pi, axis=((0, 0, 0), (0, 0, 1))) -> Any:
    mk = BRepPrimAPI_MakeRevol(face, gp_Ax1(gp_Pnt(*axis[0]), gp_Dir(*axis[1])), angle)
    return mk.Shape()


def transformed(shape: Any, trsf: Any) -> Any:
    return BRepBuilderAPI_Transform(shape, trsf, True).Shape()


def mirror_yz(shape: Any) -> Any:
    """`shape` mirrored about the YZ plane (its cylinders / cones / spheres get indirect frames)."""
    trsf = gp_Trsf()
    trsf.SetMirror(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0)))
    return transformed(shape, trsf)


# ------------------------------------------------------------------------------------------
# the exporter's parts


def plate_with_holes() -> Any:
    """80 × 60 × 10 with six through holes (Ø6) and four counterbored ones (Ø4, Ø7 × 3)."""
    plate = box(80, 60, 10)
    holes = [cylinder(3, 12, (x, y, -6)) for x in (-20, 0, 20) for y in (-10, 10)]
    for x in (-30, 30):
        for y in (-20, 20):
            holes += [cylinder(2, 12, (x, y, -6)), cylinder(3.5, 4, (x, y, 2))]
    return cut(plate, *holes)


def filleted_box() -> Any:
    """Every edge of a 30 × 20 × 10 box filleted (r 3): planes, cylinders, sphere corners."""
    shape = box(30, 20, 10)
    mk = BRepFilletAPI_MakeFillet(shape)
    for e in sub_shapes(shape, TopAbs_EDGE):
        mk.Add(3.0, _edge(e))
    return mk.Shape()


def revolved() -> Any:
    """A profile of lines and a spline in XZ revolved about Z: planes, a cone, a cylinder, a
    surface of revolution of the spline."""
    pts = [(0, 0, 0), (10, 0, 0), (12, 0, 5), (12, 0, 10)]
    edges = [segment(a, b) for a, b in zip(pts, pts[1:])]
    edges.append(spline_edge([(12, 0, 10), (11, 0, 14), (7, 0, 17), (6, 0, 22)]))
    edges += [segment((6, 0, 22), (0, 0, 22)), segment((0, 0, 22), (0, 0, 0))]
    return revolve(planar_face(wire(*edges)))


def revolved_torus() -> Any:
    """A circle of radius 4 at x = 20 in XZ revolved 270° about Z: a torus and two discs."""
    circle = BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp_Pnt(20, 0, 0), gp_Dir(0, 1, 0)), 4)).Edge()
    return revolve(planar_face(wire(circle)), 1.5 * math.pi)


def lofted() -> Any:
    """A smooth loft through a 20 × 20 square (z 0), a circle r 8 (z 15) and an ellipse 12 × 6
    (z 25): B-spline faces."""
    square = BRepBuilderAPI_MakePolygon(gp_Pnt(-10, -10, 0), gp_Pnt(10, -10, 0), gp_Pnt(10, 10, 0),
                                        gp_Pnt(-10, 10, 0), True).Wire()
    circle = wire(BRepBuilderAPI_MakeEdge(gp_Circ(gp_Ax2(gp_Pnt(0, 0, 15), gp_Dir(0, 0, 1)), 8)).Edge())
    ellipse = wire(BRepBuilderAPI_MakeEdge(gp_Elips(gp_Ax2(gp_Pnt(0, 0, 25), gp_Dir(0, 0, 1)), 12, 6)).Edge())
    mk = BRepOffsetAPI_ThruSections(True, False)
    for w in (square, circle, ellipse):
        mk.AddWire(w)
    mk.Build()
    assert mk.IsDone(), "loft failed"
    return mk.Shape()


def island() -> Any:
    """A 50 × 50 × 10 block with a ring pocket (r 6 to 15, 4 deep): the top face has a hole,
    the island's disc is a face of its own in it, the pocket's floor is a ring."""
    ring = cut(cylinder(15, 5, (0, 0, 1)), cylinder(6, 5, (0, 0, 1)))
    return cut(box(50, 50, 10), ring)


def mirrored() -> Any:
    """A block with a hole, filleted vertical edges, a chamfered bottom (planes and a cone) and a
    sphere on top, mirrored about YZ: OCP's frames of its cylinders, cones and spheres turn
    indirect (left-handed)."""
    part = cut(box(30, 20, 10), cylinder(4, 12, (0, 0, -6)))
    fil = BRepFilletAPI_MakeFillet(part)
    for e in sub_shapes(part, TopAbs_EDGE):
        e = _edge(e)
        a, b = _s(TopExp, "FirstVertex")(e), _s(TopExp, "LastVertex")(e)
        pa, pb = _s(BRep_Tool, "Pnt")(a), _s(BRep_Tool, "Pnt")(b)
        if abs(pa.X() - pb.X()) < 1e-9 and abs(pa.Y() - pb.Y()) < 1e-9 and abs(pa.X()) == 15:
            fil.Add(2.0, e)  # the block's four vertical edges
    part = fil.Shape()
    bottom = [f for f in sub_shapes(part, TopAbs_FACE) if _is_plane_at(_face(f), -5.0)]
    assert len(bottom) == 1
    ch = BRepFilletAPI_MakeChamfer(part)
    for e in sub_shapes(bottom[0], TopAbs_EDGE):
        ch.Add(1.0, _edge(e))
    part = fuse(ch.Shape(), BRepPrimAPI_MakeSphere(gp_Pnt(0, 0, 8), 6).Shape())
    return mirror_yz(part)


def _is_plane_at(face: Any, z: float) -> bool:
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Plane

    ad = BRepAdaptor_Surface(face)
    if ad.GetType() != GeomAbs_Plane:
        return False
    pl = ad.Plane()
    return abs(abs(pl.Axis().Direction().Z()) - 1) < 1e-12 and abs(pl.Location().Z() - z) < 1e-9


def extruded_spline() -> Any:
    """A spline through (0, 0), (10, 5), (20, -3), (30, 4) closed by lines, extruded 8 along Z."""
    w = wire(spline_edge([(0, 0, 0), (10, 5, 0), (20, -3, 0), (30, 4, 0)]),
             segment((30, 4, 0), (30, 20, 0)), segment((30, 20, 0), (0, 20, 0)),
             segment((0, 20, 0), (0, 0, 0)))
    return BRepPrimAPI_MakePrism(planar_face(w), gp_Vec(0, 0, 8)).Shape()


def moved() -> Any:
    """A cylinder (r 4, h 10, centred) placed by a TopLoc_Location (not baked into its
    geometry): rotated 33° about (1, 1, 0), moved by (5, -3, 7)."""
    c = cylinder(4, 10, (0, 0, -5))
    trsf = gp_Trsf()
    trsf.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 1, 0)), math.radians(33))
    move = gp_Trsf()
    move.SetTranslation(gp_Vec(5, -3, 7))
    return c.Moved(TopLoc_Location(move.Multiplied(trsf)))


def offset_face() -> Any:
    """The loft's first B-spline face offset by 1.5 (a Geom_OffsetSurface: no format type, it
    goes through BRepBuilderAPI_NurbsConvert)."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_BSplineSurface

    faces = [_face(f) for f in sub_shapes(lofted(), TopAbs_FACE)]
    bs = next(f for f in faces if BRepAdaptor_Surface(f).GetType() == GeomAbs_BSplineSurface)
    u0, u1, v0, v1 = _s(BRepTools, "UVBounds")(bs)
    off = Geom_OffsetSurface(_s(BRep_Tool, "Surface")(bs), 1.5)
    return BRepBuilderAPI_MakeFace(off, u0, u1, v0, v1, 1e-7).Face()


PARTS: Dict[str, Callable[[], Any]] = {
    "plate_with_holes": plate_with_holes,
    "filleted_box": filleted_box,
    "revolved": revolved,
    "revolved_torus": revolved_torus,
    "lofted": lofted,
    "island": island,
    "mirrored": mirrored,
    "extruded_spline": extruded_spline,
    "moved": moved,
    "offset_face": offset_face,
}


# ------------------------------------------------------------------------------------------
# the file fixtures


def revolved_bspline(tmp: str) -> Any:
    """A profile with a wavy degree-3 B-spline (lines to the axis at both ends) revolved a full
    turn about Z: a surface of revolution of the B-spline (with its seam) between two discs."""
    w = wire(segment((0, 0, 0), (15, 0, 0)),
             spline_edge([(15, 0, 0), (22, 0, 8), (5, 0, 16), (14, 0, 24), (8, 0, 30)]),
             segment((8, 0, 30), (0, 0, 30)), segment((0, 0, 30), (0, 0, 0)))
    return revolve(planar_face(w))


def extruded_bspline(tmp: str) -> Any:
    """A B-spline (degree 3, 6 poles) closed by two lines, extruded obliquely along
    (3, 2, 25): a surface of linear extrusion of the B-spline, two planes, two B-spline-bounded
    caps."""
    w = wire(spline_edge([(0, 0, 0), (10, 8, 0), (20, -6, 0), (30, 10, 0), (40, -4, 0), (50, 0, 0)]),
             segment((50, 0, 0), (25, 30, 0)), segment((25, 30, 0), (0, 0, 0)))
    return BRepPrimAPI_MakePrism(planar_face(w), gp_Vec(3, 2, 25)).Shape()


def offset_solid(tmp: str) -> Any:
    """`extruded_bspline` offset outwards by 2 (BRepOffsetAPI_MakeOffsetShape, arc joins): the
    B-spline extrusion's offset is a Geom_OffsetSurface (exported through NurbsConvert) meeting
    planes, cylinders and spheres of the joins that are exported as they are."""
    mk = BRepOffsetAPI_MakeOffsetShape()
    mk.PerformByJoin(extruded_bspline(tmp), 2.0, 1e-7)
    assert mk.IsDone(), "offset failed"
    return mk.Shape()


def write_step(shape: Any, path: str) -> None:
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    w = STEPControl_Writer()
    assert w.Transfer(shape, STEPControl_AsIs) == IFSelect_RetDone, "STEP transfer failed"
    assert w.Write(path) == IFSelect_RetDone, f"cannot write {path}"


def write_iges_faces(faces: Sequence[Any], path: str) -> None:
    """Each face as an IGES surface entity of its own (trimmed surfaces, mode 0: no B-Rep
    topology), as surface-model IGES files come: read back, they are a compound of unsewn
    faces."""
    from OCP.IGESControl import IGESControl_Writer

    w = IGESControl_Writer("MM", 0)
    for f in faces:
        assert w.AddShape(f), "IGES transfer failed"
    w.ComputeModel()
    assert w.Write(path), f"cannot write {path}"


def read_back(path: str) -> Any:
    return brep_ocp.read_file(path, units="mm")


def mirrored_step(tmp: str) -> Any:
    """`mirrored` (indirect frames) written to STEP by STEPControl_Writer and read back."""
    path = os.path.join(tmp, "mirrored.step")
    write_step(mirrored(), path)
    return read_back(path)


# How far each edge of `loose_step` is moved off its vertices and faces (mm): gaps between the
# edges' ends at a vertex of up to 2 × this, within the vertex tolerances of 1e-3 mm.
LOOSE_SHIFT = 5e-4
LOOSE_TOLERANCE = 1e-3


def loose_step(tmp: str) -> Any:
    """A block with a cylindrical hole whose every edge curve is moved by LOOSE_SHIFT in its own
    direction (deterministic), so that at each vertex the edges' ends miss each other and the
    vertex point by up to 2 × LOOSE_SHIFT, and every tolerance raised to LOOSE_TOLERANCE
    (`BRep_Builder.UpdateEdge / UpdateVertex`): a valid B-Rep within 1e-3 mm, as files from
    systems with loose tolerances are. Written to STEP and read back (the reader recomputes
    the tolerances from the gaps it finds)."""
    part = cut(box(40, 30, 12), cylinder(6, 14, (4, 2, -7)))
    builder = BRep_Builder()
    for k, e in enumerate(sub_shapes(part, TopAbs_EDGE)):
        e = _edge(e)
        if _s(BRep_Tool, "Degenerated")(e):
            continue
        loc = TopLoc_Location()
        curve, _first, _last = _curve_with_range(e, loc)
        a = 2.0 * math.pi * k / 7.0
        shift = gp_Vec(math.cos(a), math.sin(a), math.cos(3 * a)).Normalized().Multiplied(LOOSE_SHIFT)
        moved_curve = curve.Translated(shift)
        builder.UpdateEdge(e, moved_curve, loc, LOOSE_TOLERANCE)
    for v in sub_shapes(part, TopAbs_VERTEX):
        builder.UpdateVertex(_vertex(v), LOOSE_TOLERANCE)
    path = os.path.join(tmp, "loose.step")
    write_step(part, path)
    return read_back(path)


def _curve_with_range(edge: Any, loc: Any):
    """The edge's 3D curve (in its own location `loc`) and range."""
    got = _s(BRep_Tool, "Curve")(edge, loc, 0.0, 0.0)
    first, last = _s(BRep_Tool, "Range")(edge)
    return got, first, last


def iges_open_box(tmp: str) -> Any:
    """Five faces of a 40 × 30 × 20 box (the top left out), each an IGES surface of its own,
    read back as a compound of unsewn faces: sewn, a shell whose only free edges are the top
    rim (140 mm)."""
    faces = [f for f in sub_shapes(BRepPrimAPI_MakeBox(40, 30, 20).Shape(), TopAbs_FACE)
             if not _is_plane_at(_face(f), 20.0)]
    assert len(faces) == 5
    path = os.path.join(tmp, "open_box.igs")
    write_iges_faces(faces, path)
    return read_back(path)


def iges_cylinder(tmp: str) -> Any:
    """The three faces of a cylinder (r 12, h 30), each an IGES surface of its own, read back
    unsewn: sewn, a closed shell (no free edges; the lateral face's seam is no free edge)."""
    faces = sub_shapes(BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 12, 30).Shape(),
                       TopAbs_FACE)
    assert len(faces) == 3
    path = os.path.join(tmp, "cylinder.igs")
    write_iges_faces(faces, path)
    return read_back(path)


FILE_FIXTURES: Dict[str, Callable[[str], Any]] = {
    "revolved_bspline": revolved_bspline,
    "extruded_bspline": extruded_bspline,
    "offset_solid": offset_solid,
    "mirrored_step": mirrored_step,
    "loose_step": loose_step,
    "iges_open_box": iges_open_box,
    "iges_cylinder": iges_cylinder,
}
# The fixtures that are closed (their sewn / exported shell has no free edge).
CLOSED = {"revolved_bspline", "extruded_bspline", "offset_solid", "mirrored_step", "loose_step",
          "iges_cylinder"}
# The free-edge length of the open ones (mm): the box's top rim.
FREE_LENGTH = {"iges_open_box": 2 * (40 + 30)}
