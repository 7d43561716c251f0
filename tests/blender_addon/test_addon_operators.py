"""Every operator through bpy.ops with parameters, against the real daemon; counts checked
against the daemon's CLI on the same mesh exported by Blender's PLY exporter."""

from __future__ import annotations

import numpy as np
import pytest

import scenes
from scenes import cli, counts, same_matrix, export_mesh, names, scene_state, select


@pytest.fixture
def bpy(addon):
    import bpy as _bpy

    scenes.empty_scene()
    return _bpy


SIMPLIFY_CASES = [
    (dict(method='GRID', cells=8), ["--method", "grid", "--cells", "8"]),
    (dict(method='GRID', use_cell_size=True, cell_size=0.2, representative='HEAVIEST'),
     ["--method", "grid", "--cell-size", "0.2", "--representative", "heaviest"]),
    (dict(method='QUALITY', max_error=2.0, max_error_relative=True, representative='QUADRIC'),
     ["--method", "quality", "--max-error", "2%", "--representative", "quadric"]),
    (dict(method='QUALITY', max_error=0.05, max_error_relative=False, representative='HEAVIEST'),
     ["--method", "quality", "--max-error", "0.05", "--representative", "heaviest"]),
    (dict(method='COMPLEXITY', target=25.0, target_is_percent=True),
     ["--method", "complexity", "--target-vertices", "25%"]),
    (dict(method='COMPLEXITY', target=120, target_is_percent=False, representative='QUADRIC'),
     ["--method", "complexity", "--target-vertices", "120", "--representative", "quadric"]),
]


@pytest.mark.parametrize("props,args", SIMPLIFY_CASES, ids=lambda x: str(x)[:40])
def test_simplify_matches_cli(bpy, tmp_path, props, args):
    src = scenes.suzanne()
    ref = cli("simplify", str(export_mesh(src, tmp_path / "in.ply")), str(tmp_path / "out.obj"), *args)
    select(src)
    assert bpy.ops.tessd.simplify(**props) == {'FINISHED'}
    assert names() == ["Suzanne", "Suzanne_simplified"]
    out = bpy.data.objects["Suzanne_simplified"]
    assert counts(out) == (ref["output_vertices"], ref["output_faces"])
    assert counts(out)[0] < counts(src)[0]
    assert bpy.context.view_layer.objects.active == out and out.select_get()


def test_simplify_show_partition(bpy, tmp_path):
    src = scenes.suzanne()
    ref = cli("simplify", str(export_mesh(src, tmp_path / "in.ply")), str(tmp_path / "out.obj"),
              "--method", "complexity", "--target-vertices", "30%")
    select(src)
    assert bpy.ops.tessd.simplify(method='COMPLEXITY', target=30, target_is_percent=True,
                                  show_partition=True) == {'FINISHED'}
    assert names() == ["Suzanne", "Suzanne_partition", "Suzanne_simplified"]
    part = bpy.data.objects["Suzanne_partition"]
    assert part.display_type == 'WIRE'
    assert len(part.data.vertices) == 8 * ref["clusters"]
    assert len(part.data.edges) == 12 * ref["clusters"] and len(part.data.polygons) == 0
    assert same_matrix(part.matrix_world, src.matrix_world)
    # every vertex of the input lies in a cell
    co = np.empty(len(src.data.vertices) * 3, np.float32)
    src.data.vertices.foreach_get("co", co)
    box = np.empty(len(part.data.vertices) * 3, np.float32)
    part.data.vertices.foreach_get("co", box)
    box = box.reshape(-1, 8, 3)
    lo, hi = box.min(axis=1), box.max(axis=1)
    p = co.reshape(-1, 3)
    inside = ((p[:, None, :] >= lo[None] - 1e-5) & (p[:, None, :] <= hi[None] + 1e-5)).all(axis=2)
    assert inside.any(axis=1).all()


