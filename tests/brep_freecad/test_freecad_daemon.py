"""FreeCAD's documents through the daemon: every shared part and built part, exported by
python/tessd/brep/freecad.py, is accepted by `brep.load` (the Rust validator of core/brep, an
independent reader of the format) with its counts equal to FreeCAD's own (faces, faces per
surface type, reversed faces, loops, holes, edges, degenerate edges), and tessellated by
`tessellate` to a mesh whose area is FreeCAD's `shape.Area` within 0.5 % (each face's, too, for
the built parts). System Python (conftest.py); the `daemon` fixture is the root conftest's."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tessd
from fc_checks import boundary_edges, exported, face_edges, indirect_frame, shared_files, surface_counts
from fc_parts import PARTS

CASES = shared_files() + sorted(PARTS)
# Faces below this share of the part's area are left out of the per-face comparison (their
# relative error is dominated by the edge discretisation they share with big neighbours).
SMALL_FACE = 1e-3


def _reversed_count(shape):
    """Faces whose normal is -∂S/∂u × ∂S/∂v in the format: FreeCAD's reversed faces, except
    where a left-handed frame (mirrored by the exporter) turns that round."""
    n = 0
    for f in shape.Faces:
        rev = f.Orientation == "Reversed"
        s = f.Surface if type(f.Surface).__name__ in ("Cylinder", "Cone", "Sphere", "Toroid") else None
        n += rev != (s is not None and indirect_frame(s))
    return n


@pytest.mark.parametrize("name", CASES)
def test_load(daemon, name):
    shape, doc = exported(name)
    with tessd.Client(daemon.socket, timeout=120) as c:
        result = c.call("brep.load", {"brep": doc})[0]
    faces = shape.Faces
    assert result["faces"] == list(range(1, len(faces) + 1))
    stats = result["stats"]
    assert stats["faces"] == len(faces)
    by_surface = {k: v for k, v in stats["faces_by_surface"].items() if v}
    assert by_surface == dict(surface_counts(shape)), (by_surface, surface_counts(shape))
    assert stats["reversed_faces"] == _reversed_count(shape)
    wires = [len([w for w in f.Wires if boundary_edges(w)]) for f in faces]
    assert stats["loops"] == sum(wires)
    assert stats["holes"] == sum(max(n - 1, 0) for n in wires)
    edges = face_edges(shape)
    assert stats["edges"] == len(edges) == len(result["edges"])
    assert stats["edges_by_curve"].get("none", 0) == sum(e.Degenerated for e in edges)
    print(name, stats)


def _mesh_areas(arrays, groups):
    """The mesh's area per face group (the B-Rep face at that index of the document)."""
    corners = np.asarray(arrays["positions"], dtype=np.float64).reshape(-1, 3)[
        np.asarray(arrays["face_indices"], dtype=np.int64).reshape(-1, 3)]  # [triangles, 3, 3]
    doubled = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    return np.bincount(np.asarray(arrays["face_groups"], dtype=np.int64), weights=0.5 * doubled,
                       minlength=groups)


@pytest.mark.parametrize("name", CASES)
def test_tessellated_area(daemon, name):
    shape, doc = exported(name)
    total = shape.Area
    tolerance = 2e-4 * math.sqrt(total)
    with tessd.Client(daemon.socket, timeout=300) as c:
        result, arrays = c.call("tessellate", {"brep": doc, "tolerance": tolerance, "angle": 0.1})
    assert result["faces"] == len(doc["faces"])
    assert result["empty_faces"] == [], result["empty_faces"]
    areas = _mesh_areas(arrays, len(doc["faces"]))
    rel = abs(areas.sum() - total) / total
    print(f"{name}: {result['triangles']} triangles, area {areas.sum():.6g} vs FreeCAD {total:.6g} "
          f"({100 * rel:.3f} %)")
    assert rel < 0.005, f"{name}: mesh area {areas.sum()} vs FreeCAD's {total}"
    if name in PARTS:
        for f, mine in zip(doc["faces"], areas):
            theirs = shape.Faces[f["id"] - 1].Area
            if theirs >= SMALL_FACE * total:
                assert abs(mine - theirs) / theirs < 0.005, f"{name}: face {f['id']}: {mine} vs {theirs}"
