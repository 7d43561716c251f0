"""Triangle meshes between the daemon's arrays and FreeCAD's `Mesh.Mesh`.

- :func:`weld` makes the daemon's tessellation a shared-vertex mesh. `tessellate` discretises
  each B-Rep edge once and every face using it reuses those very points, but writes them once
  per face (docs/protocol.md, "tessellate": weld equal positions); merging bit-equal positions,
  and nothing else, gives the watertight mesh of a closed part without moving a vertex.
- :func:`build_mesh` makes a `Mesh.Mesh` with one segment per face group (a B-Rep face of the
  part, or a segment of the mesh the result came from). FreeCAD 0.20's `addFacets((points,
  facets), False)` takes `FreeCAD.Vector` points only (other items are skipped silently, and
  the facets then index past the end: a crash), and its False keeps every facet as given.
- :func:`daemon_arrays` is the other way: a mesh as the protocol's arrays (f32 positions,
  which is what the daemon computes with; FreeCAD stores f32 too).

Pure numpy and FreeCAD's Mesh module: safe on a worker thread (no document access).
"""

from typing import Any, Dict, Optional, Tuple

import FreeCAD
import Mesh
import numpy as np


def weld(positions: Any, face_indices: Any) -> Tuple[np.ndarray, np.ndarray]:
    """``(positions [V, 3] f64, triangles [F, 3] int64)`` with bit-equal positions merged, in
    order of first use. ``face_indices`` is flat, three per triangle."""
    pos = np.asarray(positions, dtype=np.float64).reshape(-1, 3) + 0.0  # -0.0 becomes 0.0
    if len(pos) == 0:
        return pos, np.zeros((0, 3), dtype=np.int64)
    _, first, inverse = np.unique(pos, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    index = rank[inverse.reshape(-1)]
    triangles = index[np.asarray(face_indices, dtype=np.int64)].reshape(-1, 3)
    return pos[first[order]], triangles


def triangles_of(arrays: Dict[str, Any], prefix: str = "") -> np.ndarray:
    """The triangles [F, 3] of a reply's mesh arrays (``prefix``: ``"lod1."`` and so on),
    checking that every face is a triangle (tessellate, simplify and lod give triangles)."""
    indices = np.asarray(arrays[prefix + "face_indices"], dtype=np.int64).reshape(-1)
    sizes = arrays.get(prefix + "face_sizes")
    if sizes is not None and len(sizes) and np.any(np.asarray(sizes) != 3):
        raise ValueError("the daemon returned faces that are not triangles")
    return indices.reshape(-1, 3)


def build_mesh(positions: Any, triangles: np.ndarray, groups: Optional[Any] = None,
               group_count: int = 0) -> Any:
    """A `Mesh.Mesh` of the triangles, with a segment per group ``0..group_count-1`` (in that
    order, empty ones included, so segment i is group i) when ``groups`` (per triangle) is given.
    Triangles of group ``group_count`` or above belong to no segment."""
    points = [FreeCAD.Vector(*p) for p in np.asarray(positions, dtype=np.float64).tolist()]
    facets = [tuple(t) for t in np.asarray(triangles, dtype=np.int64).tolist()]
    mesh = Mesh.Mesh()
    if facets:
        mesh.addFacets((points, facets), False)
    if groups is not None and group_count:
        groups = np.asarray(groups, dtype=np.int64).reshape(-1)
        order = np.argsort(groups, kind="stable")
        bounds = np.searchsorted(groups[order], np.arange(group_count + 1))
        for g in range(group_count):
            mesh.addSegment(order[bounds[g]:bounds[g + 1]].tolist())
    return mesh


def daemon_arrays(positions: Any, triangles: Any, groups: Optional[Any] = None) -> Dict[str, Any]:
    """The protocol's mesh arrays (positions f32, triangles as [F, 3] u32, ``face_groups``)."""
    out = {"positions": np.ascontiguousarray(np.asarray(positions, dtype=np.float32).reshape(-1, 3)),
           "face_indices": np.ascontiguousarray(np.asarray(triangles).reshape(-1, 3), dtype=np.uint32)}
    if groups is not None:
        out["face_groups"] = np.ascontiguousarray(groups, dtype=np.uint32)
    return out


def edge_use_counts(triangles: np.ndarray) -> np.ndarray:
    """How many triangles use each undirected edge (2 everywhere: a closed, manifold mesh)."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    return np.unique(edges, axis=0, return_counts=True)[1]


__all__ = ["build_mesh", "daemon_arrays", "edge_use_counts", "triangles_of", "weld"]