def test_simplify_keeps_transform_materials_uvs_normals(bpy):
    src = scenes.two_material_cube()
    select(src)
    assert bpy.ops.tessd.simplify(method='GRID', cells=4) == {'FINISHED'}
    out = bpy.data.objects["Painted_simplified"]
    assert same_matrix(out.matrix_world, src.matrix_world)
    assert [m.name for m in out.data.materials] == ["Red", "Blue"]
    assert out.users_collection == src.users_collection
    mats = np.empty(len(out.data.polygons), np.int32)
    out.data.polygons.foreach_get("material_index", mats)
    assert sorted(set(mats.tolist())) == [0, 1]
    assert [uv.name for uv in out.data.uv_layers] == ["UVMap"]
    # a cube at 4 cells keeps its 8 corners and 6 faces
    assert counts(out) == (8, 6)
    # UVs and normals come back per corner (the daemon averages them per cell and face group,
    # docs/simplify.md), so they lie within the source's ranges
    uv_src = np.empty(len(src.data.loops) * 2, np.float32)
    src.data.uv_layers.active.data.foreach_get("uv", uv_src)
    uv_out = np.empty(len(out.data.loops) * 2, np.float32)
    out.data.uv_layers.active.data.foreach_get("uv", uv_out)
    assert uv_out.min() >= uv_src.min() - 1e-6 and uv_out.max() <= uv_src.max() + 1e-6
    assert len(set(map(tuple, uv_out.reshape(-1, 2).round(5)))) > 1
    # Blender's own normals by default: the cube's flat faces come back flat
    assert not out.data.has_custom_normals
    flat = np.zeros(len(out.data.polygons), bool)
    out.data.attributes["sharp_face"].data.foreach_get("value", flat)
    assert flat.all()
    # custom normals on request: the input's corner normals averaged per cell and group
    select(src)
    assert bpy.ops.tessd.simplify(method='GRID', cells=4, normals='CUSTOM') == {'FINISHED'}
    out = bpy.data.objects["Painted_simplified.001"]
    assert out.data.has_custom_normals
    n = np.empty(len(out.data.loops) * 3, np.float32)
    out.data.corner_normals.foreach_get("vector", n)
    assert np.allclose(np.linalg.norm(n.reshape(-1, 3), axis=1), 1.0, atol=1e-4)


def test_simplify_replace(bpy):
    src = scenes.suzanne()
    before = counts(src)
    select(src)
    assert bpy.ops.tessd.simplify(method='QUALITY', max_error=3.0, replace=True) == {'FINISHED'}
    assert names() == ["Suzanne"]
    assert counts(bpy.data.objects["Suzanne"])[0] < before[0]


def test_simplify_several_objects_and_modifiers(bpy, tmp_path):
    a = scenes.suzanne("A")
    b = scenes.suzanne("B")  # at the origin: the PLY exporter writes world coordinates
    mod = b.modifiers.new("sub", 'SUBSURF')
    mod.levels = 1
    ref = cli("simplify", str(export_mesh(b, tmp_path / "b.ply")), str(tmp_path / "o.obj"),
              "--method", "grid", "--cells", "10")
    select(a, b)
    assert bpy.ops.tessd.simplify(method='GRID', cells=10) == {'FINISHED'}
    assert names() == ["A", "A_simplified", "B", "B_simplified"]
    assert counts(bpy.data.objects["B_simplified"]) == (ref["output_vertices"], ref["output_faces"])
    assert same_matrix(bpy.data.objects["B_simplified"].matrix_world, b.matrix_world)
    select(b)
    assert bpy.ops.tessd.simplify(method='GRID', cells=10, use_modifiers=False) == {'FINISHED'}
    assert counts(bpy.data.objects["B_simplified.001"])[0] < counts(bpy.data.objects["B_simplified"])[0] + 1


def test_generate_lods(bpy, tmp_path):
    from pxr import Usd

    src = scenes.suzanne()
    obj_in = export_mesh(src, tmp_path / "in.ply")
    ref = cli("lod", str(obj_in), "--levels", "50%,20%,5%", "--out", str(tmp_path / "ref.usda"))
    select(src)
    usd = tmp_path / "lods.usda"
    assert bpy.ops.tessd.generate_lods(levels="50%,20%,5%", usd_path=str(usd)) == {'FINISHED'}
    coll = bpy.data.collections["Suzanne_LODs"]
    assert sorted(o.name for o in coll.objects) == ["Suzanne_LOD%d" % i for i in range(4)]
    assert counts(bpy.data.objects["Suzanne_LOD0"]) == counts(src)
    for i, level in enumerate(ref["levels"], start=1):
        assert counts(bpy.data.objects["Suzanne_LOD%d" % i]) == (
            level["output_vertices"], level["output_faces"])
    for o in coll.objects:
        assert same_matrix(o.matrix_world, src.matrix_world)
    assert (tmp_path / "lods_Suzanne.usda").is_file()  # the object's chain, usd references it
    stage = Usd.Stage.Open(str(usd))
    root = lod_prim(stage)
    vset = root.GetVariantSets().GetVariantSet("LOD")
    assert vset.GetVariantNames() == ["LOD0", "LOD1", "LOD2", "LOD3"]
    assert vset.GetVariantSelection() == "LOD0"
    vset.SetVariantSelection("LOD2")
    mesh = [p for p in stage.Traverse() if p.GetTypeName() == "Mesh"][0]
    assert len(mesh.GetAttribute("points").Get()) == ref["levels"][1]["output_vertices"]


