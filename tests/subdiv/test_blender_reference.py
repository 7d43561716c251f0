"""Checks of the Blender reference harness itself (blender_ref.py), independent of tessd:
Blender's Subdivision Surface modifier must reproduce OpenSubdiv's own regression outputs
(shared/data/subdiv, OpenSubdiv's Hbr baselines) and known answers for creases, so that a
mismatch in test_catmull_clark_vs_blender.py is ours, not the harness's.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import locate
from blender_ref import (assert_same_points, blender_version, crease_to_sharpness, read_obj,
                         sharpness_to_crease, subdivide_with_blender)

SUBDIV = locate.shared_data() / "subdiv"


def test_bpy_is_blender_5():
    assert blender_version().startswith("5.0."), blender_version()


@pytest.mark.parametrize("name, boundary", [("catmark_cube", "edge-only"),
                                            ("catmark_edgecorner", "edge-and-corner")])
@pytest.mark.parametrize("start", [0, 1])
def test_one_blender_level_reproduces_opensubdiv(name, boundary, start):
    """levelK -> level(K+1) of OpenSubdiv's regression sequence, order-independently."""
    src = SUBDIV / f"{name}_level{start}.obj"
    ref = SUBDIV / f"{name}_level{start + 1}.obj"
    assert src.is_file() and ref.is_file(), f"shared test data missing: {src}, {ref}"
    pos, faces = read_obj(src)
    ref_pos, ref_faces = read_obj(ref)
    got = subdivide_with_blender(pos, faces, 1, boundary=boundary)
    assert got.face_count == len(ref_faces)
    assert_same_points(got.positions, ref_pos, 1e-5, what=f"{src.name} -> {ref.name}")


def test_two_blender_levels_reproduce_opensubdiv():
    pos, faces = read_obj(SUBDIV / "catmark_cube_level0.obj")
    ref_pos, ref_faces = read_obj(SUBDIV / "catmark_cube_level2.obj")
    got = subdivide_with_blender(pos, faces, 2)
    assert got.face_count == len(ref_faces)
    assert_same_points(got.positions, ref_pos, 1e-5, what="catmark_cube level0 -> level2")


def test_boundary_option_reaches_blender():
    """The two boundary rules differ on the edge-corner shape (valence-2 corners)."""
    pos, faces = read_obj(SUBDIV / "catmark_edgecorner_level0.obj")
    a = subdivide_with_blender(pos, faces, 1, boundary="edge-only").positions
    b = subdivide_with_blender(pos, faces, 1, boundary="edge-and-corner").positions
    assert a.shape == b.shape
    assert np.abs(a - b).max() > 1e-3


# ---------------------------------------------------------------------------------------------
# Creases: the sharpness <-> Blender crease mapping and known answers on a cube


def test_crease_mapping_round_trips():
    for s in (0.1, 0.5, 1.0, 1.5, 2.0, 3.0, 4.5, 9.0):
        c = sharpness_to_crease(s)
        assert 0 < c < 1
        got = crease_to_sharpness(c)
        assert s <= got <= s * (1 + 1e-6), (s, c, got)
    assert sharpness_to_crease(10.0) == 1.0 and crease_to_sharpness(1.0) == 10.0
    assert sharpness_to_crease(25.0) == 1.0
    assert sharpness_to_crease(0.0) == 0.0


def cube():
    """[-1, 1]^3, vertex index = (x>0) + 2 (y>0) + 4 (z>0), quads outward."""
    pos = np.array([[x, y, z] for z in (-1.0, 1.0) for y in (-1.0, 1.0) for x in (-1.0, 1.0)])
    faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    return pos, faces


def cube_edges(faces):
    return sorted({(min(a, b), max(a, b)) for f in faces for a, b in zip(f, f[1:] + f[:1])})


def test_smooth_cube_known_answer():
    """Level 1 of the smooth cube: corners at 5/9, edge points at 3/4, face points on faces."""
    pos, faces = cube()
    got = subdivide_with_blender(pos, faces, 1)
    expected = expected_cube_level1(corner=5 / 9, edge=3 / 4)
    assert_same_points(got.positions, expected, 1e-6, what="smooth cube")


def expected_cube_level1(corner, edge):
    pts = [[sx * corner, sy * corner, sz * corner] for sx, sy, sz in itertools.product((-1, 1), repeat=3)]
    for axis in range(3):  # edge points: the coordinate along the edge is 0
        for s1, s2 in itertools.product((-1, 1), repeat=2):
            p = [0.0, 0.0, 0.0]
            others = [i for i in range(3) if i != axis]
            p[others[0]], p[others[1]] = s1 * edge, s2 * edge
            pts.append(p)
    for axis in range(3):  # face points
        for s in (-1, 1):
            p = [0.0, 0.0, 0.0]
            p[axis] = s
            pts.append(p)
    return np.array(pts)


@pytest.mark.parametrize("sharpness, corner, edge", [
    (10.0, 1.0, 1.0),      # infinitely sharp: a bilinear split of the cube
    (1.0, 1.0, 1.0),       # sharpness 1: sharp for exactly one level
    (0.5, 7 / 9, 7 / 8),   # fractional: halfway between the smooth and the sharp rules
])
def test_creased_cube_known_answer(sharpness, corner, edge):
    pos, faces = cube()
    creases = [(e, sharpness) for e in cube_edges(faces)]
    got = subdivide_with_blender(pos, faces, 1, creases=creases)
    assert_same_points(got.positions, expected_cube_level1(corner, edge), 1e-6,
                       what=f"cube, all edges sharpness {sharpness}")


def test_integer_sharpness_holds_for_that_many_levels():
    """Sharpness 2 on every edge: two levels stay exactly on the cube's surface; the third
    level (smooth) does not."""
    pos, faces = cube()
    creases = [(e, 2.0) for e in cube_edges(faces)]
    two = subdivide_with_blender(pos, faces, 2, creases=creases).positions
    assert np.abs(np.abs(two).max(axis=1) - 1.0).max() < 1e-6
    three = subdivide_with_blender(pos, faces, 3, creases=creases).positions
    assert np.abs(np.abs(three).max(axis=1) - 1.0).max() > 1e-3


def test_counts_of_an_ngon_cage():
    """A pentagonal prism: each n-gon becomes n quads (Catmull-Clark's first step)."""
    n = 5
    ring = [[np.cos(2 * np.pi * k / n), np.sin(2 * np.pi * k / n)] for k in range(n)]
    pos = [[x, y, -1.0] for x, y in ring] + [[x, y, 1.0] for x, y in ring]
    faces = [list(range(n))[::-1], list(range(n, 2 * n))]
    faces += [[k, (k + 1) % n, n + (k + 1) % n, n + k] for k in range(n)]
    got = subdivide_with_blender(pos, faces, 1)
    v, e, f = 2 * n, 3 * n, n + 2
    assert got.vertex_count == v + e + f
    assert got.face_count == 2 * n + 4 * n
    assert set(got.face_sizes.tolist()) == {4}


def test_uvs_come_back_per_corner():
    pos, faces = cube()
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]] * len(faces), dtype=float)
    got = subdivide_with_blender(pos, faces, 1, uv=uv, uv_smooth="PRESERVE_BOUNDARIES")
    assert got.uvs is not None and got.uvs.shape == (len(got.face_indices), 2)
    assert got.uvs.min() >= -1e-6 and got.uvs.max() <= 1 + 1e-6
