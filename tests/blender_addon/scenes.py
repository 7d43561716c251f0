"""Scenes for the add-on tests, built with Blender's own operators and data API, and the
daemon's CLI as the reference for counts."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import List

import numpy as np

import locate


def bpy():
    import bpy as _bpy

    return _bpy


def empty_scene():
    b = bpy()
    for obj in list(b.data.objects):
        b.data.objects.remove(obj)
    for coll in list(b.data.collections):
        b.data.collections.remove(coll)
    for mesh in list(b.data.meshes):
        b.data.meshes.remove(mesh)
    if len(b.data.cache_files):
        b.data.batch_remove(list(b.data.cache_files))
    b.context.scene.frame_set(1)


def select(*objs):
    b = bpy()
    for o in b.context.view_layer.objects:
        o.select_set(False)
    for o in objs:
        o.select_set(True)
    b.context.view_layer.objects.active = objs[0] if objs else None


def suzanne(name="Suzanne", location=(0.0, 0.0, 0.0)):
    b = bpy()
    b.ops.mesh.primitive_monkey_add(location=location)
    obj = b.context.object
    obj.name = name
    obj.data.name = name
    return obj


def creased_cube(name="CreasedCube"):
    """A cube cage whose four top edges are fully creased (crease_edge = 1)."""
    b = bpy()
    b.ops.mesh.primitive_cube_add()
    obj = b.context.object
    obj.name = name
    mesh = obj.data
    verts = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", verts)
    z = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", z)
    top = z.reshape(-1, 3)[:, 2] > 0
    values = top[verts.reshape(-1, 2)].all(axis=1).astype(np.float32)
    attr = mesh.attributes.new("crease_edge", "FLOAT", "EDGE")
    attr.data.foreach_set("value", values)
    return obj


def two_material_cube(name="Painted"):
    """A cube (with its UV map) whose faces use two materials, moved and rotated."""
    b = bpy()
    b.ops.mesh.primitive_cube_add(location=(3.0, -1.0, 0.5), rotation=(0.3, 0.2, 0.9))
    obj = b.context.object
    obj.name = name
    for mat_name in ("Red", "Blue"):
        mat = b.data.materials.get(mat_name) or b.data.materials.new(mat_name)
        obj.data.materials.append(mat)
    idx = np.array([0, 0, 0, 1, 1, 1], dtype=np.int32)
    obj.data.polygons.foreach_set("material_index", idx)
    obj.data.update()
    return obj


def non_manifold(name="Fin"):
    """Three quads sharing one edge."""
    b = bpy()
    mesh = b.data.meshes.new(name)
    mesh.from_pydata([(0, 0, 0), (0, 0, 1), (1, 0, 0), (1, 0, 1), (-1, 0, 0), (-1, 0, 1),
                      (0, 1, 0), (0, 1, 1)], [], [[0, 2, 3, 1], [0, 1, 5, 4], [0, 1, 7, 6]])
    mesh.update()
    obj = b.data.objects.new(name, mesh)
    b.context.scene.collection.objects.link(obj)
    return obj


def export_mesh(obj, path: Path) -> Path:
    """The object's evaluated mesh through Blender's own binary PLY exporter (float32 kept
    exactly; OBJ's 6 decimals would move vertices across cell borders), coordinates as they
    are (Z up, no axis change), nothing but positions and faces."""
    b = bpy()
    select(obj)
    b.ops.wm.ply_export(filepath=str(path), export_selected_objects=True, apply_modifiers=True,
                        forward_axis='Y', up_axis='Z', export_normals=False, export_uv=False,
                        export_colors='NONE', export_attributes=False,
                        export_triangulated_mesh=False, ascii_format=False)
    return path


def cli(*args: str) -> dict:
    """Runs `tessd <args> --json` and returns its JSON result."""
    proc = subprocess.run([str(locate.tessd_bin()), *args, "--json"], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def counts(obj):
    return len(obj.data.vertices), len(obj.data.polygons)


def scene_state():
    """What an action must leave alone when it fails: names of objects, meshes, collections,
    and each object's mesh and vertex count."""
    b = bpy()
    return (sorted(o.name for o in b.data.objects), sorted(m.name for m in b.data.meshes),
            sorted(c.name for c in b.data.collections),
            sorted((o.name, o.data.name if o.data else "", len(o.data.vertices) if o.type == 'MESH' else 0)
                   for o in b.data.objects))


def names(prefix: str = "") -> List[str]:
    return sorted(o.name for o in bpy().data.objects if o.name.startswith(prefix))


def same_matrix(a, b, tol=1e-5) -> bool:
    return all(abs(a[i][j] - b[i][j]) <= tol for i in range(4) for j in range(4))
