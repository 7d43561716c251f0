"""What the operators share: the selection as units of work, conversion, result objects,
world-space distances and USD paths."""

import os
import re

import bpy
import numpy as np

from . import attributes, convert
from .jobs import UserError


class Unit:
    """The objects whose results come from one conversion: one object, or every selected
    object sharing one mesh (sent once; its result mesh is shared again)."""

    def __init__(self, objects):
        self.names = [o.name for o in objects]

    @property
    def objects(self):
        return [get_object(n) for n in self.names]

    @property
    def label(self):
        if len(self.names) == 1:
            return self.names[0]
        return "%s (+%d sharing its mesh)" % (self.names[0], len(self.names) - 1)

    def scale(self):
        """The largest scale factor of the objects' world matrices: an object-space distance
        d is at most d × scale in world space, for every one of them."""
        return max(world_scale(o) for o in self.objects)


def world_scale(obj):
    """The largest singular value of the object's world matrix (its largest stretch)."""
    m = np.array(obj.matrix_world.to_3x3(), dtype=np.float64)
    s = float(np.linalg.svd(m, compute_uv=False)[0])
    return s if s > 0 else 1.0


def has_modifiers(obj):
    return any(m.show_viewport for m in obj.modifiers)


def has_shape_keys(obj):
    keys = obj.data.shape_keys
    return keys is not None and len(keys.key_blocks) > 1


def linked_reason(obj):
    """Why `obj`'s mesh cannot be changed in place (linked from a library), or None."""
    for block in (obj, obj.data):
        if block.library is not None:
            return ("%s is linked from %s and cannot be changed here (Object > Relations > "
                    "Make Local first, or turn off Replace)" % (block.name, block.library.filepath))
        if not block.is_editable:
            return "%s is not editable (a library override); turn off Replace" % block.name
    return None


def gather(context, use_modifiers, replace=False):
    """The selection as units of work, and (name, why) of the selected objects skipped:
    instances and other non-mesh objects, and with `replace` linked or non-editable data.
    Objects sharing a mesh form one unit unless their modifiers make their meshes differ."""
    skipped, units, by_mesh = [], [], {}
    for obj in sorted(context.selected_objects, key=lambda o: o.name):
        if obj.type != 'MESH':
            if obj.instance_type == 'COLLECTION' and obj.instance_collection is not None:
                skipped.append((obj.name, "an instance of the collection %s (Object > Apply > "
                                          "Make Instances Real to process its meshes)"
                                % obj.instance_collection.name))
            else:
                skipped.append((obj.name, "a %s, not a mesh" % obj.type.lower()))
            continue
        why = linked_reason(obj) if replace else None
        if why:
            skipped.append((obj.name, why))
            continue
        if use_modifiers and not replace and has_modifiers(obj):
            units.append([obj])
            continue
        key = obj.data.name_full
        if key in by_mesh:
            by_mesh[key].append(obj)
        else:
            by_mesh[key] = [obj]
            units.append(by_mesh[key])
    return [Unit(objs) for objs in units], skipped


def require_units(context, use_modifiers, replace=False):
    """:func:`gather`, raising UserError when nothing can be processed."""
    units, skipped = gather(context, use_modifiers, replace)
    if not units:
        if skipped:
            raise UserError("tessd: nothing to process: " + "; ".join(
                "%s is %s" % s if not s[1].startswith(s[0]) else s[1] for s in skipped))
        raise UserError("tessd: select at least one mesh object (Object mode)")
    return units, skipped


def describe_skipped(skipped):
    return "; ".join("%s: %s" % s for s in skipped)


def arrays_of(context, obj, evaluated, **kw):
    """(arrays, params, sent) of one object, or a UserError naming it.

    Shape keys travel only with the object's own mesh: an object with shape keys and no
    modifiers sends its own mesh (the keys' reference shape) even when modifiers are
    applied; with modifiers applied, its keys are listed as not carried."""
    if obj.mode == 'EDIT':
        # In Edit Mode the mesh's own data is stale (the edit mesh holds the truth; its UV
        # layers even read as empty), and a Replace would be overwritten on leaving it.
        raise UserError("%s is in Edit Mode: leave Edit Mode first" % obj.name)
    keys = has_shape_keys(obj)
    # Without modifiers the evaluated mesh is the object's own (its shape keys mixed in, and
    # those are sent as keys): read the object's mesh directly, without evaluating the
    # depsgraph or copying the mesh by `to_mesh`.
    if evaluated and not has_modifiers(obj):
        evaluated = False
    depsgraph = context.evaluated_depsgraph_get() if evaluated else None
    try:
        with convert.source_mesh(obj, depsgraph, evaluated) as mesh:
            arrays, params, sent = convert.mesh_to_arrays(mesh, obj, shape_keys=keys and not evaluated,
                                                          **kw)
    except ValueError as e:
        raise UserError("%s cannot be sent: %s" % (obj.name, e)) from e
    if keys and evaluated:
        sent.dropped.append("shape keys (the modifiers are applied; turn off Apply modifiers "
                            "to keep them)")
    return arrays, params, sent


