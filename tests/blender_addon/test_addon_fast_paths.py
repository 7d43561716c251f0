"""The add-on's bulk reads and writes (issue 33, "What the user waits for"): every array is read
straight into the attribute's own dtype, a triangle mesh goes as `face_indices` [F, 3], and the
vertex groups of a large mesh go through geometry nodes instead of a Python loop over the
vertices. Each fast path is checked against the slow one it replaced, on real Blender data.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

import artist_scenes as art
import scenes
from addon_env import ADDON
from scenes import select


@pytest.fixture
def bpy(addon):
    import bpy as _bpy

    scenes.empty_scene()
    return _bpy


def module(name):
    return sys.modules[ADDON + "." + name]


def ico_with_groups(bpy, subdivisions=5):
    """An ico sphere with four vertex groups: two ramps over x (overlapping), one with a few
    distinct weights, and one empty group."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions)
    obj = bpy.context.object
    co = np.empty(len(obj.data.vertices) * 3, np.float32)
    obj.data.vertices.foreach_get("co", co)
    x = co[0::3]
    left = obj.vertex_groups.new(name="Left")
    right = obj.vertex_groups.new(name="Right")
    steps = obj.vertex_groups.new(name="Steps")
    obj.vertex_groups.new(name="Empty")
    for i in np.flatnonzero(x < 0.3)[::7]:
        left.add([int(i)], float(0.5 - 0.5 * x[i]), 'REPLACE')
    for i in np.flatnonzero(x > -0.3)[::5]:
        right.add([int(i)], float(0.5 + 0.5 * x[i]), 'REPLACE')
    for k in range(4):
        steps.add(np.flatnonzero(np.abs(x - (-0.75 + 0.5 * k)) < 0.1).tolist(), 0.25 * (k + 1), 'REPLACE')
    return obj


def test_vertex_groups_bulk_equals_the_loop(bpy):
    """The geometry-nodes read gives the loop's weights exactly (shape keys on the mesh too)
    and leaves nothing behind."""
    vg = module("vertex_groups")
    obj = ico_with_groups(bpy)
    obj.shape_key_add(name="Basis")
    obj.shape_key_add(name="Key").value = 0.5
    names = [g.name for g in obj.vertex_groups]
    before = (len(bpy.data.objects), len(bpy.data.node_groups), len(bpy.data.scenes),
              [o.name for o in bpy.context.view_layer.objects])
    assert vg.bulk_possible(obj.data, obj, names)
    bulk = vg.weights_bulk(obj.data, names)
    loop = vg.weights_loop(obj.data, names)
    assert bulk.shape == (4, len(obj.data.vertices))
    assert np.array_equal(bulk, loop)
    assert vg.agrees(obj.data, names, bulk)
    wrong = bulk.copy()
    wrong[1] = 0.0  # what a node wired to the wrong socket would give: caught
    assert not vg.agrees(obj.data, names, wrong)
    assert (loop[0] > 0).sum() > 50 and (loop[1] > 0).sum() > 50 and not loop[3].any()
    assert sorted(set(loop[2][loop[2] > 0].tolist())) == [0.25, 0.5, 0.75, 1.0]
    # Nothing left behind, and the user's view layer never saw the temporary object.
    after = (len(bpy.data.objects), len(bpy.data.node_groups), len(bpy.data.scenes),
             [o and o.name for o in bpy.context.view_layer.objects])
    assert after == before


def test_vertex_groups_bulk_is_not_used_where_it_would_read_something_else(bpy):
    """A group named as an attribute (the node would read the attribute), or a mesh that is
    not the object's own (an evaluated copy): the loop."""
    vg = module("vertex_groups")
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3)
    obj = bpy.context.object
    # Blender refuses an attribute named as an existing group, not a group named as an
    # existing attribute.
    attr = obj.data.attributes.new("Steps", 'FLOAT', 'POINT')
    attr.data.foreach_set("value", np.full(len(obj.data.vertices), 9.0, np.float32))
    obj.vertex_groups.new(name="Steps").add(list(range(0, len(obj.data.vertices), 3)), 1.0, 'REPLACE')
    names = [g.name for g in obj.vertex_groups]
    assert names == ["Steps"]
    assert not vg.bulk_possible(obj.data, obj, names)
    saved = vg.BULK_MIN_VERTICES
    vg.BULK_MIN_VERTICES = 0
    try:
        got = vg.weights(obj.data, obj, names)
    finally:
        vg.BULK_MIN_VERTICES = saved
    assert got.max() == 1.0 and got.sum() == (len(obj.data.vertices) + 2) // 3  # not the 9s
    obj.data.attributes.remove(obj.data.attributes["Steps"])
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    try:
        assert not vg.bulk_possible(mesh, obj, names)
    finally:
        evaluated.to_mesh_clear()


def test_simplify_carries_the_same_groups_through_either_path(bpy):
    """The operator's result weights are the same whether the groups were read in bulk or by
    the loop."""
    vg = module("vertex_groups")
    obj = ico_with_groups(bpy)
    results = []
    saved = vg.BULK_MIN_VERTICES
    try:
        for threshold in (0, 10 ** 9):
            vg.BULK_MIN_VERTICES = threshold
            select(obj)
            assert bpy.ops.tessd.simplify(method='COMPLEXITY', target=20) == {'FINISHED'}
            out = bpy.data.objects[obj.name + "_simplified"]
            names, w, _ = art.group_weights(out)
            results.append((names, w, len(out.data.vertices)))
            bpy.data.objects.remove(out)
            bpy.context.view_layer.update()  # drops the removed object's base
    finally:
        vg.BULK_MIN_VERTICES = saved
    (n0, w0, v0), (n1, w1, v1) = results
    assert n0 == n1 == ["Left", "Right", "Steps", "Empty"] and v0 == v1 < len(obj.data.vertices)
    assert np.array_equal(w0, w1) and w0[0].any() and w0[2].any()


