"""UVs (and normals) of tessd's `subdivide` op against Blender's Subdivision Surface modifier,
i.e. OpenSubdiv's face-varying refinement (blender_ref.py runs the real Blender 5.0.1 `bpy`).

The op's contract: the cage's `uvs` (+ `uv_indices`, or one UV per corner) are refined with
`uv_interpolation`, one of

    "linear"                    Blender 'NONE'                                   FVAR_LINEAR_ALL
    "corners" (default)         Blender 'PRESERVE_CORNERS' (Blender's default)   FVAR_LINEAR_CORNERS_ONLY
    "corners-junctions"         'PRESERVE_CORNERS_AND_JUNCTIONS'                 FVAR_LINEAR_CORNERS_PLUS1
    "corners-junctions-concave" 'PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE'         FVAR_LINEAR_CORNERS_PLUS2
    "boundaries"                'PRESERVE_BOUNDARIES'                            FVAR_LINEAR_BOUNDARIES
    "smooth"                    'SMOOTH_ALL'                                     FVAR_LINEAR_NONE

and come back as `uvs` + `uv_indices` following the refined corners.

Vertex order is not part of the contract, so corners are matched: each of our refined vertices
to Blender's nearest (within 1e-5 x the bounding box; the map must be one to one), then each of
our corners' UV to the nearest UV among that Blender vertex's corners, and the other way round.
Every corner must agree within 1e-5 (UVs are in [0, 1]).
"""

from __future__ import annotations

import functools
import itertools
import sys
from pathlib import Path
from typing import List, Tuple

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "daemon"))

import locate  # noqa: E402
import tessd  # noqa: E402
from blender_ref import bbox_size, subdivide_with_blender  # noqa: E402

LEVELS = (1, 2, 3)
UV_TOL = 1e-5
POS_REL_TOL = 1e-5

#: Our `uv_interpolation` names and Blender's `uv_smooth` values.
UV_MODES = {
    "linear": "NONE",
    "corners": "PRESERVE_CORNERS",
    "corners-junctions": "PRESERVE_CORNERS_AND_JUNCTIONS",
    "corners-junctions-concave": "PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE",
    "boundaries": "PRESERVE_BOUNDARIES",
    "smooth": "SMOOTH_ALL",
}

Cage = Tuple[np.ndarray, List[List[int]], np.ndarray]  # positions, faces, per-corner UVs


# ---------------------------------------------------------------------------------------------
# Cages with UVs


