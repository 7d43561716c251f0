"""What the operators share: the selection, result objects and USD paths."""

import os
import re

import bpy

from . import convert
from .jobs import UserError


def selected_meshes(context):
    """The selected mesh objects (sorted by name, so results come in a stable order)."""
    objs = [o for o in context.selected_objects if o.type == 'MESH']
    return sorted(objs, key=lambda o: o.name)


def require_meshes(context):
    objs = selected_meshes(context)
    if not objs:
        raise UserError("tessd: select at least one mesh object (Object mode)")
    return objs


def arrays_of(context, obj, evaluated, **kw):
    """(arrays, params) of one object, or a UserError naming it."""
    depsgraph = context.evaluated_depsgraph_get()
    try:
        with convert.source_mesh(obj, depsgraph, evaluated) as mesh:
            return convert.mesh_to_arrays(mesh, obj, **kw)
    except ValueError as e:
        raise UserError("tessd: %s cannot be sent: %s" % (obj.name, e)) from e


def uv_name_of(obj):
    uv = obj.data.uv_layers.active
    return uv.name if uv is not None else "UVMap"


def materials_of(obj):
    return [slot.material for slot in obj.material_slots]


def get_object(name):
    obj = bpy.data.objects.get(name)
    if obj is None:
        raise UserError("tessd: the object %s was deleted while the daemon worked" % name)
    return obj


def new_object(created, name, mesh, source, collections=None):
    """A new object with `mesh`, `source`'s world matrix, in `collections` (default: the
    source's collections)."""
    obj = created.add(bpy.data.objects.new(name, mesh))
    obj.matrix_world = source.matrix_world.copy()
    for coll in (collections or source.users_collection or [bpy.context.scene.collection]):
        coll.objects.link(obj)
    return obj


def result_object(created, src, arrays, suffix, replace, swaps):
    """The result of one source object: with `replace`, `src` itself, its new mesh queued in
    `swaps` for the caller to swap in once nothing can fail any more; else a new object
    `<name><suffix>` beside it. Either way with the source's materials and UV map name."""
    name = src.name if replace else src.name + suffix
    mesh = created.add(convert.mesh_from_arrays(name, arrays, materials=materials_of(src),
                                                uv_name=uv_name_of(src)))
    if replace:
        swaps.append((src, mesh))
        return src
    return new_object(created, name, mesh, src)


def select_only(context, objects):
    for o in context.selected_objects:
        o.select_set(False)
    for o in objects:
        o.select_set(True)
    if objects:
        context.view_layer.objects.active = objects[0]


def abs_path(path):
    return os.path.abspath(bpy.path.abspath(path))


def per_object_path(path, name, count):
    """`path` for one object; `<stem>_<name><ext>` beside it when there are several."""
    if count == 1:
        return path
    stem, ext = os.path.splitext(path)
    return "%s_%s%s" % (stem, usd_name(name), ext or ".usda")


def usd_name(name):
    """A valid USD prim name from a Blender name."""
    out = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return out if out and not out[0].isdigit() else "_" + out


def stage_metadata(context):
    return {"up_axis": "Z", "meters_per_unit": float(context.scene.unit_settings.scale_length)}


def write_assembly(path, context, entries):
    """A small .usda stage referencing one file per object, each under an Xform with the
    object's world matrix: `entries` are (object, file path) pairs."""
    meta = stage_metadata(context)
    lines = ["#usda 1.0", "(", '    defaultPrim = "Scene"',
             "    metersPerUnit = %r" % meta["meters_per_unit"], '    upAxis = "Z"', ")", "",
             'def Xform "Scene" (', '    kind = "assembly"', ")", "{"]
    folder = os.path.dirname(path)
    for obj, file in entries:
        rel = os.path.relpath(file, folder).replace(os.sep, "/")
        m = obj.matrix_world.transposed()  # USD: row vectors, translation in the last row
        rows = ", ".join("(%s)" % ", ".join(repr(float(v)) for v in row) for row in m)
        lines += ['    def Xform "%s" (' % usd_name(obj.name),
                  "        prepend references = @./%s@" % rel, "    )", "    {",
                  "        matrix4d xformOp:transform = (%s)" % rows,
                  '        uniform token[] xformOpOrder = ["xformOp:transform"]', "    }", ""]
    lines.append("}")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