def test_triangle_mesh_goes_as_rows_of_three_and_reads_match_the_element_api(bpy):
    """A triangle mesh sends `face_indices` [F, 3] and no `face_sizes`; a mesh with quads sends
    1-D indices with sizes. Every array equals what the element-by-element API reads."""
    convert = module("convert")
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3)
    ico = bpy.context.object
    arrays, _, _ = convert.mesh_to_arrays(ico.data, ico)
    assert arrays["face_indices"].shape == (len(ico.data.polygons), 3) and "face_sizes" not in arrays
    suzanne = scenes.suzanne()
    mesh = suzanne.data
    arrays, _, _ = convert.mesh_to_arrays(mesh, suzanne)
    sizes = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    corner_v = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corner_v)
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers.active.data.foreach_get("uv", uv)
    assert (sizes == 4).any() and (sizes == 3).any()
    assert arrays["face_sizes"].dtype == np.uint32 and np.array_equal(arrays["face_sizes"], sizes)
    assert arrays["face_indices"].dtype == np.uint32 and np.array_equal(arrays["face_indices"], corner_v)
    assert np.array_equal(arrays["positions"].reshape(-1), co)
    assert np.array_equal(arrays["uvs"].reshape(-1), uv)
    # n-gons (a cylinder's 32-gon caps): the sizes from the faces' starts.
    bpy.ops.mesh.primitive_cylinder_add(vertices=32)
    cyl = bpy.context.object.data
    arrays, _, _ = convert.mesh_to_arrays(cyl, bpy.context.object)
    sizes = np.empty(len(cyl.polygons), np.int32)
    cyl.polygons.foreach_get("loop_total", sizes)
    assert sizes.max() == 32 and np.array_equal(arrays["face_sizes"], sizes)


@pytest.mark.parametrize("shading", ["smooth", "flat", "mixed"])
def test_sharp_face_travels_only_when_it_differs_between_faces(bpy, shading):
    """For a result that only comes back to Blender, `sharp_face` the same on every face is
    not sent: all false gives a smooth result, all true a flat one (every result face has a
    source face); mixed, it is sent and carried. For a file (USD) it always goes."""
    convert = module("convert")
    src = scenes.suzanne()
    mesh = src.data
    flags = np.zeros(len(mesh.polygons), bool)
    if shading == "flat":
        flags[:] = True
    elif shading == "mixed":
        flags[: len(flags) // 2] = True
    attr = mesh.attributes.get("sharp_face") or mesh.attributes.new("sharp_face", 'BOOLEAN', 'FACE')
    attr.data.foreach_set("value", flags)
    arrays, _, sent = convert.mesh_to_arrays(mesh, src)  # for a file: always sent
    assert "face:sharp_face" in arrays and not sent.all_sharp_faces
    arrays, _, sent = convert.mesh_to_arrays(mesh, src, uniform_sharp_face=False)
    assert ("face:sharp_face" in arrays) == (shading == "mixed")
    assert sent.all_sharp_faces == (shading == "flat")
    select(src)
    assert bpy.ops.tessd.simplify(method='COMPLEXITY', target=30) == {'FINISHED'}
    out = art.sharp_faces(bpy.data.objects["Suzanne_simplified"].data)
    if shading == "flat":
        assert out.all()
    elif shading == "smooth":
        assert not out.all()  # only faces made flat against black specks, if any
    else:
        assert out.any() and not out.all()


def test_generic_attributes_of_every_type_round_trip_through_native_dtypes(bpy):
    """Each attribute type is read in its own dtype and written back the same: integers,
    booleans and floats keep their values (the old f32 reads gave the same numbers)."""
    convert = module("convert")
    attributes = module("attributes")
    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.object
    mesh = obj.data
    rng = np.random.default_rng(3)
    n_f = len(mesh.polygons)
    values = {
        'INT': rng.integers(-1000, 1000, n_f).astype(np.int32),
        'INT8': rng.integers(-100, 100, n_f).astype(np.int8),
        'BOOLEAN': rng.random(n_f) > 0.5,
        'FLOAT': rng.random(n_f).astype(np.float32),
        'FLOAT_VECTOR': rng.random(n_f * 3).astype(np.float32),
    }
    for data_type, v in values.items():
        _, key, _ = attributes.TYPES[data_type]
        mesh.attributes.new("a_" + data_type, data_type, 'FACE').data.foreach_set(key, v)
    arrays, _, sent = convert.mesh_to_arrays(mesh, obj)
    for data_type, v in values.items():
        got = arrays["face:a_" + data_type]
        assert got.dtype == np.float32
        assert np.array_equal(got.reshape(-1), v.astype(np.float32)), data_type
    # Back: a mesh with the same faces (same count) gets them in their own types.
    copy = convert.mesh_from_arrays("copy", arrays, sent=sent)
    for data_type, v in values.items():
        _, key, dtype = attributes.TYPES[data_type]
        attr = copy.attributes["a_" + data_type]
        assert attr.data_type == data_type
        out = np.empty(v.size, dtype)
        attr.data.foreach_get(key, out)
        assert np.array_equal(out, v), data_type
    bpy.data.meshes.remove(copy)
