"""Scenes for test_addon_artist.py: what an artist has in a file (the Stanford bunny, flat and
smooth primitives, a mesh carrying every kind of data Blender attaches to one, a linked
library object, shared meshes, collection instances), built with Blender's own operators and
data API, and numpy readers of what the results carry."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import locate
import scenes

BUNNY_PLY = locate.shared_data() / "mesh" / "bun_zipper.ply"


def bpy():
    return scenes.bpy()


# -- builders ---------------------------------------------------------------------------------

def bunny(name="Bunny", smooth=True):
    """The Stanford bunny (35 947 vertices, 69 451 triangles, 1 113 loose vertices) through
    Blender's PLY importer, smooth-shaded as an artist would show a scan."""
    b = bpy()
    b.ops.wm.ply_import(filepath=str(BUNNY_PLY))
    obj = b.context.object
    obj.name = name
    obj.data.name = name
    if smooth:
        obj.data.shade_smooth()
    return obj


def cube(name="Cube", smooth=False):
    """Blender's default cube (flat: every face has sharp_face), or smooth-shaded."""
    b = bpy()
    b.ops.mesh.primitive_cube_add()
    obj = b.context.object
    obj.name = name
    obj.data.name = name
    if smooth:
        obj.data.shade_smooth()
    return obj


def uv_sphere(name="Sphere", segments=64, rings=32):
    """A UV sphere: segments × (rings − 1) + 2 vertices (1 986 by default)."""
    b = bpy()
    b.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=rings)
    obj = b.context.object
    obj.name = name
    obj.data.name = name
    return obj


def rich_suzanne(name="Rich"):
    """Suzanne carrying what the issue saw vanish:

    - a second UV map "Lightmap" (the vertex xy), UVMap staying the active one;
    - "Paint": a BYTE_COLOR corner colour, constant red (the active colour);
    - "Tint": a FLOAT_COLOR point colour (z mapped to [0, 1]);
    - "x": a FLOAT point attribute equal to the vertex x;
    - "part": an INT face attribute (face index mod 5);
    - vertex groups "Left" (w) and "Right" (1 − w), w varying with x: normalised;
    - shape keys Basis, "Up" (Basis + (0, 0, 1), value 0.25) and "Fat" (Basis × 1.2, value
      0.5, relative to "Up").
    """
    b = bpy()
    obj = scenes.suzanne(name)
    mesh = obj.data
    co = positions(mesh)
    n_v, n_l, n_f = len(mesh.vertices), len(mesh.loops), len(mesh.polygons)
    corner_v = np.empty(n_l, np.int32)
    mesh.loops.foreach_get("vertex_index", corner_v)

    light = mesh.uv_layers.new(name="Lightmap")
    light.data.foreach_set("uv", np.ascontiguousarray(co[corner_v, :2] * 0.5 + 0.5).reshape(-1))
    mesh.uv_layers.active = mesh.uv_layers["UVMap"]

    paint = mesh.color_attributes.new("Paint", 'BYTE_COLOR', 'CORNER')
    paint.data.foreach_set("color", np.tile(np.array([1, 0, 0, 1], np.float32), n_l))
    tint = mesh.color_attributes.new("Tint", 'FLOAT_COLOR', 'POINT')
    z = (co[:, 2] - co[:, 2].min()) / np.ptp(co[:, 2])
    tint.data.foreach_set("color", np.stack([z, 1 - z, np.full(n_v, 0.5), np.ones(n_v)], 1)
                          .astype(np.float32).reshape(-1))
    mesh.color_attributes.active_color = paint

    mesh.attributes.new("x", 'FLOAT', 'POINT').data.foreach_set("value", co[:, 0].copy())
    part = mesh.attributes.new("part", 'INT', 'FACE')
    part.data.foreach_set("value", (np.arange(n_f) % 5).astype(np.int32))

    w = np.round((co[:, 0] - co[:, 0].min()) / np.ptp(co[:, 0]), 3)
    left = obj.vertex_groups.new(name="Left")
    right = obj.vertex_groups.new(name="Right")
    for value in np.unique(w):
        idx = np.flatnonzero(w == value).tolist()
        left.add(idx, float(value), 'REPLACE')
        right.add(idx, float(1.0 - value), 'REPLACE')

    obj.shape_key_add(name="Basis")
    up = obj.shape_key_add(name="Up")
    up.data.foreach_set("co", (co + np.float32([0, 0, 1])).reshape(-1))
    fat = obj.shape_key_add(name="Fat")
    fat.data.foreach_set("co", (co * np.float32(1.2)).reshape(-1))
    up.value = 0.25
    fat.value = 0.5
    fat.relative_key = up
    mesh.update()
    b.context.view_layer.update()
    return obj


def animated_suzanne(name="Jelly", frames=120, levels=2):
    """Suzanne with a shape key "Squash" (z halved) keyed 0 at frame 1 and 1 at frame
    `frames`, under a Subdivision Surface modifier of `levels`: a cage whose evaluation costs
    a few milliseconds per frame, as a character's would (level 2: about 8 000 vertices)."""
    obj = scenes.suzanne(name)
    basis = obj.shape_key_add(name="Basis")
    key = obj.shape_key_add(name="Squash")
    co = key_co(basis)
    co[:, 2] *= 0.5
    key.data.foreach_set("co", co.reshape(-1))
    for frame, value in ((1, 0.0), (frames, 1.0)):
        key.value = value
        key.keyframe_insert("value", frame=frame)
    mod = obj.modifiers.new("subsurf", 'SUBSURF')
    mod.levels = levels
    return obj


