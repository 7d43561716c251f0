"""Reference Catmull-Clark subdivision by Blender's Subdivision Surface modifier (OpenSubdiv),
through the real `bpy` package (Blender as a Python module, pinned in
python/requirements-test.txt), plus the small helpers the subdivision tests share: an OBJ
reader and an order-independent comparison of two vertex sets.

How our parameters map onto Blender (checked against Blender's source, blender/blender):

- scheme: `subdivision_type = 'CATMULL_CLARK'` -> OpenSubdiv `SCHEME_CATMARK`
  (`SIMPLE` would be `SCHEME_BILINEAR`; source/blender/blenkernel/BKE_subdiv.hh, SubdivSettings).
- boundary: the modifier's `boundary_smooth`
      'ALL'              -> SUBDIV_VTX_BOUNDARY_EDGE_ONLY       -> our "edge-only"
      'PRESERVE_CORNERS' -> SUBDIV_VTX_BOUNDARY_EDGE_AND_CORNER -> our "edge-and-corner"
  (blenkernel/intern/subdiv.cc, `vtx_boundary_interpolation_from_subsurf`; Cycles and the USD
  exporter map the same two values to edgeOnly / edgeAndCorner).
- creases: Blender stores an edge crease c in [0, 1] in the float edge attribute
  `crease_edge`; with `use_creases` its OpenSubdiv converter passes
      sharpness = crease_to_sharpness(c) = c * c * 10.0f
  (blenkernel/intern/subdiv_inline.hh, `crease_to_sharpness`, and its inverse
  `sharpness_to_crease(s) = sqrt(s * 0.1f)`; used by `get_edge_sharpness` in
  blenkernel/intern/subdiv_converter_mesh.cc). Our crease values are OpenSubdiv sharpness, so
  we store c = sqrt(s / 10), clamped to 1 (s >= 10 is OpenSubdiv's SHARPNESS_INFINITE = 10),
  nudged up by float32 ulps until Blender's float32 c*c*10 is >= s (so an integer sharpness
  stays integral and does not become 1.9999999). The creasing method is CREASE_UNIFORM
  (intern/opensubdiv, `getSdcOptions`: `options.SetCreasingMethod(Options::CREASE_UNIFORM)`).
  Loose edges (none in our meshes) would make their vertices infinitely sharp.
- levels: `levels = render_levels = N` (uniform refinement N times); `use_limit_surface =
  False` so the refined vertices are the level-N control points, not pushed to the limit;
  `quality` (OpenSubdiv isolation level) at its maximum, which only matters for the limit
  surface but is pinned so nothing adaptive creeps in.
- UVs (face-varying): the modifier's `uv_smooth` enum, as in subdiv.cc
  `fvar_interpolation_from_uv_smooth`: 'NONE' -> FVAR_LINEAR_ALL, 'PRESERVE_CORNERS' ->
  CORNERS_ONLY, 'PRESERVE_CORNERS_AND_JUNCTIONS' -> CORNERS_PLUS1,
  'PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE' -> CORNERS_PLUS2, 'PRESERVE_BOUNDARIES' ->
  FVAR_LINEAR_BOUNDARIES, 'SMOOTH_ALL' -> FVAR_LINEAR_NONE.

Blender keeps positions in float32, so results agree with a float64 implementation to ~1e-7
relative; the tests compare at 1e-5 of the bounding-box size.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

#: OpenSubdiv's Sdc::Crease::SHARPNESS_INFINITE.
SHARPNESS_INFINITE = 10.0

BOUNDARY_SMOOTH = {"edge-only": "ALL", "edge-and-corner": "PRESERVE_CORNERS"}
UV_SMOOTH = ("NONE", "PRESERVE_CORNERS", "PRESERVE_CORNERS_AND_JUNCTIONS",
             "PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE", "PRESERVE_BOUNDARIES", "SMOOTH_ALL")


def _bpy():
    try:
        import bpy  # noqa: F401
    except ImportError as e:  # pragma: no cover - setup problem, reported as a failure
        raise AssertionError(
            "the Blender reference needs `bpy` (pinned in python/requirements-test.txt; "
            "run scripts/setup.sh): %s" % e) from e
    return bpy


def blender_version() -> str:
    return _bpy().app.version_string


# ---------------------------------------------------------------------------------------------
# Crease mapping


def crease_to_sharpness(crease: float) -> float:
    """Blender's mapping, as float32 arithmetic like its C++ (`crease * crease * 10.0f`)."""
    c = np.float32(crease)
    return float(np.float32(np.float32(c * c) * np.float32(10.0)))


def sharpness_to_crease(sharpness: float) -> float:
    """The Blender crease value (a float32) whose sharpness is `sharpness` (>= it, by <= 1 ulp
    of the crease): the inverse of :func:`crease_to_sharpness`."""
    s = float(sharpness)
    if not s > 0.0:
        return 0.0
    if s >= SHARPNESS_INFINITE:
        return 1.0
    c = np.float32(math.sqrt(s / 10.0))
    while crease_to_sharpness(c) < s and c < 1.0:
        c = np.nextafter(c, np.float32(2.0))
    return float(c)


