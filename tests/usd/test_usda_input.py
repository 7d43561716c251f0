"""`.usda` stages as mesh inputs, checked against real usd-core (an independent writer).

usd-core (``pxr``) writes the stages: meshes under transformed Xforms (translate, scale,
rotateXYZ, orient, pivots with ``!invert!``), time-sampled points, an invisible mesh, a variant
set of three meshes of different face counts beside a mesh outside it. ``tessd stats
STAGE.usda --json`` must report the counts and bounds that usd-core computes for the same
stage (points x ``ComputeLocalToWorldTransform`` at the earliest time, over the meshes the
default traversal shows in the selected variant). Binary crate files (usd-core's ``.usdc``)
and truncated stages give clear errors, on the command line and over the socket.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from pxr import Gf, Usd, UsdGeom, Vt

import locate
import tessd

TESSD = str(locate.tessd_bin())
EARLY = Usd.TimeCode.EarliestTime()


def run_tessd(*args, check: bool = True) -> subprocess.CompletedProcess:
    run = subprocess.run([TESSD, *map(str, args)], capture_output=True, text=True, timeout=120)
    if check:
        assert run.returncode == 0, run.stderr
    return run


def stats(path: Path) -> dict:
    return json.loads(run_tessd("stats", path, "--json").stdout)


def grid(n: int, z: float = 0.0, seed: int = 0):
    """An n x n grid of quads with bumpy heights: points, counts, indices."""
    rng = np.random.default_rng(seed)
    pts = [(i / n, j / n, z + float(rng.uniform(-0.2, 0.2))) for j in range(n + 1) for i in range(n + 1)]
    counts, indices = [], []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            counts.append(4)
            indices += [a, a + 1, a + n + 2, a + n + 1]
    return pts, counts, indices


def define_mesh(stage: Usd.Stage, path: str, pts, counts, indices) -> UsdGeom.Mesh:
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(Vt.Vec3fArray([Gf.Vec3f(*p) for p in pts]))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(indices))
    mesh.CreateExtentAttr(UsdGeom.PointBased.ComputeExtent(mesh.GetPointsAttr().Get()))
    return mesh


def reference(stage: Usd.Stage) -> dict:
    """What usd-core shows: counts and the bounds of the referenced points in world space."""
    faces = triangles = stored = 0
    used = []
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        if UsdGeom.Imageable(prim).ComputeVisibility(EARLY) == UsdGeom.Tokens.invisible:
            continue
        mesh = UsdGeom.Mesh(prim)
        pts = np.array(mesh.GetPointsAttr().Get(EARLY), dtype=np.float64)
        counts = np.array(mesh.GetFaceVertexCountsAttr().Get(EARLY))
        idx = np.array(mesh.GetFaceVertexIndicesAttr().Get(EARLY))
        xf = np.array(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(EARLY))
        world = np.c_[pts, np.ones(len(pts))] @ xf
        world = world[:, :3] / world[:, 3:]
        faces += len(counts)
        triangles += int((counts - 2).sum())
        stored += len(pts)
        used.append(world[np.unique(idx)])
    used = np.concatenate(used)
    return {
        "faces": faces,
        "triangles": triangles,
        "stored_vertices": stored,
        "min": used.min(axis=0),
        "max": used.max(axis=0),
    }


def assert_matches(got: dict, ref: dict) -> None:
    assert got["faces"] == ref["faces"]
    assert got["triangles"] == ref["triangles"]
    assert got["stored_vertices"] == ref["stored_vertices"]
    scale = max(1.0, float(np.abs(ref["max"]).max()), float(np.abs(ref["min"]).max()))
    # tessd holds positions in f32: half an f32 ulp of the coordinates, plus the double
    # arithmetic's order of operations.
    tol = 4 * np.finfo(np.float32).eps * scale
    np.testing.assert_allclose(got["bounds"]["min"], ref["min"], rtol=0, atol=tol)
    np.testing.assert_allclose(got["bounds"]["max"], ref["max"], rtol=0, atol=tol)


@pytest.fixture
def transformed_stage(tmp_path) -> Path:
    path = tmp_path / "transformed.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 0.001)
    root = UsdGeom.Xform.Define(stage, "/Root")
    root.AddTranslateOp().Set(Gf.Vec3d(10, -5, 2.5))
    root.AddRotateXYZOp().Set(Gf.Vec3f(30, 45, 60))
    stage.SetDefaultPrim(root.GetPrim())

    # translate + scale on the mesh itself.
    a = define_mesh(stage, "/Root/A", *grid(5, seed=1))
    a.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    a.AddScaleOp().Set(Gf.Vec3f(2, 0.5, 3))

    # A nested Xform with orient about a pivot (translate:pivot ... !invert!translate:pivot).
    sub = UsdGeom.Xform.Define(stage, "/Root/Sub")
    sub.AddTranslateOp(opSuffix="pivot").Set(Gf.Vec3d(0.5, 0.5, 0))
    sub.AddOrientOp().Set(Gf.Quatf(0.8, 0.36, 0.48, 0))
    sub.AddTranslateOp(opSuffix="pivot", isInverseOp=True)
    b = define_mesh(stage, "/Root/Sub/B", *grid(3, z=1.0, seed=2))
    b.AddTransformOp().Set(Gf.Matrix4d(1).SetScale(Gf.Vec3d(1, 1, 4)).SetTranslateOnly(Gf.Vec3d(0, 0, -7)))
    # Time-sampled points: the earliest sample is what a viewer shows first.
    pts, _, _ = grid(3, z=1.0, seed=2)
    b.GetPointsAttr().Set(Vt.Vec3fArray([Gf.Vec3f(x, y, z + 5) for x, y, z in pts]), 2.0)
    b.GetPointsAttr().Set(Vt.Vec3fArray([Gf.Vec3f(x, y, z - 5) for x, y, z in pts]), 1.0)

    # Invisible: not shown.
    hidden = define_mesh(stage, "/Root/Hidden", *grid(2, z=100.0))
    hidden.CreateVisibilityAttr(UsdGeom.Tokens.invisible)
    stage.GetRootLayer().Save()
    return path


def test_transforms_match_usd_core(transformed_stage):
    stage = Usd.Stage.Open(str(transformed_stage))
    ref = reference(stage)
    assert ref["faces"] == 25 + 9
    got = stats(transformed_stage)
    assert_matches(got, ref)
    assert got["face_sizes"] == {"4": 34}


def test_translate_scale_bounds_match_bbox_cache(tmp_path):
    """Axis-aligned transforms only, so usd-core's BBoxCache (from the authored extent) is the
    exact box of the points."""
    path = tmp_path / "box.usda"
    stage = Usd.Stage.CreateNew(str(path))
    root = UsdGeom.Xform.Define(stage, "/Root")
    root.AddScaleOp().Set(Gf.Vec3f(10, 10, 10))
    m = define_mesh(stage, "/Root/M", *grid(4, seed=3))
    m.AddTranslateOp().Set(Gf.Vec3d(-3, 4, 0.5))
    m.AddScaleOp().Set(Gf.Vec3f(1, 2, -1))
    stage.GetRootLayer().Save()

    cache = UsdGeom.BBoxCache(EARLY, [UsdGeom.Tokens.default_])
    box = cache.ComputeWorldBound(stage.GetPrimAtPath("/Root")).ComputeAlignedRange()
    got = stats(path)
    np.testing.assert_allclose(got["bounds"]["min"], list(box.GetMin()), rtol=0, atol=1e-5)
    np.testing.assert_allclose(got["bounds"]["max"], list(box.GetMax()), rtol=0, atol=1e-5)
    assert_matches(got, reference(stage))


def variant_stage(path: Path, selection: str) -> Usd.Stage:
    """/Root with a mesh outside any variant and a variant set LOD of three grids."""
    stage = Usd.Stage.CreateNew(str(path))
    root = UsdGeom.Xform.Define(stage, "/Root")
    root.AddTranslateOp().Set(Gf.Vec3d(0, 0, 1))
    define_mesh(stage, "/Root/base", *grid(1, z=-1.0))
    vset = root.GetPrim().GetVariantSets().AddVariantSet("LOD")
    for k, (name, n) in enumerate([("LOD0", 8), ("LOD1", 4), ("LOD2", 2)]):
        vset.AddVariant(name)
        vset.SetVariantSelection(name)
        with vset.GetVariantEditContext():
            m = define_mesh(stage, "/Root/grid", *grid(n, z=float(k), seed=k))
            m.AddScaleOp().Set(Gf.Vec3f(1 + k, 1, 1))
    vset.SetVariantSelection(selection)
    stage.GetRootLayer().Save()
    return stage


@pytest.mark.parametrize("selection,grid_faces", [("LOD0", 64), ("LOD1", 16), ("LOD2", 4)])
def test_selected_variant_is_read(tmp_path, selection, grid_faces):
    path = tmp_path / f"lods_{selection}.usda"
    stage = variant_stage(path, selection)
    ref = reference(stage)
    assert ref["faces"] == 1 + grid_faces
    assert_matches(stats(path), ref)


def test_our_lod_stage_reads_as_level_0(tmp_path, shared_data):
    spot = shared_data / "mesh" / "spot_triangulated.obj"
    out = tmp_path / "spot_lods.usda"
    run_tessd("lod", spot, "--levels", "50%,20%", "--out", out)
    got = stats(out)
    stage = Usd.Stage.Open(str(out))
    assert_matches(got, reference(stage))
    assert got["faces"] == stats(spot)["faces"]
    # And it can be fed to the other operations.
    obj = tmp_path / "lod0.obj"
    run_tessd("convert", out, obj)
    assert stats(obj)["faces"] == got["faces"]
    run_tessd("simplify", out, tmp_path / "half.obj", "--method", "complexity", "--target-vertices", "50%")


def test_binary_crate_files_are_refused(tmp_path):
    stage = variant_stage(tmp_path / "v.usda", "LOD1")
    usdc = tmp_path / "v.usdc"
    assert stage.Export(str(usdc))
    assert usdc.read_bytes().startswith(b"PXR-USDC")
    run = run_tessd("stats", usdc, check=False)
    assert run.returncode == 1
    assert "unsupported" in run.stderr and "binary crate files are not read" in run.stderr
    assert ".usda" in run.stderr


def test_truncated_stage_names_the_line(tmp_path):
    variant_stage(tmp_path / "v.usda", "LOD1")
    text = (tmp_path / "v.usda").read_text()
    cut = tmp_path / "cut.usda"
    cut.write_text(text[: len(text) * 2 // 3])
    run = run_tessd("stats", cut, check=False)
    assert run.returncode == 1
    assert f"invalid_mesh: {cut}:" in run.stderr, run.stderr
    line = int(run.stderr.split(f"{cut}:")[1].split(":")[0])
    assert 1 <= line <= text.count("\n") + 1


def test_usda_input_over_the_socket(daemon, tmp_path):
    path = tmp_path / "v.usda"
    stage = variant_stage(path, "LOD2")
    variant_stage(tmp_path / "w.usda", "LOD2").Export(str(tmp_path / "w.usdc"))
    with tessd.Client(daemon.socket, timeout=60) as c:
        r, _ = c.call("mesh.stats", {"input": str(path)})
        assert_matches(r, reference(stage))
        with pytest.raises(tessd.TessdError) as e:
            c.call("mesh.stats", {"input": str(tmp_path / "w.usdc")})
        assert e.value.code == "unsupported"
        assert "capabilities" in c.hello() and "usd.read.usda" in c.hello()["capabilities"]


def test_render_draws_a_usd_core_lod_stage_one_panel_per_variant(tmp_path):
    """A LOD chain written by usd-core (an independent writer): a variant set `LOD` of three
    meshes on a root Xform, plus a mesh outside the set. `tessd render STAGE OUT.png` draws one
    panel per variant, in the set's order, each with the variant's triangles plus the shared
    mesh's, and each panel is exactly the picture of that variant selected alone (the stage
    saved with that selection: in a list of inputs a stage is one panel, what it shows by
    default)."""
    stage_path = tmp_path / "chain.usda"
    stage = Usd.Stage.CreateNew(str(stage_path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    root = UsdGeom.Xform.Define(stage, "/Root").GetPrim()
    stage.SetDefaultPrim(root)
    define_mesh(stage, "/Root/base", *grid(2, z=-1.0, seed=9))
    vset = root.GetVariantSets().AddVariantSet("LOD")
    sizes = {"LOD0": 12, "LOD1": 6, "LOD2": 3}
    for name, n in sizes.items():
        vset.AddVariant(name)
        vset.SetVariantSelection(name)
        with vset.GetVariantEditContext():
            define_mesh(stage, "/Root/part", *grid(n, seed=n))
    vset.SetVariantSelection("LOD0")
    stage.GetRootLayer().Save()

    cam = ["--eye", "2.5,-2,2", "--target", "0.5,0.5,-0.5", "--up", "0,0,1"]
    out = tmp_path / "chain.png"
    r = json.loads(run_tessd("render", stage_path, out, "--size", "64x48", *cam, "--json").stdout)
    base_tris = 2 * 2 * 2
    assert [p["label"] for p in r["panels"]] == list(sizes)
    assert [p["triangles"] for p in r["panels"]] == [2 * n * n + base_tris for n in sizes.values()]
    assert (r["width"], r["height"]) == (3 * 64, 48)
    from png_decode import read_png
    grid_png = np.asarray(read_png(out))
    for i, name in enumerate(sizes):
        vset.SetVariantSelection(name)
        one = tmp_path / f"{name}.usda"
        stage.GetRootLayer().Export(str(one))
        # In a list, each stage is one panel: the variant usd-core selected (twice, stacked).
        alone = tmp_path / f"{name}.png"
        ra = json.loads(run_tessd("render", one, one, alone, "--size", "64x48", *cam,
                                  "--columns", "1", "--json").stdout)
        assert ra["panels"][0]["triangles"] == r["panels"][i]["triangles"]
        assert np.array_equal(grid_png[:, 64 * i:64 * (i + 1)], np.asarray(read_png(alone))[:48])
