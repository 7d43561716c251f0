"""`tessd demo` end to end: it starts a real daemon, and its outputs are re-opened with
usd-core and checked against the bundled sample's known counts (Spot: 2930 vertices, 5856
triangles, closed — MANIFEST.md), including its LOD chain (50 %, 20 %, 5 % of the vertices)."""

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

    # The LOD chain: a variant set `LOD` on the root, LOD0 the input, LOD1..3 at 50 %, 20 %
    # and 5 % of its vertices (within 1 %), every variant valid.
    lods = out / "spot_lods.usda"
    assert validate_stage(lods) == []
    stage = Usd.Stage.Open(str(lods))
    root = stage.GetDefaultPrim()
    vset = root.GetVariantSets().GetVariantSet("LOD")
    assert vset.GetVariantNames() == ["LOD0", "LOD1", "LOD2", "LOD3"]
    assert vset.GetVariantSelection() == "LOD0"
    counts = []
    for name in vset.GetVariantNames():
        vset.SetVariantSelection(name)
        counts.append(len(UsdGeom.Mesh(stage.GetPrimAtPath("/Root/spot")).GetPointsAttr().Get()))
    assert counts[0] == 2930
    for got, percent in zip(counts[1:], (50, 20, 5)):
        target = int(percent / 100 * 2930 + 0.5)
        assert abs(got - target) <= 0.01 * target, (counts, percent)
    assert "lod: LOD0 2930 vertices" in run.stdout

    # The socket is gone after the demo's daemon shut down: nothing left in the output folder
    # but the three results.
    assert sorted(p.name for p in out.iterdir()) == ["spot.usda", "spot_lods.usda", "spot_stats.json"]
