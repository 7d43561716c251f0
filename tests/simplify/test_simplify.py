"""`tessd simplify` and `tessd compare` end to end, on every shared mesh and on known-answer
cases, through the CLI and through a real daemon (the `simplify` and `compare` protocol ops).

The error bound of the quality mode is checked twice: by the report (`max_displacement` ≤
`tolerance`) and independently, by the Metro-style surface distance of `tessd compare` (the
one-sided Hausdorff distance from the output surface to the input surface).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

import tessd
from simplify_util import shared_meshes, stats, tessd_json
from simplify_util import tessd as run_tessd
from tessd import TessdError
from usd_checks import validate_stage

MESHES = shared_meshes()
IDS = [m.name for m in MESHES]


def largest_side(path: Path) -> float:
    b = stats(path)["bounds"]
    return max(hi - lo for lo, hi in zip(b["min"], b["max"]))


# ------------------------------------------------------------------------------------------
# Every shared mesh


@pytest.mark.parametrize("fraction", ["5%", "1%", "0.5%", "0.1%"])
@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_quality_bound_holds_between_the_surfaces(mesh, fraction, tmp_path):
    out = tmp_path / "q.obj"
    r = tessd_json("simplify", mesh, out, "--method", "quality", "--max-error", fraction)
    assert r["method"] == "quality" and r["target_vertices"] is None
    # A percentage of the largest side of the bounding box of the referenced vertices (a mesh
    # with unreferenced vertices, like the bunny, may have a larger stored box).
    f = float(fraction.rstrip("%")) / 100
    tol = r["tolerance"]
    assert 0 < tol <= f * largest_side(mesh) * (1 + 1e-6)
    assert r["max_displacement"] <= tol
    assert r["uncovered_faces"] == 0 and r["surface_error"] <= tol
    assert 0 < r["output_vertices"] <= r["input_vertices"]
    s = stats(out)
    assert (s["vertices"], s["faces"]) == (r["output_vertices"], r["output_faces"])
    # Independent check, both ways (every vertex, every edge and ≥ 1 M face samples of each
    # surface against the other): the symmetric Hausdorff distance is within the tolerance.
    c = tessd_json("compare", mesh, out, "--edges")
    for way in ("a_to_b", "b_to_a"):
        assert c[way]["samples"] >= 1_000_000
        assert c[way]["max"] <= tol * 1.001, (way, c[way], r)
        # The reported bound is a bound of what was measured.
        assert c[way]["max"] <= r["surface_error"] + 1e-9 * largest_side(mesh), (way, c[way], r)


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_complexity_targets_are_met_or_explained(mesh, tmp_path):
    for percent in (50, 20, 5):
        out = tmp_path / f"c{percent}.ply"
        r = tessd_json("simplify", mesh, out, "--method", "complexity", "--target-vertices", f"{percent}%")
        # The target is the percentage of the referenced vertices, rounded half away from zero.
        assert r["target_vertices"] == max(1, int(percent / 100 * r["input_vertices"] + 0.5))
        s = stats(out)
        assert (s["vertices"], s["faces"]) == (r["output_vertices"], r["output_faces"])
        assert s["unreferenced_vertices"] == 0
        miss = abs(r["output_vertices"] - r["target_vertices"])
        if miss <= 0.01 * r["target_vertices"]:
            # The only note then is about the input's twisted polygons (test_polygon_twist.py).
            assert (r["note"] is not None) == (r["twisted_polygons"] > 0), r
            assert "asked for" not in (r["note"] or ""), r
        else:
            # Only a target the mesh cannot reach may be missed, and the result says why.
            assert r["note"] and "asked for" in r["note"], r
            if r["target_vertices"] < 3:
                assert "a face needs 3 distinct vertices" in r["note"]
            else:
                pytest.fail(f"{mesh.name} {percent}%: {r['output_vertices']} vertices for a "
                            f"target of {r['target_vertices']}: {r['note']}")


@pytest.mark.parametrize("mesh", MESHES, ids=IDS)
def test_grid_reduces_and_writes_a_valid_mesh(mesh, tmp_path):
    out = tmp_path / "g.off"
    r = tessd_json("simplify", mesh, out, "--method", "grid", "--cells", "4")
    assert r["tolerance"] is None and r["target_vertices"] is None
    assert 0 < r["output_vertices"] < r["input_vertices"]
    assert r["clusters"] <= 4 ** 3
    s = stats(out)
    assert (s["vertices"], s["faces"]) == (r["output_vertices"], r["output_faces"])
    assert s["unreferenced_vertices"] == 0


# ------------------------------------------------------------------------------------------
# Known answers

CUBE = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
CUBE_TRIS = [(0, 3, 1), (0, 2, 3), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
             (1, 3, 7), (1, 7, 5), (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)]


def write_obj(path: Path, positions, faces) -> Path:
    with open(path, "w") as f:
        for p in positions:
            f.write("v %r %r %r\n" % tuple(float(c) for c in p))
        for face in faces:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")
    return path


def read_obj_positions(path: Path):
    return [tuple(float(c) for c in line.split()[1:4]) for line in open(path) if line.startswith("v ")]


def test_heaviest_vertex_keeps_exactly_the_cube_corners(tmp_path):
    cube = write_obj(tmp_path / "cube.obj", CUBE, CUBE_TRIS)
    out = tmp_path / "out.obj"
    # The coarsest quality goal that cannot merge two corners (edges are 1 long): the heaviest
    # vertex of any cell holding two corners is 1 away from the other, so every corner stays.
    r = tessd_json("simplify", cube, out, "--method", "quality", "--max-error", "0.99",
                   "--representative", "heaviest")
    assert (r["output_vertices"], r["output_faces"], r["max_displacement"]) == (8, 12, 0.0)
    assert sorted(read_obj_positions(out)) == sorted(map(lambda p: tuple(map(float, p)), CUBE))
    # The barycentre of the whole cube is only √3/2 ≈ 0.87 from each corner, so the paper's
    # partition keeps one cell and every face collapses onto one point; the input's surface
    # would then be covered by nothing. The surface guarantee splits that cell until the
    # faces that collapse lie on the result's edges and vertices.
    r = tessd_json("simplify", cube, out, "--method", "quality", "--max-error", "0.99")
    assert r["refinement_rounds"] >= 1 and r["uncovered_faces"] == 0
    assert r["output_faces"] > 0 and r["surface_error"] <= 0.99
    c = tessd_json("compare", cube, out)
    assert max(c["a_to_b"]["max"], c["b_to_a"]["max"]) <= 0.99
    # A 2 × 2 × 2 grid puts every corner in its own cell.
    r = tessd_json("simplify", cube, out, "--method", "grid", "--cells", "2",
                   "--representative", "heaviest")
    assert (r["clusters"], r["output_vertices"], r["output_faces"]) == (8, 8, 12)
    assert sorted(read_obj_positions(out)) == sorted(map(lambda p: tuple(map(float, p)), CUBE))


BOX_QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]


def test_stacked_cad_boxes_report_every_duplicate(tmp_path):
    # Two unit boxes stacked along z, each with its own 8 vertices (as CAD exports solids):
    # box A's top and box B's bottom are the same quad, reversed.
    positions = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    positions += [(x, y, z + 1) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    faces = [q for q in BOX_QUADS] + [tuple(i + 8 for i in q) for q in BOX_QUADS]
    # Three doubled facets: the same quad again, one reversed, one from another start corner.
    faces += [(0, 1, 5, 4), tuple(reversed((9, 11, 15, 13))), (6, 7, 3, 2)]
    mesh = write_obj(tmp_path / "stacked.obj", positions, faces)
    # A grid that gives every position its own cell (the quality and complexity goals
    # triangulate first, and a reversed quad split along the other diagonal is no duplicate).
    r = tessd_json("simplify", mesh, tmp_path / "out.obj", "--method", "grid", "--cells", "4")
    assert r["duplicate_faces"] == 1 + 3
    assert r["degenerate_faces"] == 0
    assert (r["output_vertices"], r["output_faces"]) == (12, 12 + 3 - 4)
    assert r["max_displacement"] == 0.0


def test_partition_boxes_obj_and_usd(tmp_path):
    spot = locate_mesh("spot_triangulated.obj")
    boxes = tmp_path / "boxes.obj"
    r = tessd_json("simplify", spot, tmp_path / "out.obj", "--method", "complexity",
                   "--target-vertices", "5%", "--partition", boxes)
    c = r["clusters"]
    assert r["cells"] == c and r["partition_output"] == str(boxes)
    lines = boxes.read_text().splitlines()
    assert sum(1 for l in lines if l.startswith("v ")) == 8 * c
    assert sum(1 for l in lines if l.startswith("l ")) == 12 * c
    assert max(int(i) for l in lines if l.startswith("l ") for i in l.split()[1:]) == 8 * c

    usd = tmp_path / "boxes.usda"
    r = tessd_json("simplify", spot, tmp_path / "out.ply", "--method", "grid", "--cells", "6",
                   "--partition", usd)
    assert validate_stage(usd) == []
    from pxr import Usd, UsdGeom
    stage = Usd.Stage.Open(str(usd))
    mesh = UsdGeom.Mesh(stage.GetDefaultPrim().GetChildren()[0])
    assert len(mesh.GetPointsAttr().Get()) == 8 * r["clusters"]
    assert len(mesh.GetFaceVertexCountsAttr().Get()) == 6 * r["clusters"]


def locate_mesh(name: str) -> Path:
    return next(m for m in MESHES if m.name == name)


# ------------------------------------------------------------------------------------------
# compare


def test_compare_a_mesh_with_itself_is_zero():
    spot = locate_mesh("spot_triangulated.obj")
    c = tessd_json("compare", spot, spot, "--samples", "200000")
    # Zero up to the rounding of the closest-point arithmetic (in f64).
    eps = 1e-12 * c["bbox_diagonal"]
    assert c["hausdorff"] <= eps and c["rms"] <= eps and c["mean"] <= eps
    assert c["a_to_b"]["max"] <= eps and c["b_to_a"]["max"] <= eps
    assert c["a_to_b"]["samples"] == 200_000 + 2930
    text = run_tessd("compare", spot, spot, "--samples", "1000").stdout
    assert "(0.0000 % of the diagonal)" in text and text.startswith("A -> B: max ")


def test_compare_a_translated_copy_gives_the_translation(tmp_path):
    spot = locate_mesh("spot_triangulated.obj")
    lines = []
    for line in open(spot):
        if line.startswith("v "):
            x, y, z = (float(c) for c in line.split()[1:4])
            line = "v %r %r %r\n" % (x, y, z + 0.0625)
        lines.append(line)
    moved = tmp_path / "moved.obj"
    moved.write_text("".join(lines))
    c = tessd_json("compare", spot, moved)
    # Every point is at most the translation away from the copy; the extreme vertices along
    # the translation are exactly that far.
    assert c["hausdorff"] == pytest.approx(0.0625, abs=1e-6)
    assert c["a_to_b"]["max"] == pytest.approx(0.0625, abs=1e-6)
    assert c["b_to_a"]["max"] == pytest.approx(0.0625, abs=1e-6)
    assert 0 < c["rms"] <= 0.0625 + 1e-6
    assert c["hausdorff_relative"] == pytest.approx(0.0625 / c["bbox_diagonal"], rel=1e-5)


# ------------------------------------------------------------------------------------------
# The protocol ops


def arrays_of(positions, faces):
    return tessd.mesh_to_arrays(np.asarray(positions, dtype=np.float32), faces)


def error_of(client, op, params, arrays=None) -> TessdError:
    with pytest.raises(TessdError) as info:
        client.call(op, params, arrays)
    return info.value


def test_socket_result_matches_the_cli(daemon, tmp_path):
    spot = locate_mesh("spot_triangulated.obj")
    cli = tessd_json("simplify", spot, tmp_path / "cli.obj", "--method", "quality", "--max-error", "2%",
                     "--representative", "quadric")
    with tessd.Client(daemon.socket, timeout=60) as c:
        r, arrays = c.call("simplify", {"input": str(spot), "method": "quality", "max_error": "2%",
                                        "representative": "quadric"})
    assert {k: v for k, v in r.items()} == {k: v for k, v in cli.items() if k != "output"}
    assert arrays["positions"].shape == (r["output_vertices"], 3)
    assert arrays["face_sizes"].shape == (r["output_faces"],)
    got = np.asarray(read_obj_positions(tmp_path / "cli.obj"), dtype=np.float32)
    np.testing.assert_array_equal(got, arrays["positions"])


def test_partition_arrays_over_the_socket(daemon):
    spot = locate_mesh("spot_quadrangulated.obj")
    with tessd.Client(daemon.socket, timeout=60) as c:
        r, arrays = c.call("simplify", {"input": str(spot), "method": "complexity",
                                        "target_vertices": 300, "partition": True,
                                        "triangulate": True})
    n = r["clusters"]
    assert r["cells"] == n and r["output_vertices"] == 300
    lo, hi = arrays["cells_min"], arrays["cells_max"]
    assert lo.shape == hi.shape == (n, 3) and lo.dtype == hi.dtype == np.float32
    assert (lo <= hi).all()
    # Triangulated first: the output is all triangles.
    assert set(arrays["face_sizes"].tolist()) == {3}


def test_bad_requests_get_clear_errors(daemon):
    tri = arrays_of([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [[0, 1, 2]])
    spot = str(locate_mesh("spot_triangulated.obj"))
    with tessd.Client(daemon.socket, timeout=60) as c:
        cases = [
            ({"input": spot}, "`method` is required"),
            ({"input": spot, "method": "octree"}, "`method` must be"),
            ({"input": spot, "method": "quality"}, "needs `max_error`"),
            ({"input": spot, "method": "quality", "max_error": -1}, "`max_error` must be positive, got -1"),
            ({"input": spot, "method": "quality", "max_error": 0}, "`max_error` must be positive, got 0"),
            ({"input": spot, "method": "quality", "max_error": "-5%"}, "`max_error` must be positive, got -5%"),
            ({"input": spot, "method": "quality", "max_error": "abc%"}, "`max_error` must be a positive number"),
            ({"input": spot, "method": "quality", "max_error": "NaN%"}, "`max_error` must be a positive number"),
            ({"input": spot, "method": "quality", "max_error": "inf%"}, "`max_error` must be a positive number"),
            ({"input": spot, "method": "quality", "max_error": "0%"}, "`max_error` must be positive, got 0%"),
            ({"input": spot, "method": "quality", "max_error": [1]}, "`max_error` must be a positive number"),
            ({"input": spot, "method": "complexity", "target_vertices": 2930},
             "`target_vertices`: the target of 2930 vertices must be between 1 and the input's 2930"),
            ({"input": spot, "method": "complexity", "target_vertices": 10**9}, "`target_vertices`"),
            ({"input": spot, "method": "complexity", "target_vertices": "100%"}, "below 100%"),
            ({"input": spot, "method": "complexity", "target_vertices": 2.5}, "integer number of vertices"),
            ({"input": spot, "method": "grid"}, "needs `cells`"),
            ({"input": spot, "method": "grid", "cells": 0}, "`cells` must be a positive integer"),
            ({"input": spot, "method": "grid", "cells": 4, "cell_size": 1}, "not both"),
            ({"input": spot, "method": "grid", "cell_size": -1}, "`cell_size` must be a positive number"),
            ({"input": spot, "method": "grid", "cells": 4, "max_error": 1}, "`max_error` applies to method"),
            ({"input": spot, "method": "grid", "cells": 4, "representative": "median"}, "`representative`"),
            ({"input": spot, "method": "grid", "cells": 4, "weighting": "area"}, "`weighting`"),
            ({"input": spot, "method": "grid", "cells": 4, "triangulate": "yes"}, "`triangulate`"),
        ]
        for params, message in cases:
            e = error_of(c, "simplify", params)
            assert e.code == "invalid_request" and message in e.message, (params, e.code, e.message)

        e = error_of(c, "simplify", {"method": "grid", "cells": 2, "output": "/tmp/x.xyz"}, tri)
        assert e.code == "unsupported"

        # No faces; NaN coordinates.
        empty = {"positions": np.zeros((3, 3), np.float32), "face_indices": np.zeros(0, np.uint32),
                 "face_sizes": np.zeros(0, np.uint32)}
        e = error_of(c, "simplify", {"method": "grid", "cells": 2}, empty)
        assert (e.code, e.message) == ("invalid_mesh", "the mesh has no faces")
        nan = arrays_of([(0, 0, 0), (1, float("nan"), 0), (0, 1, 0)], [[0, 1, 2]])
        e = error_of(c, "simplify", {"method": "quality", "max_error": "1%"}, nan)
        assert e.code == "invalid_mesh" and "vertex 1" in e.message, e.message

        # All vertices at one point: a relative tolerance is 0 and says so; an absolute one
        # merges everything, and no face survives.
        point = arrays_of([(1, 1, 1)] * 4, [[0, 1, 2], [0, 2, 3]])
        e = error_of(c, "simplify", {"method": "quality", "max_error": "1%"}, point)
        assert e.code == "invalid_request" and "give an absolute distance" in e.message, e.message
        r, arrays = c.call("simplify", {"method": "quality", "max_error": 0.1}, point)
        assert (r["output_vertices"], r["output_faces"], r["degenerate_faces"]) == (0, 0, 2)
        assert arrays["positions"].shape == (0, 3)

        # A single triangle cannot lose a vertex and keep its face.
        r, _ = c.call("simplify", {"method": "quality", "max_error": "1%"}, tri)
        assert (r["output_vertices"], r["output_faces"], r["max_displacement"]) == (3, 1, 0.0)
        r, _ = c.call("simplify", {"method": "complexity", "target_vertices": "50%"}, tri)
        assert r["target_vertices"] == 2 and r["output_vertices"] == 3
        assert "a face needs 3 distinct vertices" in r["note"]

        assert c.ping("still serving") == "still serving"


def big_grid(n: int, m: int):
    """An n × m grid of quads on a wavy surface: (n + 1)(m + 1) vertices."""
    x, y = np.meshgrid(np.arange(n + 1, dtype=np.float32), np.arange(m + 1, dtype=np.float32))
    z = (np.sin(x * 0.05) * np.cos(y * 0.07) * 5).astype(np.float32)
    positions = np.stack([x.ravel(), y.ravel(), z.ravel()], 1)
    v = (np.arange(m)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel().astype(np.uint32)
    quads = np.stack([v, v + 1, v + n + 2, v + n + 1], 1)
    return tessd.mesh_to_arrays(positions, quads)


def test_cancel_a_large_simplify(daemon, tmp_path):
    arrays = big_grid(2000, 1500)  # 3 M vertices
    out = tmp_path / "never.ply"
    with tessd.Client(daemon.socket, timeout=120) as c:
        job = c.submit("simplify", {"method": "quality", "max_error": "0.05%", "output": str(out)}, arrays)
        deadline = time.monotonic() + 60
        while job.progress is None or job.progress.stage in ("read", "simplify"):
            assert not job.poll() and time.monotonic() < deadline, job
            time.sleep(0.005)
        t = time.monotonic()
        assert job.cancel() is True
        with pytest.raises(TessdError) as info:
            job.result(timeout=30)
        assert info.value.code == "cancelled"
        assert time.monotonic() - t < 5, "cancel took too long"
        assert c.ping("after cancel") == "after cancel"
    assert os.listdir(tmp_path) == []
