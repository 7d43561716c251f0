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


# ------------------------------------------------------------------------------------------
# References and payloads (what the Blender add-on's export_usd writes)


def _part_layer(path: Path, seed: int, translate=None, default: bool = True) -> None:
    """A layer written by usd-core: `/Part` (an Xform, translated when asked) holding a bumpy
    grid mesh, its defaultPrim."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    part = UsdGeom.Xform.Define(stage, "/Part")
    if translate is not None:
        part.AddTranslateOp().Set(Gf.Vec3d(*translate))
        part.AddRotateXYZOp().Set(Gf.Vec3f(30, 0, 45))
    define_mesh(stage, "/Part/geo", *grid(3, seed=seed))
    if default:
        stage.SetDefaultPrim(part.GetPrim())
    stage.GetRootLayer().Save()


def _matrix(tx: float, ty: float, tz: float, angle: float) -> Gf.Matrix4d:
    """A world matrix as the add-on writes it (`matrix4d xformOp:transform`)."""
    m = Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(1, 0, 0), angle))
    m.SetTranslateOnly(Gf.Vec3d(tx, ty, tz))
    return m


@pytest.fixture
def assembly(tmp_path, shared_data) -> Path:
    """What `export_usd` writes for three objects: `scene.usda` (usd-core here) with one Xform
    per object carrying its world matrix as `xformOp:transform` and `prepend references =
    @./scene_<name>.usda@`, beside the objects' own stages. One object's stage is what the
    daemon's `mesh.convert` writes for the add-on (tessd's writer), the others usd-core's:
    one with its own transform on the referenced prim, one reached through a payload and a
    second reference from a subfolder, one referenced twice (instanced)."""
    run_tessd("convert", shared_data / "mesh/spot_triangulated.obj", tmp_path / "scene_Spot.usda")
    _part_layer(tmp_path / "scene_Plate.usda", 1, translate=(0, 0, 2))
    (tmp_path / "parts").mkdir()
    _part_layer(tmp_path / "parts/inner.usda", 2)
    # A layer whose default prim has a payload to a sibling file (resolved relative to itself).
    stage = Usd.Stage.CreateNew(str(tmp_path / "parts/holder.usda"))
    holder = UsdGeom.Xform.Define(stage, "/Holder")
    holder.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    holder.GetPrim().GetPayloads().AddPayload("./inner.usda")
    stage.SetDefaultPrim(holder.GetPrim())
    stage.GetRootLayer().Save()

    path = tmp_path / "scene.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    scene = UsdGeom.Xform.Define(stage, "/Scene")
    stage.SetDefaultPrim(scene.GetPrim())
    for name, file, m in [("Spot", "./scene_Spot.usda", _matrix(1, 2, 3, 90)),
                          ("Plate", "./scene_Plate.usda", None),
                          ("Holder", "parts/holder.usda", _matrix(-4, 0, 0, 0)),
                          ("Spot_001", "./scene_Spot.usda", _matrix(0, 5, 0, -90))]:
        x = UsdGeom.Xform.Define(stage, "/Scene/" + name)
        if m is not None:
            x.AddTransformOp().Set(m)
        x.GetPrim().GetReferences().AddReference(file)
    stage.GetRootLayer().Save()
    text = path.read_text()
    assert "prepend references = @./scene_Spot.usda@" in text
    return path


def test_references_and_payloads_compose_as_usd_core_does(assembly):
    stage = Usd.Stage.Open(str(assembly))
    ref = reference(stage)
    got = stats(assembly)
    # Two spots, the plate's grid, the holder's grid: all four reached.
    assert ref["faces"] == 2 * 5856 + 2 * 9
    assert_matches(got, ref)
    # Each object alone where usd-core puts it (the referenced prim's own transform kept under
    # a referencing prim without one; the payload's scale under the holder's matrix): the
    # others deactivated in a copy of the assembly beside it.
    for name in ("Spot", "Plate", "Holder", "Spot_001"):
        one = Usd.Stage.Open(str(assembly))
        for other in ("Spot", "Plate", "Holder", "Spot_001"):
            if other != name:
                one.GetPrimAtPath("/Scene/" + other).SetActive(False)
        alone = assembly.with_name(f"only_{name}.usda")
        one.GetRootLayer().Export(str(alone))
        one.GetRootLayer().Reload(True)  # the assembly's layer is shared by the next Open
        one_ref = reference(Usd.Stage.Open(str(alone)))
        assert one_ref["faces"] == (5856 if name.startswith("Spot") else 9)
        assert_matches(stats(alone), one_ref)


def test_a_stage_reached_through_references_renders(assembly, tmp_path, daemon):
    out = tmp_path / "scene.png"
    r = json.loads(run_tessd("render", assembly, out, "--size", "96x64", "--json").stdout)
    assert r["triangles"] == 2 * 5856 + 2 * 18
    assert r["covered"] > 100 and out.exists()
    # Over the socket too: mesh.stats of the assembly.
    with tessd.Client(daemon.socket, timeout=60) as c:
        s, _ = c.call("mesh.stats", {"input": str(assembly)})
    assert s["faces"] == 2 * 5856 + 2 * 9


def test_arcs_tessd_does_not_follow_are_refused_naming_them(tmp_path):
    _part_layer(tmp_path / "part.usda", 3)
    assert Usd.Stage.Open(str(tmp_path / "part.usda")).Export(str(tmp_path / "part.usdc"))
    path = tmp_path / "s.usda"
    stage = Usd.Stage.CreateNew(str(path))
    stage.DefinePrim("/A").GetReferences().AddReference("./part.usdc")
    stage.GetRootLayer().Save()
    # usd-core composes it; tessd says which arc of which prim it does not follow, and how.
    assert reference(Usd.Stage.Open(str(path)))["faces"] == 9
    run = run_tessd("stats", path, check=False)
    assert run.returncode == 1
    assert "unsupported:" in run.stderr
    assert "/A: references @./part.usdc@: only .usda layers are followed, not .usdc" in run.stderr
    assert str(path) in run.stderr and "usdcat" in run.stderr
    # A missing file names the arc and the resolved path.
    path.write_text(path.read_text().replace("part.usdc", "gone.usda"))
    run = run_tessd("stats", path, check=False)
    assert run.returncode == 1 and "io:" in run.stderr
    assert "gone.usda (/A: references @./gone.usda@" in run.stderr, run.stderr
    # A cycle: a layer referencing itself through another.
    for a, b in (("x", "y"), ("y", "x")):
        s = Usd.Stage.CreateNew(str(tmp_path / f"{a}.usda"))
        p = s.DefinePrim(f"/{a.upper()}")
        p.GetReferences().AddReference(f"./{b}.usda")
        s.SetDefaultPrim(p)
        s.GetRootLayer().Save()
    run = run_tessd("stats", tmp_path / "x.usda", check=False)
    assert run.returncode == 1 and "a cycle of references" in run.stderr, run.stderr