def lod_prim(stage):
    """The prim holding the `LOD` variant set (the object's, below the assembly's Xform)."""
    [prim] = [p for p in stage.Traverse() if p.GetVariantSets().HasVariantSet("LOD")]
    return prim


def world_bounds(obj):
    """(min, max) of the object's vertices in world space, as Blender places them."""
    m = np.array(obj.matrix_world, dtype=np.float64)
    co = np.empty(len(obj.data.vertices) * 3, dtype=np.float64)
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
    return co.min(axis=0), co.max(axis=0)


@pytest.mark.parametrize("count", [1, 2])
def test_generate_lods_usd_has_the_world_transform(bpy, tmp_path, count):
    """Issue 32: with one object selected the stage held object-space points and no transform
    (an OBJ import, rotated 90° about X, lay on its back); with two it was right. Now one
    object is written as two are: its file, referenced under an Xform with its world matrix."""
    from pxr import Usd, UsdGeom

    objs = []
    for i in range(count):
        obj = scenes.suzanne("Monkey%d" % i)
        obj.rotation_euler = (np.pi / 2, 0.0, 0.3 * i)  # as Blender's OBJ importer leaves it
        obj.location = (1.5 + 4 * i, -2.0, 0.75)
        obj.scale = (2.0, 2.0, 2.0)
        objs.append(obj)
    bpy.context.view_layer.update()
    select(*objs)
    usd = tmp_path / "lods.usda"
    assert bpy.ops.tessd.generate_lods(levels="50%", usd_path=str(usd)) == {'FINISHED'}
    stage = Usd.Stage.Open(str(usd))
    assert UsdGeom.GetStageUpAxis(stage) == "Z"
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == count
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_])
    for obj in objs:
        [mesh] = [p for p in meshes if str(p.GetPath()).split("/")[2] == obj.name]
        xf = UsdGeom.Xformable(mesh).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        want = np.array(obj.matrix_world, dtype=np.float64).T  # USD: row vectors
        print("\n%s %s world transform:\n%s" % (obj.name, mesh.GetPath(), np.array(xf)))
        assert np.allclose(np.array(xf), want, atol=1e-6), (np.array(xf), want)
        # The stage's points (LOD0, the default variant) placed by the stage's transform.
        points = np.array(UsdGeom.Mesh(mesh).GetPointsAttr().Get(), dtype=np.float64)
        world = np.c_[points, np.ones(len(points))] @ np.array(xf)
        lo, hi = world_bounds(obj)
        print("bounds: usd %s %s, blender %s %s" % (world[:, :3].min(0), world[:, :3].max(0),
                                                   lo, hi))
        # lying on its back would swap the Y and Z extents
        assert np.allclose(world[:, :3].min(axis=0), lo, atol=1e-4)
        assert np.allclose(world[:, :3].max(axis=0), hi, atol=1e-4)
        # usd-core's own bound agrees (an axis-aligned box holding the points)
        box = cache.ComputeWorldBound(mesh).ComputeAlignedRange()
        assert np.all(np.array(box.GetMin()) <= lo + 1e-4)
        assert np.all(np.array(box.GetMax()) >= hi - 1e-4)


def test_generate_lods_side_by_side_without_usd(bpy, tmp_path):
    a = scenes.suzanne("A")
    b = scenes.two_material_cube("Box")
    select(a, b)
    assert bpy.ops.tessd.generate_lods(levels="50%", side_by_side=True) == {'FINISHED'}
    assert {"A_LODs", "Box_LODs"} <= {c.name for c in bpy.data.collections}
    assert names("A_LOD") == ["A_LOD0", "A_LOD1"]
    assert bpy.data.objects["A_LOD1"].matrix_world.translation.x > 1.0
    assert [m.name for m in bpy.data.objects["Box_LOD1"].data.materials] == ["Red", "Blue"]
    assert list(tmp_path.iterdir()) == []