# ---------------------------------------------------------------------------------------------
# The reference


class Subdivided(NamedTuple):
    """A refined mesh: positions [V, 3] f64, face_sizes [F], face_indices [K], and per-corner
    uvs [K, 2] when UVs were given (else None)."""

    positions: np.ndarray
    face_sizes: np.ndarray
    face_indices: np.ndarray
    uvs: Optional[np.ndarray] = None

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def face_count(self) -> int:
        return int(self.face_sizes.shape[0])


def subdivide_with_blender(positions: Any, faces: Sequence[Sequence[int]], levels: int,
                           boundary: str = "edge-only",
                           creases: Optional[Sequence[Tuple[Tuple[int, int], float]]] = None,
                           uv: Any = None, uv_smooth: str = "PRESERVE_BOUNDARIES") -> Subdivided:
    """Catmull-Clark subdivision of a polygon mesh by Blender's Subdivision Surface modifier.

    - positions: [V, 3]; faces: lists of vertex indices (any sizes >= 3).
    - levels: uniform refinement steps (1..6 in Blender's UI; the modifier allows more).
    - boundary: "edge-only" or "edge-and-corner" (see the module docstring).
    - creases: ((a, b), sharpness) with OpenSubdiv sharpness; each (a, b) must be an edge of a
      face.
    - uv: per-corner UVs [K, 2] in the order of the flattened faces; uv_smooth: the modifier's
      `uv_smooth` value.

    Runs in a fresh empty Blender session (factory settings), so calls do not interfere.
    """
    bpy = _bpy()
    if boundary not in BOUNDARY_SMOOTH:
        raise ValueError("boundary must be one of %s, got %r" % (sorted(BOUNDARY_SMOOTH), boundary))
    if uv_smooth not in UV_SMOOTH:
        raise ValueError("uv_smooth must be one of %s, got %r" % (UV_SMOOTH, uv_smooth))
    pos = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    faces = [[int(i) for i in f] for f in faces]

    bpy.ops.wm.read_factory_settings(use_empty=True)
    # No GPU subdivision (headless has no GPU anyway): the CPU OpenSubdiv path is the reference.
    bpy.context.preferences.system.use_gpu_subdivision = False

    mesh = bpy.data.meshes.new("cage")
    # from_pydata with no edges derives the edges from the faces (mesh.update(calc_edges)).
    mesh.from_pydata(pos.tolist(), [], faces)
    mesh.update()

    if creases:
        edge_of = {}
        verts = np.empty(len(mesh.edges) * 2, dtype=np.int64)
        mesh.edges.foreach_get("vertices", verts)
        for e, (a, b) in enumerate(verts.reshape(-1, 2).tolist()):
            edge_of[(min(a, b), max(a, b))] = e
        values = np.zeros(len(mesh.edges), dtype=np.float32)
        for (a, b), sharpness in creases:
            key = (min(a, b), max(a, b))
            if key not in edge_of:
                raise ValueError("crease on (%d, %d), which is not an edge of the mesh" % key)
            values[edge_of[key]] = sharpness_to_crease(sharpness)
        # Blender 4.0+: edge creases are the generic float edge attribute "crease_edge".
        attr = mesh.attributes.get("crease_edge") or mesh.attributes.new("crease_edge", "FLOAT", "EDGE")
        attr.data.foreach_set("value", values)

    if uv is not None:
        uvs = np.asarray(uv, dtype=np.float32).reshape(-1, 2)
        if uvs.shape[0] != len(mesh.loops):
            raise ValueError("uv: %d rows for %d face corners" % (uvs.shape[0], len(mesh.loops)))
        layer = mesh.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", uvs.reshape(-1))

    obj = bpy.data.objects.new("cage", mesh)
    bpy.context.scene.collection.objects.link(obj)

    mod = obj.modifiers.new("subsurf", "SUBSURF")
    mod.subdivision_type = "CATMULL_CLARK"
    mod.levels = levels            # the viewport level (what a background depsgraph evaluates)
    mod.render_levels = levels     # the render level, kept equal
    mod.use_limit_surface = False  # level-N control points, not limit positions
    mod.use_creases = True         # read crease_edge (and crease_vert)
    mod.boundary_smooth = BOUNDARY_SMOOTH[boundary]
    mod.quality = mod.bl_rna.properties["quality"].hard_max  # 10
    mod.uv_smooth = uv_smooth
    mod.use_custom_normals = False

    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    out = evaluated.to_mesh()
    try:
        n_v, n_f, n_l = len(out.vertices), len(out.polygons), len(out.loops)
        co = np.empty(n_v * 3, dtype=np.float32)
        out.vertices.foreach_get("co", co)
        sizes = np.empty(n_f, dtype=np.int64)
        out.polygons.foreach_get("loop_total", sizes)
        starts = np.empty(n_f, dtype=np.int64)
        out.polygons.foreach_get("loop_start", starts)
        loop_verts = np.empty(n_l, dtype=np.int64)
        out.loops.foreach_get("vertex_index", loop_verts)
        order = np.concatenate([np.arange(s, s + n) for s, n in zip(starts, sizes)]) if n_f else \
            np.zeros(0, dtype=np.int64)
        face_indices = loop_verts[order]
        out_uv = None
        if uv is not None:
            flat = np.empty(n_l * 2, dtype=np.float32)
            out.uv_layers[0].data.foreach_get("uv", flat)
            out_uv = flat.reshape(-1, 2)[order].astype(np.float64)
        return Subdivided(co.reshape(-1, 3).astype(np.float64), sizes, face_indices, out_uv)
    finally:
        evaluated.to_mesh_clear()


