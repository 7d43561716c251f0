"""The `render` op through the real daemon and the Python client: arrays (colour, depth, face
ids, (u, v)) with the documented shapes and dtypes, PNG files that the tests' PNG decoder
(tests/png_decode.py: zlib and the five row filters, independent of tessd) reads back to the
same pixels, mesh arrays in, B-Rep inline, progress frames, cancellation and refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import tessd
from png_decode import read_png
from tessd.client import TessdError

REPO = Path(__file__).resolve().parents[2]
CRANK = REPO / "core/tessellate/tests/data/CrankArm.json"


def test_arrays_of_the_bunny(daemon, shared_data):
    seen = []
    with tessd.Client(daemon.socket) as c:
        r, a = c.call("render", {"input": str(shared_data / "mesh/stanford_bunny.obj"),
                                 "size": "160x120", "view": "front"},
                      progress=lambda f, stage, msg: seen.append((f, stage)))
    color, depth, ids, uv = (np.asarray(a[k]) for k in ("color", "depth", "face_id", "uv"))
    assert color.shape == (120, 160, 4) and color.dtype == np.uint8
    assert depth.shape == (120, 160) and depth.dtype == np.float32
    assert ids.shape == (120, 160) and ids.dtype == np.uint32
    assert uv.shape == (120, 160, 2) and uv.dtype == np.float32
    covered = ids != 0
    assert r["covered"] == int(covered.sum()) > 500
    assert r["pixels"] == 160 * 120 and r["triangles"] == 69451
    assert set(np.unique(ids)) == {0, 1}  # no groups: face index 0 everywhere
    # Depth: within the camera's planes where covered, infinite on the background.
    cam = r["camera"]
    assert np.all((depth[covered] >= cam["near"]) & (depth[covered] <= cam["far"]))
    assert np.all(np.isinf(depth[~covered]))
    assert np.all(color[~covered] == [224, 224, 224, 255])
    assert np.all(uv == 0)  # the bunny has no uvs
    assert not r["files"] and r["output"] is None
    stages = [s for _, s in seen]
    assert "upload" in stages and "render" in stages
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)
    for step in ("tessellate", "upload", "draw", "readback", "encode"):
        assert r["timings_ms"][step] >= 0
    assert r["adapter"]["backend"] and r["adapter"]["name"]


def test_png_output_and_face_ids_png(daemon, tmp_path):
    out, ids_png = tmp_path / "crank.png", tmp_path / "ids.png"
    params = {"input": str(CRANK), "size": [120, 90], "shading": "face-ids", "edges": True}
    with tessd.Client(daemon.socket) as c:
        r, _ = c.call("render", {**params, "output": str(out), "face_ids": str(ids_png)})
        _, a = c.call("render", params)
    assert sorted(Path(f).name for f in r["files"]) == ["crank.png", "ids.png"]
    color = read_png(out)
    assert np.array_equal(color, np.asarray(a["color"]))
    rgba = read_png(ids_png).astype(np.uint32)
    decoded = rgba[..., 0] + 256 * rgba[..., 1] + 65536 * rgba[..., 2]
    assert np.all(rgba[..., 3] == 255)
    assert np.array_equal(decoded, np.asarray(a["face_id"]))
    # One id per B-Rep face (index in document order + 1).
    faces = len(json.loads(CRANK.read_text())["faces"])
    assert 10 < len(np.unique(decoded)) <= faces + 1 and decoded.max() <= faces
    assert r["tolerance"] > 0 and r["faces"] == faces


def test_mesh_arrays_and_inline_brep(daemon):
    # A unit cube from arrays, one group per side.
    p = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.float32)
    sides = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    f = np.array([[s[0], s[1], s[2]] for s in sides] + [[s[0], s[2], s[3]] for s in sides], dtype=np.uint32)
    groups = np.array(list(range(6)) * 2, dtype=np.uint32)
    with tessd.Client(daemon.socket) as c:
        r, a = c.call("render", {"size": "64x48", "view": "iso"},
                      arrays={"positions": p, "face_indices": f, "face_groups": groups})
        # iso from (+1, −1, +1): sides x = 1, y = 0, z = 1 (groups 5, 2, 1).
        assert set(np.unique(np.asarray(a["face_id"]))) == {0, 2, 3, 6}
        doc = json.loads(CRANK.read_text())
        r2, a2 = c.call("render", {"brep": doc, "size": "64x48", "view": "top"})
    assert r2["view"] == "top" and np.asarray(a2["face_id"]).max() >= 1


def test_cancel_and_refusals_write_nothing(daemon, tmp_path, shared_data):
    bunny = str(shared_data / "mesh/stanford_bunny.obj")
    with tessd.Client(daemon.socket) as c:
        with pytest.raises(TessdError) as e:
            c.call("render", {"input": bunny, "output": str(tmp_path / "x.png"), "turntable": 4},
                   progress=lambda f, stage, msg: stage != "render")
        assert e.value.code == "cancelled"
        for params, code, text in [
            ({"size": "0x0"}, "invalid_request", "0x0"),
            ({"size": "100000x100000"}, "invalid_request", "100000x100000"),
            ({"cracks": "sideways"}, "invalid_request", "sideways"),
            ({"raycast": True}, "unsupported", "B-Rep"),
            ({"view": "sideways"}, "invalid_request", "sideways"),
            ({"output": str(tmp_path / "x.jpg")}, "unsupported", "x.jpg"),
        ]:
            with pytest.raises(TessdError) as e:
                c.call("render", {"input": bunny, "output": str(tmp_path / "y.png"), **params})
            assert e.value.code == code and text in str(e.value), (params, e.value)
    assert list(tmp_path.iterdir()) == []


def _tessd_json(*args):
    """`tessd ARGS --json` through the CLI, its report parsed."""
    import subprocess

    import locate
    out = subprocess.run([str(locate.tessd_bin()), *map(str, args), "--json"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def _ids(path):
    rgba = np.asarray(read_png(path)).astype(np.int64)
    return rgba[..., 0] + 256 * rgba[..., 1] + 65536 * rgba[..., 2]


def test_several_meshes_side_by_side(tmp_path, shared_data):
    """A LOD chain as panels: `tessd render A B C OUT.png` draws each mesh in its own panel
    from one camera, so each panel is exactly the picture of that mesh alone from that camera
    (colour and face ids), panels left to right in the given order; `--columns` stacks them."""
    spot = shared_data / "mesh/spot_triangulated.obj"
    lods = tmp_path / "lods"
    _tessd_json("lod", spot, "--levels", "20%,2%", "--out", tmp_path / "spot.usda",
                "--per-level-dir", lods)
    files = [lods / f"spot_LOD{i}.obj" for i in range(3)]
    cam = ["--eye", "-2.6,1.2,-3.6", "--target", "0,0.1,0.2", "--up", "0,1,0"]
    grid = _tessd_json("render", *files, tmp_path / "row.png", "--size", "96x80", *cam,
                       "--face-ids", tmp_path / "row_ids.png")
    assert (grid["width"], grid["height"], grid["columns"], grid["rows"]) == (288, 80, 3, 1)
    assert [p["label"] for p in grid["panels"]] == [f"spot_LOD{i}" for i in range(3)]
    assert [p["x"] for p in grid["panels"]] == [0, 96, 192]
    tris = [p["triangles"] for p in grid["panels"]]
    assert tris[0] > tris[1] > tris[2] > 0 and grid["triangles"] == sum(tris)
    row = np.asarray(read_png(tmp_path / "row.png"))
    row_ids = _ids(tmp_path / "row_ids.png")
    assert row.shape == (80, 288, 4)
    covered = 0
    for i, f in enumerate(files):
        one = _tessd_json("render", f, tmp_path / f"one{i}.png", "--size", "96x80", *cam,
                          "--face-ids", tmp_path / f"one{i}_ids.png")
        assert one["triangles"] == tris[i]
        panel = slice(96 * i, 96 * (i + 1))
        assert np.array_equal(row[:, panel], np.asarray(read_png(tmp_path / f"one{i}.png")))
        assert np.array_equal(row_ids[:, panel], _ids(tmp_path / f"one{i}_ids.png"))
        covered += one["covered"]
    assert grid["covered"] == covered > 3 * 500
    # One column: the panels stacked top to bottom.
    col = _tessd_json("render", *files, tmp_path / "col.png", "--size", "96x80", *cam,
                      "--columns", "1")
    assert (col["width"], col["height"]) == (96, 240)
    assert [p["y"] for p in col["panels"]] == [0, 80, 160]
    assert np.array_equal(np.asarray(read_png(tmp_path / "col.png"))[80:160], row[:, 96:192])


def test_panels_refuse_brep_and_name_the_bad_input(daemon, tmp_path, shared_data):
    spot = str(shared_data / "mesh/spot_triangulated.obj")
    with tessd.Client(daemon.socket) as c:
        for inputs, code, words in [
            ([spot, str(CRANK)], "unsupported", "`input[1]`"),
            ([spot, str(tmp_path / "missing.obj")], "io", "`input[1]`"),
            ([], "invalid_request", "1 to 64"),
            ([spot, 7], "invalid_request", "`input[1]`"),
        ]:
            out = tmp_path / "never.png"
            with pytest.raises(TessdError) as e:
                c.call("render", {"input": inputs, "size": "32x32", "output": str(out)})
            assert e.value.code == code and words in e.value.message, e.value
            assert not out.exists()
        with pytest.raises(TessdError) as e:
            c.call("render", {"input": [spot, spot], "columns": 0, "size": "32x32"})
        assert e.value.code == "invalid_request" and "`columns`" in e.value.message
