"""A part 2·10⁴ mm from its origin, tessellated at 0.01 mm by the real daemon into a `.usda`:
usd-core (a real USD reader) composes the prim's `xformOp:translate` with its f32 points into
world positions equal to the daemon's f64 positions within f32 precision *of the part's size*
(~1e-6 mm), where absolute f32 points would be off by ~1e-3 mm (a sixth of the tolerance)."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
from pxr import Gf, Usd, UsdGeom

import tessd

REPO = Path(__file__).resolve().parents[2]

FAR = [20000.123456789, -19999.87654321, 20000.3141592]


def _add(p):
    return [p[k] + FAR[k] for k in range(3)]


def _move_curve(c):
    if c["type"] == "line":
        c["origin"] = _add(c["origin"])
    elif c["type"] in ("circle", "ellipse"):
        c["center"] = _add(c["center"])
    else:
        c["poles"] = [_add(p) for p in c["poles"]]


def translated(doc):
    """The document moved by FAR: frames, axes, swept curves, poles, edge curves."""
    doc = copy.deepcopy(doc)
    for f in doc["faces"]:
        s = f["surface"]
        if "origin" in s:
            s["origin"] = _add(s["origin"])
        if "axis_origin" in s:
            s["axis_origin"] = _add(s["axis_origin"])
        if "curve" in s:
            _move_curve(s["curve"])
        if s["type"] == "bspline":
            s["poles"] = [[_add(p) for p in row] for row in s["poles"]]
    for e in doc.get("edges") or []:
        if e.get("curve"):
            _move_curve(e["curve"])
    return doc


def world_points(path):
    stage = Usd.Stage.Open(str(path))
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == 1
    prim = meshes[0]
    xf = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    pts = UsdGeom.Mesh(prim).GetPointsAttr().Get()
    return np.array([list(xf.Transform(Gf.Vec3d(*map(float, p)))) for p in pts])


def test_usd_readers_see_absolute_positions(daemon, tmp_path):
    doc = translated(json.loads((REPO / "core/tessellate/tests/data/Pump_Nut.json").read_text()))
    usda = tmp_path / "far.usda"
    with tessd.Client(daemon.socket) as c:
        exact, arrays = c.call("tessellate", {"brep": doc, "tolerance": "0.01mm", "positions": "f64"})
        f64 = np.asarray(arrays["positions"], dtype=np.float64).reshape(-1, 3)
        assert np.asarray(arrays["positions"]).dtype == np.float64
        result, _ = c.call("tessellate", {"brep": doc, "tolerance": "0.01mm", "output": str(usda)})
    assert result["origin"] != [0.0, 0.0, 0.0]
    assert len(result["warnings"]) == 1 and "relative to the origin" in result["warnings"][0]
    world = world_points(usda)
    assert world.shape == f64.shape
    err = np.abs(world - f64).max()
    naive = np.abs(f64.astype(np.float32).astype(np.float64) - f64).max()
    print(f"Pump_Nut 2e4 mm out, origin {result['origin']}: USD world points off by {err:.2e} mm, "
          f"absolute f32 by {naive:.2e} mm")
    assert err < 3e-6, err
    assert naive > 3e-4, naive