# ---------------------------------------------------------------------------------------------
# Helpers shared by the subdivision tests


def read_obj(path: Any) -> Tuple[np.ndarray, List[List[int]]]:
    """Positions [V, 3] f64 and faces (0-based vertex indices), by the daemon tests' reader."""
    from daemon_util import read_obj as read_positions_and_faces

    positions, faces = read_positions_and_faces(Path(path))
    return np.asarray(positions, dtype=np.float64).reshape(-1, 3), faces


def bbox_size(points: np.ndarray) -> float:
    """The diagonal of the bounding box."""
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def _brute_nearest(a: np.ndarray, b: np.ndarray, chunk: int = 256) -> np.ndarray:
    out = np.empty(len(a))
    b2 = (b * b).sum(axis=1)
    for s in range(0, len(a), chunk):
        p = a[s:s + chunk]
        d2 = (p * p).sum(axis=1)[:, None] - 2.0 * p @ b.T + b2[None, :]
        out[s:s + chunk] = np.sqrt(np.maximum(d2.min(axis=1), 0.0))
    return out


def nearest_distances(a: np.ndarray, b: np.ndarray, radius: float,
                      exact_misses: int = 64) -> np.ndarray:
    """For each point of `a`, the distance to the nearest point of `b` when that is within
    `radius` (a uniform grid of cell `radius`: the 27 cells around each point are searched).
    Points with nothing within `radius` get their exact nearest distance (brute force) for the
    first `exact_misses` of them and +inf after that: a failing comparison stays fast."""
    a = np.asarray(a, dtype=np.float64).reshape(-1, 3)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 3)
    out = np.full(len(a), np.inf)
    if len(a) == 0 or len(b) == 0:
        return out
    cell = float(radius)
    assert cell > 0
    origin = np.minimum(a.min(axis=0), b.min(axis=0)) - 2 * cell
    ca = np.floor((a - origin) / cell).astype(np.int64)
    cb = np.floor((b - origin) / cell).astype(np.int64)
    dims = np.maximum(ca.max(axis=0), cb.max(axis=0)) + 3
    assert float(dims[0]) * float(dims[1]) * float(dims[2]) < 2.0 ** 62, "radius too small"

    def key(c):
        return (c[:, 0] * dims[1] + c[:, 1]) * dims[2] + c[:, 2]

    kb = key(cb)
    order = np.argsort(kb, kind="stable")
    kb_sorted = kb[order]
    for off in itertools.product((-1, 0, 1), repeat=3):
        k = key(ca + np.array(off, dtype=np.int64))
        lo = np.searchsorted(kb_sorted, k, side="left")
        hi = np.searchsorted(kb_sorted, k, side="right")
        count = hi - lo
        for j in range(int(count.max()) if len(count) else 0):
            sel = np.nonzero(count > j)[0]
            d = np.linalg.norm(a[sel] - b[order[lo[sel] + j]], axis=1)
            out[sel] = np.minimum(out[sel], d)
    out[out > radius] = np.inf  # a hit in a neighbouring cell may still be beyond radius
    misses = np.nonzero(np.isinf(out))[0][:exact_misses]
    if len(misses):
        out[misses] = _brute_nearest(a[misses], b)
    return out


def assert_same_points(ours: np.ndarray, ref: np.ndarray, rel_tol: float = 1e-5,
                       what: str = "") -> None:
    """Every point of `ours` has a point of `ref` within rel_tol x bbox size, and vice versa,
    and the counts are equal."""
    ours = np.asarray(ours, dtype=np.float64).reshape(-1, 3)
    ref = np.asarray(ref, dtype=np.float64).reshape(-1, 3)
    assert len(ours) == len(ref), "%s: %d vertices, the reference has %d" % (what, len(ours), len(ref))
    tol = rel_tol * bbox_size(ref)
    for name, x, y in (("ours->ref", ours, ref), ("ref->ours", ref, ours)):
        d = nearest_distances(x, y, tol)
        worst = int(np.argmax(d))
        bad = int((d > tol).sum())
        finite = d[np.isfinite(d)]
        assert bad == 0, ("%s: %s: %d of %d vertices have no counterpart within %.3g (%g x bbox "
                          "size); e.g. %s at %.3g; largest measured distance %.3g"
                          % (what, name, bad, len(d), tol, rel_tol, x[worst].tolist(), d[worst],
                             finite.max() if len(finite) else float("nan")))