def library_file(path: Path, name="LibMonkey") -> Path:
    """A .blend holding one Suzanne object `name` in a collection `<name>_coll` (written with
    bpy.data.libraries.write; the objects are removed from this file again)."""
    b = bpy()
    obj = scenes.suzanne(name)
    coll = b.data.collections.new(name + "_coll")
    coll.objects.link(obj)
    b.data.libraries.write(str(path), {obj, obj.data, coll}, fake_user=True)
    mesh = obj.data
    b.data.objects.remove(obj)
    b.data.meshes.remove(mesh)
    b.data.collections.remove(coll)
    return path


def link_from_library(path: Path, name="LibMonkey"):
    """Links the library's collection `<name>_coll` into the scene (as File > Link does without
    instancing): the object, its mesh and its collection all come from the library."""
    b = bpy()
    with b.data.libraries.load(str(path), link=True) as (_src, dst):
        dst.collections = [name + "_coll"]
    coll = dst.collections[0]
    b.context.scene.collection.children.link(coll)
    b.context.view_layer.update()
    return coll.objects[name]


def collection_instance(name="PropsInstance", coll_name="Props"):
    """An empty instancing a collection (holding one cube) that is not in the scene itself."""
    b = bpy()
    mesh = b.data.meshes.new(coll_name + "Box")
    mesh.from_pydata([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], [],
                     [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                      (1, 5, 7, 3)])
    box = b.data.objects.new(coll_name + "Box", mesh)
    coll = b.data.collections.new(coll_name)
    coll.objects.link(box)
    inst = b.data.objects.new(name, None)
    inst.instance_type = 'COLLECTION'
    inst.instance_collection = coll
    inst.location = (4.0, 0.0, 0.0)
    b.context.scene.collection.objects.link(inst)
    return inst


# -- readers ----------------------------------------------------------------------------------

def positions(mesh):
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def sharp_faces(mesh):
    """Per face: flat-shaded (no `sharp_face` attribute means every face is smooth)."""
    flags = np.zeros(len(mesh.polygons), bool)
    attr = mesh.attributes.get("sharp_face")
    if attr is not None:
        attr.data.foreach_get("value", flags)
    return flags


def corner_face_dots(mesh):
    """Per corner: the cosine between its normal (`mesh.corner_normals`, what Blender shades
    with) and its face's normal (`polygons[].normal`)."""
    n_l, n_f = len(mesh.loops), len(mesh.polygons)
    cn = np.empty(n_l * 3, np.float32)
    mesh.corner_normals.foreach_get("vector", cn)
    fn = np.empty(n_f * 3, np.float32)
    mesh.polygons.foreach_get("normal", fn)
    sizes = np.empty(n_f, np.int32)
    starts = np.empty(n_f, np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    mesh.polygons.foreach_get("loop_start", starts)
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    corner = np.repeat(starts - offsets, sizes) + np.arange(int(sizes.sum()))
    face_of = np.empty(n_l, np.int64)
    face_of[corner] = np.repeat(np.arange(n_f), sizes)
    return np.einsum("ij,ij->i", cn.reshape(-1, 3), fn.reshape(-1, 3)[face_of])


def inverted_corners(mesh) -> int:
    """Corners whose normal is more than 90° from their face's normal: the black specks."""
    return int((corner_face_dots(mesh) < 0.0).sum())


def max_corner_angle(mesh) -> float:
    """The largest angle (degrees) between a corner normal and its face normal."""
    dots = corner_face_dots(mesh)
    return float(np.degrees(np.arccos(np.clip(dots, -1, 1))).max()) if len(dots) else 0.0


def attribute_signature(mesh):
    """(name, domain, data_type) of the mesh's user attributes (not Blender's internal ones,
    whose names start with "." or which every mesh has)."""
    internal = {"position", "sharp_face", "sharp_edge", "material_index", "custom_normal"}
    return sorted((a.name, a.domain, a.data_type) for a in mesh.attributes
                  if not a.name.startswith(".") and a.name not in internal)


def values(mesh, name):
    attr = mesh.attributes[name]
    comps = {'FLOAT': 1, 'INT': 1, 'FLOAT2': 2, 'FLOAT_VECTOR': 3, 'FLOAT_COLOR': 4,
             'BYTE_COLOR': 4, 'BOOLEAN': 1}[attr.data_type]
    key = {'FLOAT2': "vector", 'FLOAT_VECTOR': "vector", 'FLOAT_COLOR': "color",
           'BYTE_COLOR': "color"}.get(attr.data_type, "value")
    dtype = {'INT': np.int32, 'BOOLEAN': bool}.get(attr.data_type, np.float32)
    out = np.empty(len(attr.data) * comps, dtype)
    attr.data.foreach_get(key, out)
    return out.reshape(-1, comps) if comps > 1 else out


def group_weights(obj):
    """[groups, vertices] weights of the object's vertex groups (0 where not a member)."""
    names = [g.name for g in obj.vertex_groups]
    w = np.zeros((len(names), len(obj.data.vertices)), np.float32)
    member = np.zeros(len(obj.data.vertices), bool)
    for v in obj.data.vertices:
        for g in v.groups:
            w[g.group, v.index] = g.weight
            member[v.index] = True
    return names, w, member


def key_co(block):
    co = np.empty(len(block.data) * 3, np.float32)
    block.data.foreach_get("co", co)
    return co.reshape(-1, 3)


def triangles(mesh) -> int:
    sizes = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", sizes)
    return int((sizes - 2).sum())
