"""`render`'s world up axis and LOD stages, through the CLI and the daemon.

- `--up-axis Y` (and the op's `up_axis`): the Stanford bunny (`bun_zipper.ply`, a Y-up scan)
  stands up in the front view, taller than wide, as Blender shows it once imported, and lies
  on its back without the flag; the covered pixels' box is measured from the PNG.
- A `.usda` stage's own `upAxis = "Y"` turns the views without the flag (usd-core writes the
  stage: an independent writer); the flag still overrides it.
- Both LOD schemas of `tessd lod` (`variants`, `usdlod`) render as one panel per level, with
  the same triangles and the same pixels.
- `--raycast` reports progress while it ray casts (progress frames over the socket during the
  search, fractions increasing), and answers a cancel in well under a second.
"""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from pxr import Gf, Usd, UsdGeom, Vt

import locate
import tessd
from png_decode import read_png

REPO = Path(__file__).resolve().parents[2]
CRANK = REPO / "core/tessellate/tests/data/CrankArm.json"
BACKGROUND = (224, 224, 224, 255)


def _tessd(*args) -> dict:
    out = subprocess.run([str(locate.tessd_bin()), *map(str, args), "--json"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert not any(line.startswith("error") for line in out.stderr.splitlines()), out.stderr
    return json.loads(out.stdout)


def _box(png: Path, x0: int = 0, width: int | None = None) -> tuple[int, int]:
    """Width and height of the box of the non-background pixels of a panel."""
    rgba = np.asarray(read_png(png))
    panel = rgba[:, x0:x0 + width] if width else rgba
    covered = np.any(panel != BACKGROUND, axis=-1)
    ys, xs = np.nonzero(covered)
    assert len(xs) > 100, "nothing drawn"
    return int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)


def test_bunny_stands_up_with_up_axis_y(tmp_path, shared_data):
    bunny = shared_data / "mesh/bun_zipper.ply"
    size = ["--size", "200x200", "--view", "front"]
    flat = _tessd("render", bunny, tmp_path / "z.png", *size)
    up = _tessd("render", bunny, tmp_path / "y.png", *size, "--up-axis", "Y")
    assert (flat["up_axis"], up["up_axis"]) == ("Z", "Y")
    # Front with Y up: the eye on +Z, +Y up in the image.
    assert up["camera"]["up"] == [0.0, 1.0, 0.0] or np.allclose(up["camera"]["up"], [0, 1, 0])
    assert up["camera"]["eye"][2] > up["camera"]["target"][2]
    w, h = _box(tmp_path / "y.png")
    # The bunny's own box: 0.155 wide (X), 0.154 tall (Y), 0.12 deep (Z); standing, its
    # silhouette from the front is about as tall as wide (ears up), from below much flatter.
    wz, hz = _box(tmp_path / "z.png")
    assert h >= 0.9 * w, (w, h)
    assert hz < 0.85 * wz, (wz, hz)
    assert h > 1.15 * hz, (h, hz)
    # The ears are at the top: in the upright picture the top fifth of the box is narrower
    # than the bottom fifth (head and ears above the body).
    rgba = np.asarray(read_png(tmp_path / "y.png"))
    covered = np.any(rgba != BACKGROUND, axis=-1)
    ys = np.nonzero(covered.any(axis=1))[0]
    top = covered[ys[0]:ys[0] + len(ys) // 5].any(axis=0).sum()
    bottom = covered[ys[-1] - len(ys) // 5:ys[-1] + 1].any(axis=0).sum()
    assert top < bottom, (top, bottom)


def test_up_axis_over_the_socket_and_refusals(daemon, shared_data):
    bunny = str(shared_data / "mesh/bun_zipper.ply")
    with tessd.Client(daemon.socket, timeout=120) as c:
        r, a = c.call("render", {"input": bunny, "size": "64x64", "view": "top", "up_axis": "Y"})
        assert r["up_axis"] == "Y"
        # Top with Y up: looking down −Y.
        assert r["camera"]["eye"][1] > r["camera"]["target"][1]
        assert np.asarray(a["face_id"]).any()
        with pytest.raises(tessd.TessdError) as e:
            c.call("render", {"input": bunny, "size": "64x64", "up_axis": "X"})
        assert e.value.code == "invalid_request" and "`up_axis`" in e.value.message
        assert '"X"' in e.value.message
    run = subprocess.run([str(locate.tessd_bin()), "render", bunny, "/tmp/never.png",
                          "--up-axis", "x"], capture_output=True, text=True)
    assert run.returncode != 0 and "--up-axis" in run.stderr


def _y_up_stage(path: Path, up: str) -> None:
    """A tall box (1 wide, 3 high along Y, 0.5 deep) written by usd-core with `upAxis`."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, up)
    UsdGeom.Xform.Define(stage, "/Root")
    stage.SetDefaultPrim(stage.GetPrimAtPath("/Root"))
    mesh = UsdGeom.Mesh.Define(stage, "/Root/tower")
    pts = [(x, y, z) for z in (0, 0.5) for y in (0, 3) for x in (0, 1)]
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    mesh.CreatePointsAttr(Vt.Vec3fArray([Gf.Vec3f(*p) for p in pts]))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4] * 6))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([i for q in quads for i in q]))
    stage.GetRootLayer().Save()


def test_y_up_stage_renders_upright_without_the_flag(tmp_path):
    y_up, z_up = tmp_path / "y.usda", tmp_path / "z.usda"
    _y_up_stage(y_up, UsdGeom.Tokens.y)
    _y_up_stage(z_up, UsdGeom.Tokens.z)
    assert UsdGeom.GetStageUpAxis(Usd.Stage.Open(str(y_up))) == "Y"
    size = ["--size", "120x120", "--view", "front"]
    r = _tessd("render", y_up, tmp_path / "y.png", *size)
    assert r["up_axis"] == "Y"
    w, h = _box(tmp_path / "y.png")
    assert h > 2.2 * w, (w, h)  # 3 high, 1 wide
    # The same points in a Z-up stage: the tower lies along the view (seen end-on, 1 x 0.5).
    r = _tessd("render", z_up, tmp_path / "z.png", *size)
    assert r["up_axis"] == "Z"
    w, h = _box(tmp_path / "z.png")
    assert w > 1.5 * h, (w, h)
    # In a list of inputs too (the first stage that authors an upAxis).
    r = _tessd("render", y_up, y_up, tmp_path / "l.png", *size)
    assert r["up_axis"] == "Y" and len(r["panels"]) == 2
    # The flag overrides the stage's own axis.
    r = _tessd("render", y_up, tmp_path / "o.png", *size, "--up-axis", "Z")
    assert r["up_axis"] == "Z"
    assert np.array_equal(read_png(tmp_path / "o.png"), read_png(tmp_path / "z.png"))


def test_both_lod_schemas_render_one_panel_per_level(tmp_path, shared_data):
    spot = shared_data / "mesh/spot_triangulated.obj"
    results = {}
    for schema in ("variants", "usdlod"):
        stage = tmp_path / f"{schema}.usda"
        _tessd("lod", spot, "--levels", "20%,2%", "--lod-schema", schema, "--out", stage)
        results[schema] = _tessd("render", stage, tmp_path / f"{schema}.png", "--size", "96x80")
    for schema, r in results.items():
        assert [p["label"] for p in r["panels"]] == ["LOD0", "LOD1", "LOD2"], schema
        tris = [p["triangles"] for p in r["panels"]]
        assert tris[0] == 5856 and tris[0] > tris[1] > tris[2] > 0, (schema, tris)
        assert (r["width"], r["height"]) == (3 * 96, 80)
        for i in range(3):
            w, h = _box(tmp_path / f"{schema}.png", 96 * i, 96)
            assert w > 20 and h > 20, (schema, i, w, h)
    assert results["variants"]["panels"] == results["usdlod"]["panels"]
    assert np.array_equal(read_png(tmp_path / "variants.png"), read_png(tmp_path / "usdlod.png"))
    # What a viewer shows by default is still the default level alone.
    stats = _tessd("stats", tmp_path / "usdlod.usda")
    assert stats["faces"] == 5856


def test_raycast_reports_progress_and_answers_a_cancel(daemon):
    params = {"input": str(CRANK), "size": "160x120", "raycast": True}
    seen = []
    with tessd.Client(daemon.socket, timeout=300) as c:
        t0 = time.monotonic()
        r, a = c.call("render", params,
                      progress=lambda f, stage, msg: seen.append((time.monotonic() - t0, f, msg)))
        assert r["method"] == "raycast" and r["covered"] > 1000
        casting = [(t, f) for t, f, msg in seen if "ray cast" in msg]
        # Frames all along the search, not one at its end.
        assert len(casting) >= 10, seen
        fractions = [f for _, f in casting]
        assert fractions == sorted(fractions) and 0.5 <= fractions[0] < 0.6 and fractions[-1] > 0.95
        assert casting[-1][0] - casting[0][0] > 0.5 * r["timings_ms"]["draw"] / 1e3 - 0.5

        job = c.submit("render", params)
        deadline = time.monotonic() + 120
        while job.progress is None or "ray cast" not in job.progress.message:
            assert time.monotonic() < deadline, "no ray cast progress"
            time.sleep(0.005)
        t = time.monotonic()
        assert job.cancel() is True
        with pytest.raises(tessd.TessdError) as e:
            job.result(timeout=30)
        assert e.value.code == "cancelled"
        assert time.monotonic() - t < 1.0, "cancel took %.2f s" % (time.monotonic() - t)
        assert c.ping("after") == "after"
