"""`tessd lod` and the `lod` protocol op: LOD chains written as a USD variant set `LOD` or with
the native UsdLod schema (usd-core 26.8+), re-opened and checked with usd-core, plus the
per-level files and the arrays a host gets back over the socket."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom, UsdLod

import tessd
from simplify_util import shared_meshes, stats, tessd_json
from simplify_util import tessd as run_tessd
from tessd import TessdError
from usd_checks import validate_stage

SPOT = next(m for m in shared_meshes() if m.name == "spot_triangulated.obj")
SPOT_VERTICES = 2930
PERCENTS = (50, 20, 5)
LEVELS = ",".join(f"{p}%" for p in PERCENTS)


def target(percent: float, vertices: int = SPOT_VERTICES) -> int:
    """The vertex target of a percentage (rounded half away from zero, as tessd does)."""
    return max(1, int(percent / 100 * vertices + 0.5))


def check_levels(result) -> None:
    assert result["input_vertices"] == SPOT_VERTICES
    assert result["lod0"] == {"points": SPOT_VERTICES, "faces": 5856}
    assert [l["level"] for l in result["levels"]] == [1, 2, 3]
    assert [l["goal"] for l in result["levels"]] == [f"{p}%" for p in PERCENTS]
    for level, p in zip(result["levels"], PERCENTS):
        assert level["target_vertices"] == target(p)
        assert abs(level["output_vertices"] - target(p)) <= 0.01 * target(p), level
        assert level["note"] is None


def points(prim: Usd.Prim) -> int:
    return len(UsdGeom.Mesh(prim).GetPointsAttr().Get())


def test_lod_variants(tmp_path):
    out = tmp_path / "spot_lods.usda"
    r = tessd_json("lod", SPOT, "--levels", LEVELS, "--out", out)
    check_levels(r)
    assert r["lod_schema"] == "variants" and r["output"] == str(out)
    assert validate_stage(out) == []

    stage = Usd.Stage.Open(str(out))
    root = stage.GetDefaultPrim()
    vset = root.GetVariantSets().GetVariantSet("LOD")
    assert root.GetVariantSets().GetNames() == ["LOD"]
    assert vset.GetVariantNames() == ["LOD0", "LOD1", "LOD2", "LOD3"]
    assert vset.GetVariantSelection() == "LOD0"
    mesh_path = root.GetPath().AppendChild("spot_triangulated")
    counts = []
    for name in vset.GetVariantNames():
        vset.SetVariantSelection(name)
        counts.append(points(stage.GetPrimAtPath(mesh_path)))
    assert counts == [SPOT_VERTICES] + [l["output_vertices"] for l in r["levels"]]
    # LOD0 is the input, UVs included.
    vset.SetVariantSelection("LOD0")
    st = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath(mesh_path)).GetPrimvar("st")
    assert st and st.GetInterpolation() == UsdGeom.Tokens.faceVarying


def test_lod_usdlod_schema(tmp_path):
    out = tmp_path / "spot_usdlod.usda"
    r = tessd_json("lod", SPOT, "--levels", LEVELS, "--out", out, "--lod-schema", "usdlod")
    check_levels(r)
    assert r["lod_schema"] == "usdlod"
    assert validate_stage(out) == []

    stage = Usd.Stage.Open(str(out))
    root = stage.GetDefaultPrim()
    assert not root.HasVariantSets()
    lod_roots = [p for p in stage.Traverse() if p.HasAPI(UsdLod.RootAPI)]
    assert [p.GetPath() for p in lod_roots] == [root.GetPath().AppendChild("spot_triangulated")]
    lod_root = lod_roots[0]
    assert "LODRootAPI" in lod_root.GetAppliedSchemas()
    api = UsdLod.RootAPI(lod_root)

    # The LOD items are the root's children, in order, only the default one visible.
    items = lod_root.GetChildren()
    assert [p.GetName() for p in items] == ["LOD0", "LOD1", "LOD2", "LOD3"]
    assert all(p.IsA(UsdGeom.Mesh) for p in items)
    assert [points(p) for p in items] == [SPOT_VERTICES] + [l["output_vertices"] for l in r["levels"]]
    assert api.GetLodDefaultIndexAttr().Get() == 0
    visibility = [UsdGeom.Imageable(p).ComputeVisibility() for p in items]
    assert visibility == [UsdGeom.Tokens.inherited] + [UsdGeom.Tokens.invisible] * 3

    # The heuristic sits outside the LOD root (every child of the root is an LOD item) but
    # inside the default prim.
    targets = api.GetLodHeuristicsRel().GetTargets()
    assert len(targets) == 1
    heuristic = stage.GetPrimAtPath(targets[0])
    assert heuristic.IsA(UsdLod.ScreenSizeHeuristic)
    assert heuristic.GetParent() == root and not targets[0].HasPrefix(lod_root.GetPath())
    h = UsdLod.ScreenSizeHeuristic(heuristic)
    assert h.GetLodDomainAttr().Get() == "imaging"
    thresholds = list(h.GetThresholdsAttr().Get())
    assert len(thresholds) == 3 and thresholds == sorted(thresholds, reverse=True)
    assert thresholds[:2] == pytest.approx([0.25, 0.1])
    lo, hi = h.GetExtentAttr().Get()
    bounds = stats(SPOT)["bounds"]
    assert list(lo) == pytest.approx(bounds["min"]) and list(hi) == pytest.approx(bounds["max"])
    # usd-core's own query picks the full mesh up close and the coarsest far away.
    assert h.ComputeLOD(0.9) == 0.0
    assert h.ComputeLOD(0.2) == 1.0
    assert h.ComputeLOD(0.001) == 3.0

    # Referenced into another stage, the relationship still resolves (a heuristic outside the
    # default prim would be dropped as a target outside the reference's scope).
    scene = tmp_path / "scene.usda"
    layer = Sdf.Layer.CreateNew(str(scene))
    s = Usd.Stage.Open(layer)
    UsdGeom.SetStageUpAxis(s, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(s, 1.0)
    world = UsdGeom.Xform.Define(s, "/World")
    s.SetDefaultPrim(world.GetPrim())
    cow = s.DefinePrim("/World/Cow")
    cow.GetReferences().AddReference(out.name)
    layer.Save()
    s = Usd.Stage.Open(str(scene))
    assert s.GetCompositionErrors() == []
    api = UsdLod.RootAPI(s.GetPrimAtPath("/World/Cow/spot_triangulated"))
    assert api.GetLodHeuristicsRel().GetTargets() == [Sdf.Path("/World/Cow/spot_triangulated_lodHeuristic")]
    assert validate_stage(scene) == []


def test_lod_per_level_files(tmp_path):
    folder = tmp_path / "levels"
    r = tessd_json("lod", SPOT, "--levels", LEVELS, "--out", tmp_path / "cow.usda",
                   "--per-level-dir", folder)
    names = [f"cow_LOD{i}.obj" for i in range(4)]
    assert sorted(p.name for p in folder.iterdir()) == names
    assert r["per_level_files"] == [str(folder / n) for n in names]
    counts = [(SPOT_VERTICES, 5856)] + [(l["output_vertices"], l["output_faces"]) for l in r["levels"]]
    for name, (v, f) in zip(names, counts):
        s = stats(folder / name)
        assert (s["vertices"], s["faces"]) == (v, f), name

    # Without --out, the files are named after the input; other formats on request.
    r = tessd_json("lod", SPOT, "--levels", "10%", "--per-level-dir", folder / "ply",
                   "--per-level-format", "ply")
    assert "output" not in r
    assert sorted(p.name for p in (folder / "ply").iterdir()) == [
        "spot_triangulated_LOD0.ply", "spot_triangulated_LOD1.ply"]


def test_lod_quality_and_grid_levels(tmp_path):
    r = tessd_json("lod", SPOT, "--method", "quality", "--levels", "0.5%,2%,0.1", "--out",
                   tmp_path / "q.usda", "--representative", "quadric")
    tolerances = [l["tolerance"] for l in r["levels"]]
    assert tolerances[2] == 0.1 and tolerances[0] < tolerances[1] < tolerances[2]
    for level in r["levels"]:
        assert level["max_displacement"] <= level["tolerance"]
    assert validate_stage(tmp_path / "q.usda") == []
    v = [l["output_vertices"] for l in r["levels"]]
    assert SPOT_VERTICES > v[0] > v[1] > v[2] > 0 and r["warnings"] == []
    r = tessd_json("lod", SPOT, "--method", "grid", "--levels", "16,8", "--out", tmp_path / "g.usda")
    v = [l["output_vertices"] for l in r["levels"]]
    assert SPOT_VERTICES > v[0] > v[1] > 0 and r["warnings"] == []


@pytest.mark.parametrize("method, levels, reads, suggestion", [
    # The chain: for quality the levels are errors, which grow.
    ("quality", "50%,20%", "which must grow, but LOD2's 20% (0.3436) is not above LOD1's 50% (0.859)",
     "20%,50%"),
    ("quality", "0.1,1%", "LOD2's 1% (0.01718) is not above LOD1's 0.1", "1%,0.1"),
    ("complexity", "20%,50%",
     "which must shrink, but LOD2's 50% (1465 vertices) is not below LOD1's 20% (586 vertices)",
     "50%,20%"),
    ("complexity", "1000,50%", "LOD2's 50% (1465 vertices) is not below LOD1's 1000 vertices",
     "50%,1000"),
    ("complexity", "50%,1465,5%", "LOD2's 1465 vertices is not below LOD1's 50% (1465 vertices)",
     "50%,5%"),
    ("grid", "16,32,8", "the cells per axis, which must shrink, but LOD2's 32 is not below LOD1's 16",
     "32,16,8"),
    ("grid", "8,8", "LOD2's 8 is not below LOD1's 8", "8"),
])
def test_lod_refuses_levels_that_do_not_get_coarser(tmp_path, daemon, method, levels, reads,
                                                    suggestion):
    out = tmp_path / "x.usda"
    run = run_tessd("lod", SPOT, "--method", method, "--levels", levels, "--out", out, check=False)
    assert run.returncode == 1, run.stderr
    assert "`--levels` must get coarser from each level to the next" in run.stderr, run.stderr
    assert f"with method {method} a level is" in run.stderr and reads in run.stderr, run.stderr
    assert run.stderr.rstrip().endswith(f"did you mean {suggestion}?"), run.stderr
    # The op names its parameter; the same chain as a list.
    with tessd.Client(daemon.socket, timeout=60) as c:
        with pytest.raises(TessdError) as info:
            c.call("lod", {"input": str(SPOT), "method": method, "levels": levels.split(","),
                           "output": str(out)})
    e = info.value
    assert e.code == "invalid_request" and e.message.startswith("`levels` must get coarser"), e
    assert reads in e.message and e.message.endswith(f"did you mean {suggestion}?"), e
    assert list(tmp_path.iterdir()) == []
    # The suggestion is a chain that works, and its levels get coarser.
    if "," in suggestion:
        r = tessd_json("lod", SPOT, "--method", method, "--levels", suggestion, "--out", out)
        v = [l["output_vertices"] for l in r["levels"]]
        assert all(a > b for a, b in zip([SPOT_VERTICES] + v, v)), v
        assert r["warnings"] == []


def test_lod_warns_of_a_level_no_coarser_than_the_one_before(tmp_path):
    # Grid cells are not nested: 37 cells per axis keep more of Spot's vertices than 38 do.
    out = tmp_path / "g.usda"
    run = run_tessd("lod", SPOT, "--method", "grid", "--levels", "40,39,38,37,20", "--out", out)
    r = tessd_json("lod", SPOT, "--method", "grid", "--levels", "40,39,38,37,20", "--out", out)
    v = [l["output_vertices"] for l in r["levels"]]
    assert v == [2435, 2405, 2315, 2327, 1236]
    assert r["warnings"] == [
        "LOD4 (goal 37) has 2327 vertices, not fewer than LOD3's 2315: it is no coarser than the "
        "level before it"]
    assert f"warning: {r['warnings'][0]}" in run.stderr
    # A tolerance that moves nothing keeps LOD0 as it is.
    r = tessd_json("lod", SPOT, "--method", "quality", "--levels", "0.000001,1%", "--out", out)
    assert r["levels"][0]["output_vertices"] == SPOT_VERTICES
    assert len(r["warnings"]) == 1 and r["warnings"][0].startswith("LOD1 (goal "), r
    assert f"has {SPOT_VERTICES} vertices, not fewer than LOD0's {SPOT_VERTICES}" in r["warnings"][0]


def test_lod_help_says_how_levels_read():
    text = " ".join(run_tessd("lod", "--help").stdout.split())
    for words in ["each level coarser than the one before",
                  "for --method complexity the vertices to keep", "which shrink",
                  "for quality the largest error", "which grow",
                  "for grid the cells per axis"]:
        assert words in text, words


def test_lod_cli_errors(tmp_path):
    run = run_tessd("lod", SPOT, "--levels", "50%", check=False)
    assert run.returncode != 0 and "--out" in run.stderr
    run = run_tessd("lod", SPOT, "--levels", "50%,abc%", "--out", tmp_path / "x.usda", check=False)
    assert run.returncode == 1 and "`levels[1]` must be a positive number" in run.stderr
    run = run_tessd("lod", SPOT, "--levels", "50%", "--out", tmp_path / "x.obj", check=False)
    assert run.returncode == 1 and "unsupported" in run.stderr
    assert list(tmp_path.iterdir()) == []


def test_lod_over_the_socket(daemon, tmp_path):
    spot = tessd.mesh_to_arrays(*read_obj(SPOT))
    with tessd.Client(daemon.socket, timeout=60) as c:
        # No output: the levels come back as arrays, prefixed `lod<i>.`.
        r, arrays = c.call("lod", {"levels": ["50%", 100]}, spot)
        assert r["levels"][1]["output_vertices"] == 100
        assert arrays["lod1.positions"].shape == (r["levels"][0]["output_vertices"], 3)
        assert arrays["lod2.positions"].shape == (100, 3)
        assert arrays["lod2.face_sizes"].shape == (r["levels"][1]["output_faces"],)
        assert "positions" not in arrays

        out = tmp_path / "y_up.usda"
        r, _ = c.call("lod", {"levels": "50%, 20%", "output": str(out), "lod_schema": "usdlod",
                              "up_axis": "Y", "meters_per_unit": 0.01, "name": "Cow",
                              "default_level": 1}, spot)
        assert validate_stage(out) == []
        stage = Usd.Stage.Open(str(out))
        assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
        assert UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(0.01)
        api = UsdLod.RootAPI(stage.GetPrimAtPath("/Root/Cow"))
        assert api.GetLodDefaultIndexAttr().Get() == 1
        vis = [UsdGeom.Imageable(p).ComputeVisibility() for p in api.GetPrim().GetChildren()]
        assert vis == ["invisible", "inherited", "invisible"]

        for params, code, message in [
            ({}, "invalid_request", "`levels` is required"),
            ({"levels": []}, "invalid_request", "`levels` must hold 1 to"),
            ({"levels": ["50%"], "method": "quality", "max_error": 1}, "invalid_request", "not `max_error`"),
            ({"levels": ["-5%"]}, "invalid_request", "`levels[0]` must be positive, got -5%"),
            ({"levels": [3000]}, "invalid_request", "`levels`: the target of 3000 vertices"),
            ({"levels": ["50%"], "method": "grid"}, "invalid_request", "`levels[0]` must be a positive integer"),
            ({"levels": ["50%"], "lod_schema": "nested"}, "invalid_request", "`lod_schema`"),
            ({"levels": ["50%"], "default_level": 1, "output": str(tmp_path / "v.usda")},
             "invalid_request", "`default_level` applies to"),
            ({"levels": ["50%"], "per_level": True}, "invalid_request", "`per_level: true`"),
            ({"levels": ["50%"], "per_level": str(tmp_path), "per_level_format": "fbx"},
             "unsupported", "`per_level_format`"),
        ]:
            with pytest.raises(TessdError) as info:
                c.call("lod", params, spot)
            assert info.value.code == code and message in info.value.message, (params, info.value)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["y_up.usda"]


def read_obj(path: Path):
    """Positions and faces (0-based) of a triangle OBJ, read independently of tessd."""
    positions, faces = [], []
    for line in open(path):
        if line.startswith("v "):
            positions.append([float(c) for c in line.split()[1:4]])
        elif line.startswith("f "):
            faces.append([int(c.split("/")[0]) - 1 for c in line.split()[1:]])
    return np.asarray(positions, dtype=np.float32), faces


def test_lod_of_a_mesh_with_unreferenced_vertices(tmp_path):
    # The bunny stores 35947 vertices, 1113 of them unreferenced: targets count the referenced
    # ones, and LOD0 is the input as it is.
    bunny = next(m for m in shared_meshes() if m.name == "stanford_bunny.obj")
    out = tmp_path / "bunny.usda"
    r = tessd_json("lod", bunny, "--levels", "5%", "--out", out, "--lod-schema", "usdlod")
    assert r["input_vertices"] == 35947 - 1113
    assert r["lod0"] == {"points": 35947, "faces": 69451}
    assert r["levels"][0]["target_vertices"] == target(5, 35947 - 1113) == 1742
    assert r["levels"][0]["output_vertices"] == 1742
    assert validate_stage(out) == []
    stage = Usd.Stage.Open(str(out))
    items = stage.GetPrimAtPath("/Root/stanford_bunny").GetChildren()
    assert [points(p) for p in items] == [35947, 1742]
