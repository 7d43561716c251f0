"""Generate LODs…: one `lod` request per selected object, or per mesh that selected objects
share (every level simplified from the input, so each level's bound holds against it; with a
USD file the same request writes the stage and returns the meshes, so the chain is computed
once). Every level carries what LOD0 has: UV maps, colour and generic attributes, vertex
groups, shape keys, sharp faces and edges (attributes.py); what cannot travel is reported. The result is a collection `<name>_LODs`
holding `<name>_LOD0` (a copy of the input) .. `<name>_LOD<n>`, all with the source's
transform (or side by side along X with `side_by_side`). With `usd_path`, the daemon also
writes, per object, a stage with the `LOD` variant set (docs/protocol.md, lod), the points in
object space, as `<stem>_<name>.usda`; `usd_path` is a stage referencing them, one Xform per
object carrying its world matrix (as Export USD via tessd writes them), however many objects
are selected: one object is placed in the stage as it is in Blender, not at the origin.
"""

import os

import bpy

from . import attributes, common
from .jobs import JobOperator, Request, Task, UserError, skipped_task
from .ops_simplify import NORMALS, REPRESENTATIVES, WEIGHTINGS

LOD_METHODS = [
    ('COMPLEXITY', "Complexity goals", "Levels are vertex counts or percentages (50%, 20000)"),
    ('QUALITY', "Quality goals", "Levels are maximum deviations (0.5%, 0.2)"),
    ('GRID', "Regular subdivision", "Levels are cells per axis"),
]


def parse_levels(text):
    levels = [x.strip() for x in text.split(",") if x.strip()]
    if not levels:
        raise UserError("tessd: give at least one LOD goal, e.g. 50%,20%,5%")
    return ",".join(levels)