def test_subdivide_matches_cli_and_keeps_creases(bpy, tmp_path):
    src = scenes.creased_cube()
    ref = cli("subdivide", str(export_mesh(src, tmp_path / "in.ply")), str(tmp_path / "o.obj"),
              "--levels", "2")
    select(src)
    assert bpy.ops.tessd.subdivide(scheme='CATMULL_CLARK', levels=2, use_gpu=False) == {'FINISHED'}
    out = bpy.data.objects["CreasedCube_subdiv"]
    assert counts(out) == (ref["vertices"], ref["faces"])
    crease = np.empty(len(out.data.edges), np.float32)
    out.data.attributes["crease_edge"].data.foreach_get("value", crease)
    assert (crease == 1.0).sum() == 4 * 4  # each creased cage edge became 4 edges
    # The creased top edges stay sharp: the top corners do not move down like the bottom ones.
    co = np.empty(len(out.data.vertices) * 3, np.float32)
    out.data.vertices.foreach_get("co", co)
    z = co.reshape(-1, 3)[:, 2]
    assert z.max() == pytest.approx(1.0, abs=1e-6) and z.min() > -1.0 + 0.1
    assert [uv.name for uv in out.data.uv_layers] == ["UVMap"]


SCHEME_CASES = [("BILINEAR", "bilinear", "suzanne"), ("DOO_SABIN", "doo-sabin", "suzanne"),
                ("LOOP", "loop", "icosphere"), ("BUTTERFLY", "butterfly", "icosphere"),
                ("SQRT3", "sqrt3", "icosphere"), ("CATMULL_CLARK", "catmull-clark", "suzanne")]


@pytest.mark.parametrize("scheme,cli_scheme,scene", SCHEME_CASES, ids=[c[0] for c in SCHEME_CASES])
def test_subdivide_schemes_match_cli(bpy, tmp_path, scheme, cli_scheme, scene):
    if scene == "suzanne":
        src = scenes.suzanne()
    elif scene == "cube":
        src = scenes.creased_cube()
    else:
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=2)
        src = bpy.context.object
    ref = cli("subdivide", str(export_mesh(src, tmp_path / "in.ply")), str(tmp_path / "o.obj"),
              "--levels", "2", "--scheme", cli_scheme, "--boundary", "edge-and-corner")
    select(src)
    assert bpy.ops.tessd.subdivide(scheme=scheme, levels=2, boundary='EDGE_AND_CORNER') == {'FINISHED'}
    assert counts(bpy.data.objects[src.name + "_subdiv"]) == (ref["vertices"], ref["faces"])


def test_subdivide_leaves_loose_vertices_out(bpy, tmp_path):
    """Loose vertices (the daemon refuses them: subdivision has no rule for one) are not sent:
    the result equals the CLI's on the mesh without them."""
    src = scenes.suzanne()
    ref = cli("subdivide", str(export_mesh(src, tmp_path / "in.ply")), str(tmp_path / "o.obj"),
              "--levels", "1")
    src.data.vertices.add(2)
    src.data.vertices[-1].co = (5.0, 5.0, 5.0)
    src.data.update()
    select(src)
    assert bpy.ops.tessd.subdivide(levels=1) == {'FINISHED'}
    assert counts(bpy.data.objects["Suzanne_subdiv"]) == (ref["vertices"], ref["faces"])


def test_subdivide_on_the_gpu_equals_the_cpu(bpy):
    """use_gpu runs the apply phase on the GPU (lavapipe in CI): same mesh as the CPU."""
    src = scenes.creased_cube()
    select(src)
    assert bpy.ops.tessd.subdivide(levels=3, use_gpu=False) == {'FINISHED'}
    select(src)
    assert bpy.ops.tessd.subdivide(levels=3, use_gpu=True) == {'FINISHED'}
    cpu, gpu = bpy.data.objects["CreasedCube_subdiv"], bpy.data.objects["CreasedCube_subdiv.001"]
    assert counts(cpu) == counts(gpu)
    a = np.empty(len(cpu.data.vertices) * 3, np.float32)
    b = np.empty(len(gpu.data.vertices) * 3, np.float32)
    cpu.data.vertices.foreach_get("co", a)
    gpu.data.vertices.foreach_get("co", b)
    assert np.allclose(a, b, atol=1e-5)


def test_subdivide_loop_on_quads_is_a_clean_error(bpy):
    src = scenes.suzanne()
    select(src)
    before = scene_state()
    with pytest.raises(RuntimeError, match="invalid_mesh"):
        bpy.ops.tessd.subdivide(scheme='LOOP', levels=1)
    assert scene_state() == before


def test_subdivide_non_manifold_is_a_clean_error(bpy):
    src = scenes.non_manifold()
    select(src)
    before = scene_state()
    with pytest.raises(RuntimeError, match=r"Fin: .*invalid_mesh.*shared by 3 faces.*scene is unchanged"):
        bpy.ops.tessd.subdivide(levels=1)
    assert scene_state() == before