@functools.lru_cache(maxsize=None)
def blender_primitive(kind: str) -> Cage:
    """A Blender primitive with the UV map Blender gives it: "cube" (the default cube's seamed
    cross layout), "monkey" (Suzanne: open, 4 boundary loops, triangles and quads, an unwrap
    with many islands), "cylinder" (6 sides with n-gon caps, seamed)."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    if kind == "cube":
        bpy.ops.mesh.primitive_cube_add()
    elif kind == "monkey":
        bpy.ops.mesh.primitive_monkey_add(calc_uvs=True)
    elif kind == "cylinder":
        bpy.ops.mesh.primitive_cylinder_add(vertices=6, end_fill_type="NGON", calc_uvs=True)
    else:
        raise ValueError(kind)
    me = bpy.context.active_object.data
    nv, nf, nl = len(me.vertices), len(me.polygons), len(me.loops)
    co = np.empty(nv * 3, dtype=np.float32)
    me.vertices.foreach_get("co", co)
    starts = np.empty(nf, dtype=np.int64)
    sizes = np.empty(nf, dtype=np.int64)
    me.polygons.foreach_get("loop_start", starts)
    me.polygons.foreach_get("loop_total", sizes)
    loop_verts = np.empty(nl, dtype=np.int64)
    me.loops.foreach_get("vertex_index", loop_verts)
    uv = np.empty(nl * 2, dtype=np.float32)
    me.uv_layers.active.data.foreach_get("uv", uv)
    order = np.concatenate([np.arange(s, s + n) for s, n in zip(starts, sizes)])
    faces, k = [], 0
    for n in sizes:
        faces.append(loop_verts[order[k:k + n]].tolist())
        k += n
    return co.reshape(-1, 3).astype(np.float64), faces, uv.reshape(-1, 2)[order].astype(np.float64)


def obj_with_uvs(name: str) -> Cage:
    """A shared OBJ with `vt` coordinates (faces `v/vt`)."""
    path = locate.shared_data() / "mesh" / name
    assert path.is_file(), f"shared test data not found: {path} (set TESSD_SHARED_DATA)"
    pos, tex, faces, corner_uv = [], [], [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            pos.append([float(x) for x in parts[1:4]])
        elif parts[0] == "vt":
            tex.append([float(x) for x in parts[1:3]])
        elif parts[0] == "f":
            face = []
            for token in parts[1:]:
                v, t = token.split("/")[:2]
                face.append(int(v) - 1)
                corner_uv.append(tex[int(t) - 1])
            faces.append(face)
    return np.array(pos), faces, np.array(corner_uv)


def ngon_cage() -> Cage:
    """An open hexagonal tube capped by one hexagon, one side a pentagon (an extra vertex on
    the open bottom rim); UVs: the hexagon its own island, the sides unrolled into a strip
    with one vertical seam, so the top vertices are junctions of three values."""
    n = 6
    ring = [(np.cos(2 * np.pi * k / n), np.sin(2 * np.pi * k / n)) for k in range(n)]
    pos = [[x, y, 0.0] for x, y in ring] + [[0.8 * x, 0.8 * y, 1.0 + 0.1 * x] for x, y in ring]
    pos.append([0.95, 0.55, -0.1])  # on side 0's bottom edge: a pentagon
    faces = [list(range(n, 2 * n))]
    uvs: List[List[float]] = [[0.25 + 0.2 * x, 0.75 + 0.2 * y] for x, y in ring]
    for k in range(n):
        a, b = k, (k + 1) % n
        face = [a, b, n + b, n + a]
        u0, u1 = k / n, (k + 1) / n
        corner = [[u0, 0.0], [u1, 0.0], [u1 * 0.9, 0.45], [u0 * 0.9, 0.45]]
        if k == 0:
            face.insert(1, 2 * n)
            corner.insert(1, [(u0 + u1) / 2, -0.05])
        faces.append(face)
        uvs.extend(corner)
    return np.array(pos), faces, np.array(uvs)


# ---------------------------------------------------------------------------------------------
# Running both and comparing


def subdivide_with_tessd(daemon, pos, faces, uvs, levels, mode, boundary="edge-only",
                         normals=True, creases=None):
    sizes = np.array([len(f) for f in faces], dtype=np.uint32)
    indices = np.array([i for f in faces for i in f], dtype=np.uint32)
    kwargs = {}
    if creases:
        kwargs["crease_edges"] = np.array([e for e, _ in creases], dtype=np.uint32).reshape(-1, 2)
        kwargs["crease_values"] = np.array([s for _, s in creases], dtype=np.float32)
    arrays = tessd.mesh_to_arrays(np.asarray(pos, dtype=np.float32), (indices, sizes),
                                  uvs=np.asarray(uvs, dtype=np.float32), **kwargs)
    params = {"scheme": "catmull-clark", "levels": levels, "boundary": boundary,
              "uv_interpolation": mode, "normals": normals}
    with tessd.Client(daemon.socket, timeout=300) as c:
        result, reply = c.call("subdivide", params, arrays)
    for name in ("positions", "face_indices", "uvs", "uv_indices"):
        assert name in reply, "the `subdivide` reply has no %r array (it has %s)" % (name, sorted(reply))
    return result, tessd.arrays_to_mesh(reply)


def nearest_index(a: np.ndarray, b: np.ndarray, radius: float) -> np.ndarray:
    """For each point of `a`, the index of the nearest point of `b` within `radius` (-1 if
    none), searching the 27 grid cells of size `radius` around it."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    origin = np.minimum(a.min(axis=0), b.min(axis=0)) - 2 * radius
    ca = np.floor((a - origin) / radius).astype(np.int64)
    cb = np.floor((b - origin) / radius).astype(np.int64)
    dims = np.maximum(ca.max(axis=0), cb.max(axis=0)) + 3

    def key(c):
        return (c[:, 0] * dims[1] + c[:, 1]) * dims[2] + c[:, 2]

    order = np.argsort(key(cb), kind="stable")
    kb = key(cb)[order]
    best = np.full(len(a), np.inf)
    out = np.full(len(a), -1, dtype=np.int64)
    for off in itertools.product((-1, 0, 1), repeat=3):
        k = key(ca + np.array(off))
        lo, hi = np.searchsorted(kb, k, "left"), np.searchsorted(kb, k, "right")
        for j in range(int((hi - lo).max()) if len(a) else 0):
            sel = np.nonzero(hi - lo > j)[0]
            cand = order[lo[sel] + j]
            d = np.linalg.norm(a[sel] - b[cand], axis=1)
            better = d < best[sel]
            best[sel[better]] = d[better]
            out[sel[better]] = cand[better]
    out[best > radius] = -1
    return out


