"""`tessd demo` end to end: it starts a real daemon, and its outputs are re-opened with
usd-core and checked against the bundled sample's known counts (Spot: 2930 vertices, 5856
triangles, closed — MANIFEST.md)."""

from __future__ import annotations

import json
import subprocess

from locate import tessd_bin
from pxr import Usd, UsdGeom
from usd_checks import validate_stage


def test_demo_writes_stats_and_valid_usd(tmp_path):
    out = tmp_path / "demo-out"
    run = subprocess.run([str(tessd_bin()), "demo", "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "tessd demo: done" in run.stdout

    stats = json.loads((out / "spot_stats.json").read_text())
    assert (stats["vertices"], stats["faces"], stats["triangles"]) == (2930, 5856, 5856)
    assert stats["boundary_edges"] == 0 and stats["non_manifold_edges"] == 0

    usd = out / "spot.usda"
    assert validate_stage(usd) == []
    stage = Usd.Stage.Open(str(usd))
    mesh = UsdGeom.Mesh(stage.GetDefaultPrim().GetChildren()[0])
    assert len(mesh.GetPointsAttr().Get()) == 2930
    assert len(mesh.GetFaceVertexCountsAttr().Get()) == 5856
    assert mesh.GetSubdivisionSchemeAttr().Get() == "none"
    st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
    assert st and st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    # The socket is gone after the demo's daemon shut down: nothing left in the output folder
    # but the two results.
    assert sorted(p.name for p in out.iterdir()) == ["spot.usda", "spot_stats.json"]