class TESSD_OT_generate_lods(JobOperator, bpy.types.Operator):
    """Build a chain of levels of detail of the selected meshes (tessd)"""

    bl_idname = "tessd.generate_lods"
    bl_label = "Generate LODs"
    title = "tessd LODs"

    levels: bpy.props.StringProperty(name="Levels", default="50%,20%,5%",
                                     description="Goals of LOD1, LOD2, ... finest first")
    method: bpy.props.EnumProperty(name="Method", items=LOD_METHODS, default='COMPLEXITY')
    representative: bpy.props.EnumProperty(name="Representative", items=REPRESENTATIVES,
                                           default='BARYCENTER')
    weighting: bpy.props.EnumProperty(name="Weighting", items=WEIGHTINGS,
                                      default='LONGEST_EDGE')
    normals: bpy.props.EnumProperty(name="Normals", items=NORMALS, default='BLENDER')
    usd_path: bpy.props.StringProperty(name="USD file", default="", subtype='FILE_PATH',
                                       description="Also write a .usda with the LOD variant "
                                                   "set (empty: none)")
    lod_schema: bpy.props.EnumProperty(
        name="USD layout", default='VARIANTS',
        items=[('VARIANTS', "Variant set", "A `LOD` variant set (what DCC tools read)"),
               ('USDLOD', "UsdLod", "usd-core's native UsdLod schema")])
    side_by_side: bpy.props.BoolProperty(name="Side by side", default=False,
                                         description="Place the levels next to each other "
                                                     "along X instead of on top of each other")
    use_modifiers: bpy.props.BoolProperty(name="Apply modifiers", default=True)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        for name in ("levels", "method", "representative", "weighting", "normals", "usd_path",
                     "lod_schema", "side_by_side", "use_modifiers"):
            layout.prop(self, name)

    def prepare(self, context):
        levels = parse_levels(self.levels)
        units, skipped = common.require_units(context, self.use_modifiers)
        usd = common.abs_path(self.usd_path) if self.usd_path else ""
        if usd and not usd.lower().endswith(".usda"):
            raise UserError("tessd: the USD file must end in .usda, got %s" % usd)
        tasks = [skipped_task(name, why) for name, why in skipped]
        for unit in units:
            # Always one file per unit and `usd` referencing them with the objects' world
            # matrices: the daemon writes points in object space, without a transform.
            path = common.per_object_path(usd, unit.names[0], 2) if usd else ""
            tasks.append(Task(unit.label, self._steps(context, unit, levels, path), unit=unit,
                              usd_file=path))
        return tasks

    def _steps(self, context, unit, levels, usd_file):
        yield 0.0
        src = unit.objects[0]
        # A USD stage keeps every attribute as a primvar, sharp_face too.
        arrays, extra, sent = common.arrays_of(context, src, self.use_modifiers,
                                               normals=self.normals == 'CUSTOM',
                                               uniform_sharp_face=bool(usd_file))
        params = dict({"levels": levels, "method": self.method.lower(),
                       "representative": self.representative.lower(),
                       "weighting": self.weighting.lower()}, **extra)
        if usd_file:
            # One request gives the stage and the meshes: the chain is computed once.
            os.makedirs(os.path.dirname(usd_file), exist_ok=True)
            params.update(output=usd_file, return_arrays=True, name=common.usd_name(src.name),
                          lod_schema=self.lod_schema.lower(), **common.stage_metadata(context))
        return [Request("lod", params, arrays, label=unit.label, sent=sent)]

    def apply_task(self, context, task, created):
        req = task.requests[0]
        src = task.unit.objects[0]
        if self.use_modifiers and common.has_modifiers(src):
            depsgraph = context.evaluated_depsgraph_get()
            lod0 = bpy.data.meshes.new_from_object(src.evaluated_get(depsgraph),
                                                   preserve_all_data_layers=True,
                                                   depsgraph=depsgraph)
        else:
            lod0 = src.data.copy()
        lod0.name = src.name + "_LOD0"
        meshes = [created.add(lod0)]
        for i, _level in enumerate(req.result.get("levels", []), start=1):
            meshes.append(common.result_mesh(created, "%s_LOD%d" % (src.name, i),
                                             req.arrays_out, src, req.sent, self.normals,
                                             prefix="lod%d." % i))
        results = []
        for obj_src in task.unit.objects:
            coll = created.add(bpy.data.collections.new(obj_src.name + "_LODs"))
            parents = common.editable_collections(obj_src.users_collection)
            (parents[0] if parents else context.scene.collection).children.link(coll)
            width = max(obj_src.dimensions.x, 1e-6) * 1.25
            for i, mesh in enumerate(meshes):
                obj = common.new_object(created, "%s_LOD%d" % (obj_src.name, i), mesh, obj_src,
                                        [coll])
                if self.side_by_side and i:
                    m = obj.matrix_world.copy()
                    m.translation.x += i * width
                    obj.matrix_world = m
                results.append(obj)
        task.dropped = attributes.describe_dropped(req.sent, _dropped(req.result))
        # The report counts what Blender's statistics show: the levels' meshes as built.
        task.counts = [common.mesh_counts_text(m) for m in meshes]
        return results

    def finish(self, context, tasks, results):
        # Every object of a unit references the unit's file, with its own world matrix.
        files = [(obj, t.usd_file) for t in tasks if t.usd_file for obj in t.unit.objects]
        if files:
            common.write_assembly(common.abs_path(self.usd_path), context, files)

    def summary(self, context, tasks):
        dropped = ["%s: %s" % (t.label, ", ".join(t.dropped)) for t in tasks if t.dropped]
        if dropped:
            self.report({'WARNING'}, "tessd LODs: not carried to the levels: " + "; ".join(dropped))
        parts = ["%s: %s" % (t.label, ", ".join("LOD%d %s" % (i, text)
                                                for i, text in enumerate(t.counts)))
                 for t in tasks]
        return "tessd LODs: " + "; ".join(parts)


def _dropped(result):
    """Union of the levels' `dropped_attributes`."""
    out = set(result.get("dropped_attributes") or ())
    for level in result.get("levels", []):
        out.update(level.get("dropped_attributes") or ())
    return sorted(out)


def register():
    bpy.utils.register_class(TESSD_OT_generate_lods)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_generate_lods)