def corner_uv_errors(pos_a, corner_vertex_a, uv_a, pos_b, corner_vertex_b, uv_b, vertex_map):
    """For each corner of a: the distance from its UV to the nearest UV among the corners of
    b's vertex `vertex_map[its vertex]`."""
    order = np.argsort(corner_vertex_b, kind="stable")
    counts = np.bincount(corner_vertex_b, minlength=len(pos_b))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    width = int(counts.max())
    table = np.full((len(pos_b), width, 2), np.nan)
    slot = np.arange(len(order)) - np.repeat(starts, counts)
    table[corner_vertex_b[order], slot] = uv_b[order]
    cand = table[vertex_map[corner_vertex_a]]  # [K, width, 2]
    d = np.linalg.norm(cand - uv_a[:, None, :], axis=2)
    return np.nanmin(d, axis=1)


def uv_error_vs_blender(daemon, cage: Cage, levels: int, mode: str, boundary="edge-only",
                        what="", creases=None) -> float:
    pos, faces, uvs = cage
    _, ours = subdivide_with_tessd(daemon, pos, faces, uvs, levels, mode, boundary,
                                   creases=creases)
    ref = subdivide_with_blender(pos, faces, levels, boundary=boundary, uv=uvs,
                                 uv_smooth=UV_MODES[mode], creases=creases)
    what = f"{what} level {levels} uv {mode} ({UV_MODES[mode]}, {boundary})"
    our_pos = np.asarray(ours.positions, dtype=np.float64).reshape(-1, 3)
    our_fi = np.asarray(ours.face_indices, dtype=np.int64).reshape(-1)
    our_uv = np.asarray(ours.uvs, dtype=np.float64).reshape(-1, 2)[
        np.asarray(ours.uv_indices, dtype=np.int64).reshape(-1)]
    assert (len(our_pos), len(np.asarray(ours.face_sizes).reshape(-1)), len(our_fi)) == \
        (ref.vertex_count, ref.face_count, len(ref.face_indices)), what
    radius = POS_REL_TOL * bbox_size(ref.positions)
    to_ref = nearest_index(our_pos, ref.positions, radius)
    assert (to_ref >= 0).all(), f"{what}: {(to_ref < 0).sum()} vertices without a Blender twin"
    assert len(np.unique(to_ref)) == len(to_ref), f"{what}: vertex matching is not one to one"
    to_ours = np.empty_like(to_ref)
    to_ours[to_ref] = np.arange(len(to_ref))
    err = max(
        corner_uv_errors(our_pos, our_fi, our_uv, ref.positions, ref.face_indices, ref.uvs,
                         to_ref).max(),
        corner_uv_errors(ref.positions, ref.face_indices, ref.uvs, our_pos, our_fi, our_uv,
                         to_ours).max())
    assert err <= UV_TOL, f"{what}: a corner's UV is {err:.3g} from Blender's (tolerance {UV_TOL})"
    return float(err)


# ---------------------------------------------------------------------------------------------
# Cases


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("mode", list(UV_MODES))
def test_default_cube_seamed_uvs(daemon, mode, levels):
    """Blender's default cube: a cross-shaped UV layout, 14 UV values, seams on 7 edges."""
    uv_error_vs_blender(daemon, blender_primitive("cube"), levels, mode, what="default cube")


