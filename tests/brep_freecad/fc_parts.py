"""Parts built with FreeCAD's Part API for the FreeCAD exporter's tests: each reaches a case of
the format (fillets and chamfers, holes, revolution, B-spline loft, seams and poles, a torus, a
face with a hole around an island, left-handed frames, a surface that must be converted, an
extrusion, a located shape)."""

from __future__ import annotations

import math

import FreeCAD
import Part

V = FreeCAD.Vector


def filleted_box():
    """Planes and cylinders from makeFillet on the vertical edges, planes from makeChamfer."""
    box = Part.makeBox(30, 20, 10)
    vertical = [e for e in box.Edges if abs(e.tangentAt(e.FirstParameter).z) > 0.99]
    filleted = box.makeFillet(3, vertical)
    bottom = [e for e in filleted.Edges
              if e.BoundBox.ZMax < 1e-9 and e.Curve.__class__.__name__ == "Line"]
    return filleted.makeChamfer(1, bottom)


def cylinder_with_holes():
    """Three axial through holes and one radial: cylinder / cylinder intersections."""
    body = Part.makeCylinder(20, 12)
    for k in range(3):
        a = 2 * math.pi * k / 3
        body = body.cut(Part.makeCylinder(3, 12, V(11 * math.cos(a), 11 * math.sin(a), 0)))
    radial = Part.makeCylinder(2.5, 50, V(-25, 0, 6), V(1, 0, 0))
    return body.cut(radial)


def revolved_profile():
    """A profile of lines and a B-spline revolved 360°: planes, cone, cylinder, a surface of
    revolution of the spline."""
    spline = Part.BSplineCurve()
    spline.interpolate([V(12, 0, 10), V(8, 0, 16), V(6, 0, 22)])
    edges = [Part.makeLine(V(0, 0, 0), V(10, 0, 0)), Part.makeLine(V(10, 0, 0), V(12, 0, 5)),
             Part.makeLine(V(12, 0, 5), V(12, 0, 10)), spline.toShape(),
             Part.makeLine(V(6, 0, 22), V(0, 0, 22)), Part.makeLine(V(0, 0, 22), V(0, 0, 0))]
    face = Part.Face(Part.Wire(edges))
    return face.revolve(V(0, 0, 0), V(0, 0, 1), 360)


def lofted():
    """A loft through B-spline sections (interpolated closed curves): B-spline surfaces."""
    sections = []
    for z, rx, ry in ((0, 10, 10), (15, 8, 5), (25, 12, 6)):
        pts = [V(rx * math.cos(a), ry * math.sin(a), z)
               for a in (2 * math.pi * k / 8 for k in range(8))]
        bs = Part.BSplineCurve()
        bs.interpolate(pts, PeriodicFlag=True)
        sections.append(Part.Wire([bs.toShape()]))
    return Part.makeLoft(sections, True, False)


def sphere():
    """One spherical face: a seam and two degenerate (pole) edges."""
    return Part.makeSphere(6, V(1, 2, 3))


def torus():
    return Part.makeTorus(20, 4)


def island():
    """A box with a ring pocket: its top face has a hole, the island's disc is a face of its own
    in that hole, and the pocket's floor is a ring (a face with a hole)."""
    box = Part.makeBox(50, 50, 10, V(-25, -25, 0))
    ring = Part.makeCylinder(15, 4, V(0, 0, 6)).cut(Part.makeCylinder(6, 4, V(0, 0, 6)))
    return box.cut(ring)


def mirrored():
    """A part with a hole, fillets and a sphere, mirrored: left-handed (indirect) frames."""
    part = Part.makeBox(30, 20, 10).cut(Part.makeCylinder(4, 10, V(15, 10, 0)))
    vertical = [e for e in part.Edges if e.Curve.__class__.__name__ == "Line"
                and abs(e.tangentAt(e.FirstParameter).z) > 0.99]
    part = part.makeFillet(2, vertical).fuse(Part.makeSphere(6, V(15, 10, 12)))
    return part.mirror(V(0, 0, 0), V(1, 0, 0))


def offset_face():
    """A face on an offset surface (no format type: exported through toNurbs)."""
    loft = lofted()
    bs = [f for f in loft.Faces if isinstance(f.Surface, Part.BSplineSurface)][0]
    u0, u1, v0, v1 = bs.ParameterRange
    return Part.OffsetSurface(bs.Surface, 1.5).toShape(u0, u1, v0, v1)


def extruded_spline():
    """A spline profile extruded: a surface of linear extrusion."""
    spline = Part.BSplineCurve()
    spline.interpolate([V(0, 0, 0), V(10, 5, 0), V(20, -3, 0), V(30, 4, 0)])
    wire = Part.Wire([spline.toShape(), Part.makeLine(V(30, 4, 0), V(30, 20, 0)),
                      Part.makeLine(V(30, 20, 0), V(0, 20, 0)), Part.makeLine(V(0, 20, 0), V(0, 0, 0))])
    return Part.Face(wire).extrude(V(0, 0, 8))


def moved():
    """A cylinder placed by a location (not baked into its geometry)."""
    c = Part.makeCylinder(4, 10)
    c.Placement = FreeCAD.Placement(V(5, -3, 7), FreeCAD.Rotation(V(1, 1, 0), 33))
    return c


PARTS = {
    "filleted_box": filleted_box,
    "cylinder_with_holes": cylinder_with_holes,
    "revolved_profile": revolved_profile,
    "lofted": lofted,
    "sphere": sphere,
    "torus": torus,
    "island": island,
    "mirrored": mirrored,
    "offset_face": offset_face,
    "extruded_spline": extruded_spline,
    "moved": moved,
}
