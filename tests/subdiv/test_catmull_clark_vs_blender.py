"""tessd's Catmull-Clark subdivision (the `subdivide` protocol op) against Blender's
Subdivision Surface modifier, i.e. OpenSubdiv (blender_ref.py; the harness itself is checked
against OpenSubdiv's regression files in test_blender_reference.py).

The op's contract: params `{"scheme": "catmull-clark", "levels": N, "boundary":
"edge-only"|"edge-and-corner"}`; the mesh as arrays `positions` f32 [V, 3], `face_indices`
u32 [K] + `face_sizes` u32 [F], optional `crease_edges` u32 [E, 2] + `crease_values` f32 [E]
(OpenSubdiv sharpness); the reply's arrays hold the refined mesh the same way.

Each case runs levels 1, 2 and 3 and asserts equal vertex and face counts and that every vertex
of ours has a Blender vertex within 1e-5 x the bounding-box size and vice versa (order
independent: Blender's vertex order is not part of the contract).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "daemon"))

import locate  # noqa: E402
import tessd  # noqa: E402
from blender_ref import assert_same_points, read_obj, subdivide_with_blender  # noqa: E402
from tessd import TessdError  # noqa: E402

LEVELS = (1, 2, 3)
REL_TOL = 1e-5

Creases = Optional[Sequence[Tuple[Tuple[int, int], float]]]



# ---------------------------------------------------------------------------------------------
# Running both


def subdivide_with_tessd(daemon, positions, faces, levels: int, boundary: str,
                         creases: Creases = None) -> tessd.MeshArrays:
    """Our result through the `subdivide` op; a daemon without the op fails the test clearly."""
    sizes = np.array([len(f) for f in faces], dtype=np.uint32)
    indices = np.array([i for f in faces for i in f], dtype=np.uint32)
    kwargs = {}
    if creases:
        kwargs["crease_edges"] = np.array([e for e, _ in creases], dtype=np.uint32).reshape(-1, 2)
        kwargs["crease_values"] = np.array([s for _, s in creases], dtype=np.float32)
    arrays = tessd.mesh_to_arrays(np.asarray(positions, dtype=np.float32), (indices, sizes), **kwargs)
    params = {"scheme": "catmull-clark", "levels": levels, "boundary": boundary}
    missing = None
    with tessd.Client(daemon.socket, timeout=300) as c:
        try:
            _, reply = c.call("subdivide", params, arrays)
        except TessdError as e:
            if not (e.code == "invalid_request" and "unknown operation" in e.message):
                raise
            missing = e.message
    if missing is not None:
        pytest.fail("the daemon has no `subdivide` op (yet): %s" % missing, pytrace=False)
    for name in ("positions", "face_indices"):
        assert name in reply, "the `subdivide` reply has no %r array (it has %s)" % (name, sorted(reply))
    return tessd.arrays_to_mesh(reply)


def check_against_blender(daemon, positions, faces, levels: int, boundary: str = "edge-only",
                          creases: Creases = None, what: str = "") -> None:
    ours = subdivide_with_tessd(daemon, positions, faces, levels, boundary, creases)
    ref = subdivide_with_blender(positions, faces, levels, boundary=boundary, creases=creases)
    what = f"{what} level {levels} ({boundary})"
    got_pos = np.asarray(ours.positions, dtype=np.float64).reshape(-1, 3)
    assert (ours.vertex_count, ours.face_count) == (ref.vertex_count, ref.face_count), (
        f"{what}: (vertices, faces) ours {(ours.vertex_count, ours.face_count)}, "
        f"Blender {(ref.vertex_count, ref.face_count)}")
    sizes = np.asarray(ours.face_sizes).reshape(-1)
    assert int(sizes.sum()) == int(np.asarray(ours.face_indices).size), what
    assert set(sizes.tolist()) == {4}, f"{what}: Catmull-Clark output must be all quads"
    indices = np.asarray(ours.face_indices).reshape(-1)
    assert indices.size == 0 or int(indices.max()) < ours.vertex_count, what
    assert_same_points(got_pos, ref.positions, REL_TOL, what=what)


# ---------------------------------------------------------------------------------------------
# Meshes


def shared_mesh(name: str):
    path = locate.shared_data() / "mesh" / name
    assert path.is_file(), f"shared test data not found: {path} (set TESSD_SHARED_DATA)"
    return read_obj(path)


def grid(nx: int = 4, ny: int = 3) -> Tuple[np.ndarray, List[List[int]]]:
    """An open, slightly warped nx x ny quad grid (one boundary loop, 4 valence-2 corners)."""
    pos = [[x, y, 0.1 * np.sin(x + 2 * y)] for y in range(ny + 1) for x in range(nx + 1)]
    faces = [[y * (nx + 1) + x, y * (nx + 1) + x + 1, (y + 1) * (nx + 1) + x + 1, (y + 1) * (nx + 1) + x]
             for y in range(ny) for x in range(nx)]
    return np.array(pos, dtype=float), faces


def prism(n: int) -> Tuple[np.ndarray, List[List[int]]]:
    """A closed prism over a regular n-gon: two n-gon caps and n quads."""
    ring = [(np.cos(2 * np.pi * k / n), np.sin(2 * np.pi * k / n)) for k in range(n)]
    pos = [[x, y, -0.7] for x, y in ring] + [[x, y, 0.7] for x, y in ring]
    faces = [list(range(n))[::-1], list(range(n, 2 * n))]
    faces += [[k, (k + 1) % n, n + (k + 1) % n, n + k] for k in range(n)]
    return np.array(pos, dtype=float), faces


def box(n: int, size=(1.0, 0.8, 0.6)) -> Tuple[np.ndarray, List[List[int]]]:
    """A closed box [-sx, sx] x [-sy, sy] x [-sz, sz] with n x n quads on each side, outward."""
    index = {}
    pos: List[List[float]] = []

    def vid(i, j, k):
        key = (i, j, k)
        if key not in index:
            index[key] = len(pos)
            pos.append([size[0] * (2 * i / n - 1), size[1] * (2 * j / n - 1), size[2] * (2 * k / n - 1)])
        return index[key]

    faces = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3  # e_u x e_v = e_axis
        for side in (0, n):
            for a in range(n):
                for b in range(n):
                    quad = []
                    for da, db in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        c = [0, 0, 0]
                        c[axis], c[u], c[v] = side, a + da, b + db
                        quad.append(vid(*c))
                    faces.append(quad if side == n else quad[::-1])
    return np.array(pos, dtype=float), faces


def edge_between(pos: np.ndarray, p, q) -> Tuple[int, int]:
    """The vertex pair of the points nearest to p and q."""
    a = int(np.argmin(np.linalg.norm(pos - np.asarray(p, dtype=float), axis=1)))
    b = int(np.argmin(np.linalg.norm(pos - np.asarray(q, dtype=float), axis=1)))
    return a, b


def cube_creases(sharpness: float) -> Tuple[np.ndarray, List[List[int]], list]:
    """A cube with the 4 edges around its top face and one vertical edge creased: top corners
    get 2 or 3 creased edges (crease and corner rules), the bottom one of the vertical edge 1
    (a dart)."""
    pos, faces = box(1, size=(1.0, 1.0, 1.0))
    top = [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]
    edges = [edge_between(pos, top[k], top[(k + 1) % 4]) for k in range(4)]
    edges.append(edge_between(pos, (1, 1, 1), (1, 1, -1)))
    return pos, faces, [(e, sharpness) for e in edges]


def interior_crease(sharpness: float) -> Tuple[np.ndarray, List[List[int]], list]:
    """A warped 4x4-per-side box with a crease path of 3 edges across its top face that starts
    and ends at interior vertices of that face (darts at both ends)."""
    n = 4
    pos, faces = box(n)
    sx, sy, sz = 1.0, 0.8, 0.6
    # Grid points (i, j) of the top face (z = +sz), i, j in 0..n; 1..n-1 are interior. The path
    # (1,2)-(2,2)-(3,2)-(3,3) bends once and both its ends are interior vertices.
    def p(i, j):
        return (sx * (2 * i / n - 1), sy * (2 * j / n - 1), sz)
    path = [p(1, 2), p(2, 2), p(3, 2), p(3, 3)]
    edges = [edge_between(pos, path[k], path[k + 1]) for k in range(len(path) - 1)]
    # Warp it so that the top face is not flat (on a flat regular grid the crease rules and the
    # smooth rules give the same points, and a crease would go unnoticed).
    pos = pos + 0.08 * np.sin(np.array([2.0, 3.0, 5.0]) * pos[:, [1, 2, 0]] + 0.3)
    return pos, faces, [(e, sharpness) for e in edges]


# ---------------------------------------------------------------------------------------------
# Cases


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("name", ["spot_control_mesh.obj", "quadknot.obj"])
def test_closed_shared_meshes(daemon, name, levels):
    pos, faces = shared_mesh(name)
    check_against_blender(daemon, pos, faces, levels, what=name)


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("boundary", ["edge-only", "edge-and-corner"])
def test_suzanne_with_boundaries(daemon, boundary, levels):
    """suzanne.obj is open: 4 boundary loops (42 boundary edges), triangles and quads."""
    pos, faces = shared_mesh("suzanne.obj")
    check_against_blender(daemon, pos, faces, levels, boundary, what="suzanne.obj")


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("boundary", ["edge-only", "edge-and-corner"])
def test_open_grid(daemon, boundary, levels):
    pos, faces = grid()
    check_against_blender(daemon, pos, faces, levels, boundary, what="open 4x3 grid")


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("n", [5, 6])
def test_ngon_prism(daemon, n, levels):
    pos, faces = prism(n)
    check_against_blender(daemon, pos, faces, levels, what=f"{n}-gon prism")


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("sharpness", [10.0, 2.0, 1.5], ids=["infinite", "integer2", "fractional1.5"])
def test_creased_cube(daemon, sharpness, levels):
    pos, faces, creases = cube_creases(sharpness)
    check_against_blender(daemon, pos, faces, levels, creases=creases,
                          what=f"cube with creases of sharpness {sharpness}")


@pytest.mark.parametrize("levels", LEVELS)
@pytest.mark.parametrize("sharpness", [10.0, 1.5], ids=["infinite", "fractional1.5"])
def test_crease_ending_inside_the_mesh(daemon, sharpness, levels):
    pos, faces, creases = interior_crease(sharpness)
    check_against_blender(daemon, pos, faces, levels, creases=creases,
                          what=f"box with an interior crease path of sharpness {sharpness}")
