"""Checks of the daemon's `tessellate` output against OCP, shared by tests/brep (cadquery /
OCP 7.9) and tests/brep_build123d (build123d / OCP 8.0): OCP's area of each face, the mesh's
area per face group (one group per B-Rep face, in the document's face order), the open edges
left after welding equal positions, and whether a document describes a closed shell."""

from __future__ import annotations

from collections import Counter

import numpy as np
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from tessd.brep.ocp_compat import static

_surface_properties = static(BRepGProp, "SurfaceProperties")
_face = static(TopoDS, "Face")


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
