"""Checks of the daemon's `tessellate` output against OCP, shared by tests/brep (under OCP 7.9
and 8.0) and tests/brep_build123d (build123d / OCP 8.0): OCP's area of each face, the mesh's
area per face group (one group per B-Rep face, in the document's face order), the open edges
left after welding equal positions (count, length, where), whether a document describes a closed
shell, and how far each face's boundary vertices are in (u, v) from OCP's exact trims."""

from __future__ import annotations

from collections import Counter

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from tessd.brep.ocp_compat import static

_surface_properties = static(BRepGProp, "SurfaceProperties")
_face = static(TopoDS, "Face")
_edge = static(TopoDS, "Edge")


def face_area(face):
    """OCP's area of one face (`BRepGProp::SurfaceProperties`)."""
    props = GProp_GProps()
    _surface_properties(_face(face), props)
    return props.Mass()


def face_areas(shape):
    """OCP's area of each face, in the exporter's face order (TopExp_Explorer)."""
    out = []
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        out.append(face_area(exp.Current()))
        exp.Next()
    return out


def mesh_group_areas(arrays, groups):
    p = np.asarray(arrays["positions"], dtype=np.float64).reshape(-1, 3)
    tri = np.asarray(arrays["face_indices"], dtype=np.int64).reshape(-1, 3)
    g = np.asarray(arrays["face_groups"], dtype=np.int64)
    a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    return np.bincount(g, weights=area, minlength=groups)


def edge_uses(arrays):
    """How many triangles use each edge, after welding equal positions (degenerate triangles
    left out): {(a, b): count}."""
    p = np.asarray(arrays["positions"], dtype=np.float32).reshape(-1, 3)
    _, weld = np.unique(p, axis=0, return_inverse=True)
    weld = weld.reshape(-1)
    tri = weld[np.asarray(arrays["face_indices"], dtype=np.int64).reshape(-1, 3)]
    count = Counter()
    for t in tri:
        if t[0] == t[1] or t[1] == t[2] or t[0] == t[2]:
            continue
        for k in range(3):
            u, v = int(t[k]), int(t[(k + 1) % 3])
            count[(min(u, v), max(u, v))] += 1
    return count


def open_edges(arrays):
    return sum(1 for n in edge_uses(arrays).values() if n == 1)


def is_closed(doc):
    """Whether every edge with a curve is used by exactly two trims (a seam twice by one face)."""
    uses = Counter(t["edge"] for f in doc["faces"] for lp in f["loops"] for t in lp["edges"]
                   if t.get("edge") is not None)
    curved = [e["id"] for e in doc.get("edges") or [] if e.get("curve") is not None]
    return bool(curved) and all(uses[e] == 2 for e in curved)


def open_boundary(arrays):
    """The mesh's open edges after welding equal positions (used by one triangle): their
    count, total length, and midpoints ([n, 3])."""
    p = np.asarray(arrays["positions"], dtype=np.float32).reshape(-1, 3)
    uniq, weld = np.unique(p, axis=0, return_inverse=True)
    edges = [e for e, n in edge_uses(arrays).items() if n == 1]
    if not edges:
        return 0, 0.0, np.zeros((0, 3))
    e = np.asarray(edges, dtype=np.int64)
    a, b = uniq[e[:, 0]].astype(np.float64), uniq[e[:, 1]].astype(np.float64)
    return len(edges), float(np.linalg.norm(b - a, axis=1).sum()), 0.5 * (a + b)


def group_boundary_points(arrays, group):
    """The positions of the vertices on the boundary of one face group: edges used by one
    triangle of the group once its equal positions are welded (so a periodic face's seam, and
    the copies of a pole that the (u, v) triangulation has, are no boundary), triangles
    collapsed by the welding left out."""
    p = np.asarray(arrays["positions"], dtype=np.float32).reshape(-1, 3)
    _, weld = np.unique(p, axis=0, return_inverse=True)
    weld = weld.reshape(-1)
    tri = np.asarray(arrays["face_indices"], dtype=np.int64).reshape(-1, 3)
    tri = tri[np.asarray(arrays["face_groups"], dtype=np.int64) == group]
    first = {}  # welded index → one original vertex
    count = Counter()
    for t in tri.tolist():
        w = [int(weld[i]) for i in t]
        if w[0] == w[1] or w[1] == w[2] or w[0] == w[2]:
            continue
        for i, wi in zip(t, w):
            first.setdefault(wi, i)
        for k in range(3):
            u, v = w[k], w[(k + 1) % 3]
            count[(min(u, v), max(u, v))] += 1
    ids = sorted({first[i] for e, n in count.items() if n == 1 for i in e})
    return np.asarray(arrays["positions"], dtype=np.float64).reshape(-1, 3)[ids]


# Samples per pcurve for the trims' polyline in (u, v) (chords far below any ε_uv here).
PCURVE_SAMPLES = 2000


def _pcurve_polyline(face):
    """Dense samples of OCP's pcurves of `face` ([n, 2, 2] segments in OCP's (u, v))."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d
    from OCP.TopAbs import TopAbs_EDGE

    segs = []
    exp = TopExp_Explorer(face, TopAbs_EDGE)
    while exp.More():
        c = BRepAdaptor_Curve2d(_edge(exp.Current()), face)
        t = np.linspace(c.FirstParameter(), c.LastParameter(), PCURVE_SAMPLES)
        q = np.array([[c.Value(x).X(), c.Value(x).Y()] for x in t.tolist()])
        segs.append(np.stack([q[:-1], q[1:]], axis=1))
        exp.Next()
    return np.concatenate(segs) if segs else np.zeros((0, 2, 2))


def _distance_to(segs, p):
    a, b = segs[:, 0], segs[:, 1]
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


def boundary_uv_error(arrays, group, face, most=300):
    """How far the mesh's boundary vertices of face group `group` are, in (u, v), from the
    exact trims of `face` (the face whose (u, v) the document uses: tessd.brep.ocp's
    `document_face`, i.e. the NurbsConvert'ed face where the exporter converted it): each
    boundary vertex (`group_boundary_points`: a seam is welded, so no boundary; a degenerate
    edge is a point)
    (at most `most`, evenly strided) projected onto OCP's surface of the face
    (`ShapeAnalysis_Surface.ValueOfUV`), then its distance to OCP's pcurves of the face, densely
    sampled; u shifted by a period where the surface is periodic (a point on the seam projects
    to either side). A mirrored frame's u (2π − u) keeps distances, so OCP's (u, v) serve.
    Returns the largest distance."""
    from OCP.gp import gp_Pnt
    from OCP.ShapeAnalysis import ShapeAnalysis_Surface

    pts = group_boundary_points(arrays, group)
    if len(pts) == 0:
        return 0.0
    pts = pts[:: max(1, len(pts) // most)]
    surface = static(BRep_Tool, "Surface")(face)
    sas = ShapeAnalysis_Surface(surface)
    segs = _pcurve_polyline(face)
    shifts = [0.0]
    if surface.IsUPeriodic():
        shifts += [surface.UPeriod(), -surface.UPeriod()]
    worst = 0.0
    for p in pts.tolist():
        uv = sas.ValueOfUV(gp_Pnt(*p), 1e-9)
        d = min(_distance_to(segs, np.array([uv.X() + s, uv.Y()])) for s in shifts)
        worst = max(worst, d)
    return worst