def test_export_usd(bpy, tmp_path):
    from pxr import Gf, Usd, UsdGeom

    a = scenes.suzanne()
    b = scenes.two_material_cube()
    select(a, b)
    path = tmp_path / "scene.usda"
    assert bpy.ops.tessd.export_usd(filepath=str(path)) == {'FINISHED'}
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "scene.usda", "scene_Painted.usda", "scene_Suzanne.usda"]
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == "Z"
    painted = stage.GetPrimAtPath("/Scene/Painted")
    xf = UsdGeom.Xformable(painted).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    expected = Gf.Matrix4d(*[float(v) for row in b.matrix_world.transposed() for v in row])
    assert all(abs(xf[i][j] - expected[i][j]) < 1e-6 for i in range(4) for j in range(4))
    mesh = stage.GetPrimAtPath("/Scene/Painted/Painted")
    assert mesh.GetTypeName() == "Mesh"
    assert len(UsdGeom.Mesh(mesh).GetPointsAttr().Get()) == 8
    subsets = UsdGeom.Subset.GetAllGeomSubsets(UsdGeom.Imageable(mesh))
    assert sorted(s.GetPrim().GetName() for s in subsets) == ["Blue", "Red"]
    assert UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
    suz = UsdGeom.Mesh(stage.GetPrimAtPath("/Scene/Suzanne/Suzanne"))
    assert len(suz.GetFaceVertexCountsAttr().Get()) == len(a.data.polygons)


def test_export_usd_as_lods(bpy, tmp_path):
    from pxr import Usd

    a = scenes.suzanne()
    select(a)
    path = tmp_path / "lods.usda"
    assert bpy.ops.tessd.export_usd(filepath=str(path), as_lods=True, levels="40%,10%") == {'FINISHED'}
    stage = Usd.Stage.Open(str(path))
    prim = stage.GetPrimAtPath("/Scene/Suzanne")
    vset = prim.GetVariantSets().GetVariantSet("LOD")
    assert vset.GetVariantNames() == ["LOD0", "LOD1", "LOD2"]


def _scene_camera(bpy, eye, fov_deg, size):
    """A perspective camera at `eye` looking down −Z with +Y up (Blender's identity rotation),
    `fov_deg` vertical, rendering at `size`."""
    import math

    data = bpy.data.cameras.new("Cam")
    data.sensor_fit = 'VERTICAL'
    data.angle = math.radians(fov_deg)
    cam = bpy.data.objects.new("Cam", data)
    bpy.context.scene.collection.objects.link(cam)
    cam.location = eye
    cam.rotation_euler = (0.0, 0.0, 0.0)
    bpy.context.view_layer.update()
    scene = bpy.context.scene
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    return cam


def test_import_compressed_decodes_what_the_camera_needs(bpy, tmp_path):
    import locate

    mesh = locate.shared_data() / "mesh" / "bun_zipper.ply"
    tsc = tmp_path / "bunny.tsc"
    cli("compress", str(mesh), str(tsc), "--bits", "12", "--min-cell", "3000")
    centre = (-0.0168, 0.110, -0.0015)  # the bunny's bounding-box centre, about
    results = {}
    for label, distance in (("near", 0.25), ("far", 4.0)):
        scenes.empty_scene()
        eye = (centre[0], centre[1], centre[2] + distance)
        _scene_camera(bpy, eye, 30.0, (640, 480))
        assert bpy.ops.tessd.import_compressed(filepath=str(tsc), pixel_error=1.0) == {'FINISHED'}
        obj = bpy.data.objects["bunny"]
        # the same camera through the CLI gives the same mesh
        ref = cli("view-decode", str(tsc), str(tmp_path / ("%s.ply" % label)),
                  "--eye", "%r,%r,%r" % eye, "--target", "%r,%r,%r" % (eye[0], eye[1], eye[2] - 1.0),
                  "--up", "0,1,0", "--fov", "30", "--size", "640x480", "--pixel-error", "1")
        assert counts(obj) == (ref["vertices"], ref["triangles"])
        assert obj["tessd_tsc"] == str(tsc)
        results[label] = ref
    assert results["far"]["triangles"] * 4 < results["near"]["triangles"]
    assert results["far"]["bytes_read"] < results["near"]["bytes_read"]


def test_import_compressed_without_a_camera_is_refused(bpy, tmp_path):
    import locate

    tsc = tmp_path / "spot.tsc"
    cli("compress", str(locate.shared_data() / "mesh" / "spot_triangulated.obj"), str(tsc))
    before = scene_state()
    with pytest.raises(RuntimeError, match="no active camera"):
        bpy.ops.tessd.import_compressed(filepath=str(tsc))
    assert scene_state() == before