def uv_name_of(obj):
    uv = obj.data.uv_layers.active
    return uv.name if uv is not None else "UVMap"


def materials_of(obj):
    return [slot.material for slot in obj.material_slots]


def get_object(name):
    obj = bpy.data.objects.get(name)
    if obj is None:
        raise UserError("the object %s was deleted while the daemon worked" % name)
    return obj


def editable_collections(collections):
    return [c for c in collections if c.library is None and c.is_editable]


def new_object(created, name, mesh, source, collections=None):
    """A new object with `mesh`, `source`'s world matrix, in `collections` (default: the
    source's collections that can take it; the scene's collection when none can)."""
    obj = created.add(bpy.data.objects.new(name, mesh))
    obj.matrix_world = source.matrix_world.copy()
    colls = editable_collections(collections or source.users_collection) or [
        bpy.context.scene.collection]
    for coll in colls:
        coll.objects.link(obj)
    return obj


def result_mesh(created, name, arrays, src, sent, shading_mode, prefix=""):
    """The result mesh of `src` from a reply's arrays, with everything `sent` carried:
    generic attributes, vertex groups and shape keys (these need an object: a temporary one
    holds the mesh meanwhile; the data stays on the mesh)."""
    mesh = created.add(convert.mesh_from_arrays(name, arrays, materials=materials_of(src),
                                                uv_name=uv_name_of(src), prefix=prefix,
                                                sent=sent, shading_mode=shading_mode))
    if sent is not None and (sent.groups or sent.keys):
        holder = bpy.data.objects.new(name + "_tessd_tmp", mesh)
        try:
            sent.missing.update(attributes.apply_object_data(holder, arrays, prefix, sent))
        finally:
            bpy.data.objects.remove(holder)
    return mesh


def unit_results(created, unit, mesh, suffix, replace):
    """The objects of `unit` given their result `mesh`: with `replace`, the objects themselves
    (the swap queued for when nothing can fail any more; an object in Edit Mode is refused,
    its edit mesh would overwrite the result); else new objects `<name><suffix>` sharing
    `mesh`."""
    out = []
    for src in unit.objects:
        if replace:
            if src.mode == 'EDIT':
                raise UserError("%s is in Edit Mode, so its mesh was not replaced (leave Edit "
                                "Mode and run again)" % src.name)
            why = linked_reason(src)
            if why:
                raise UserError(why)
            created.swap(src, mesh)
            out.append(src)
        else:
            out.append(new_object(created, src.name + suffix, mesh, src))
    return out


def mesh_counts(mesh):
    """(vertices, faces, triangles) of a Blender mesh, as the viewport's Statistics overlay
    counts them: faces are polygons (a quad is one face), triangles what they split into
    (a face of n corners: n - 2)."""
    return len(mesh.vertices), len(mesh.polygons), len(mesh.loops) - 2 * len(mesh.polygons)


def faces_text(faces, triangles):
    """`500 faces (968 triangles)`; `278 faces` when every face is a triangle."""
    text = "%d faces" % faces
    return text if triangles == faces else "%s (%d triangles)" % (text, triangles)


def mesh_counts_text(mesh):
    """`507 vertices, 500 faces (968 triangles)`: a mesh's figures as Blender shows them."""
    vertices, faces, triangles = mesh_counts(mesh)
    return "%d vertices, %s" % (vertices, faces_text(faces, triangles))


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


def length_text(context, value):
    """A world-space length in the scene's units (`0.012 m`, `1.2 cm`, `0.4 in`)."""
    units = context.scene.unit_settings
    if units.system == 'NONE':
        return "%.4g" % value
    return bpy.utils.units.to_string(units.system, 'LENGTH', value * units.scale_length,
                                     precision=4)


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
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)