def cube_creases(sharpness: float):
    """Creases on the default cube: the 4 edges around its top face (two of them UV seams) and
    one vertical edge (a seam); with sharpness < 10 they decay while UV spans cross them."""
    pos, faces, _ = blender_primitive("cube")

    def vid(p):
        return int(np.argmin(np.linalg.norm(pos - np.asarray(p, dtype=float), axis=1)))

    top = [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]
    edges = [(vid(top[k]), vid(top[(k + 1) % 4])) for k in range(4)]
    edges.append((vid((1, 1, 1)), vid((1, 1, -1))))
    return [(e, sharpness) for e in edges]


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("mode", list(UV_MODES))
@pytest.mark.parametrize("sharpness", [10.0, 2.0, 1.5, 0.5])
def test_creased_cube_uvs(daemon, sharpness, mode, levels):
    """Creases meeting UV seams: inside UV spans (semi-sharp ones decaying, blended by their
    fractional sharpness) and along seams."""
    uv_error_vs_blender(daemon, blender_primitive("cube"), levels, mode,
                        what=f"default cube, creases of sharpness {sharpness}",
                        creases=cube_creases(sharpness))


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("mode", list(UV_MODES))
@pytest.mark.parametrize("boundary", ["edge-only", "edge-and-corner"])
def test_suzanne_open_mesh_uvs(daemon, boundary, mode, levels):
    """Suzanne (Blender's monkey with its UVs): geometric boundaries, UV islands, junctions."""
    uv_error_vs_blender(daemon, blender_primitive("monkey"), levels, mode, boundary,
                        what="Suzanne")


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("mode", list(UV_MODES))
def test_ngon_cages(daemon, mode, levels):
    uv_error_vs_blender(daemon, blender_primitive("cylinder"), levels, mode,
                        what="hexagonal cylinder with n-gon caps")
    uv_error_vs_blender(daemon, ngon_cage(), levels, mode, boundary="edge-only",
                        what="open hexagon box")


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("mode", ["linear", "corners", "smooth"])
def test_spot_control_mesh_uvs(daemon, mode, levels):
    """spot_control_mesh.obj: a closed quad cage with its own seamed texture layout."""
    uv_error_vs_blender(daemon, obj_with_uvs("spot_control_mesh.obj"), levels, mode,
                        what="spot_control_mesh.obj")


def test_normals_are_unit_and_smooth(daemon):
    """The refined mesh's normals: one per corner, unit length, close to the faces' normals
    and equal across faces at a vertex (no creases here)."""
    pos, faces, uvs = blender_primitive("monkey")
    _, m = subdivide_with_tessd(daemon, pos, faces, uvs, 2, "corners")
    n = np.asarray(m.normals, dtype=np.float64).reshape(-1, 3)
    idx = np.asarray(m.normal_indices, dtype=np.int64).reshape(-1)
    fi = np.asarray(m.face_indices, dtype=np.int64).reshape(-1)
    assert len(idx) == len(fi)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    # One normal per vertex: corners of one vertex share it.
    first = {}
    for c, v in enumerate(fi.tolist()):
        assert first.setdefault(v, idx[c]) == idx[c]
    # Each face's normal (Newell) agrees with its corners' within 60 degrees.
    p = np.asarray(m.positions, dtype=np.float64).reshape(-1, 3)
    quads = fi.reshape(-1, 4)
    fn = np.cross(p[quads[:, 2]] - p[quads[:, 0]], p[quads[:, 3]] - p[quads[:, 1]])
    fn /= np.linalg.norm(fn, axis=1, keepdims=True)
    dots = (n[idx].reshape(-1, 4, 3) * fn[:, None, :]).sum(axis=2)
    assert dots.min() > 0.5, dots.min()
    _, plain = subdivide_with_tessd(daemon, pos, faces, uvs, 1, "corners", normals=False)
    assert plain.normals is None and plain.normal_indices is None


def test_bad_uv_interpolation_is_refused(daemon):
    pos, faces, uvs = blender_primitive("cube")
    with pytest.raises(tessd.TessdError) as e:
        subdivide_with_tessd(daemon, pos, faces, uvs, 1, "preserve-corners")
    assert e.value.code == "invalid_request" and "uv_interpolation" in e.value.message
