"""Generate LODs…: one `lod` request per selected object (every level simplified from the
input, so each level's bound holds against it). The result is a collection `<name>_LODs`
holding `<name>_LOD0` (a copy of the input) .. `<name>_LOD<n>`, all with the source's
transform (or side by side along X with `side_by_side`). With `usd_path`, the daemon also
writes one stage with the `LOD` variant set (docs/protocol.md, lod); with several selected
objects each gets `<stem>_<name>.usda` and `usd_path` becomes a stage referencing them.
"""

import os

import bpy

from . import common, convert
from .jobs import JobOperator, Request, UserError
from .ops_simplify import REPRESENTATIVES

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
        for name in ("levels", "method", "representative", "usd_path", "lod_schema",
                     "side_by_side", "use_modifiers"):
            layout.prop(self, name)

    def prepare(self, context):
        levels = parse_levels(self.levels)
        objs = common.require_meshes(context)
        base = {"levels": levels, "method": self.method.lower(),
                "representative": self.representative.lower()}
        usd = common.abs_path(self.usd_path) if self.usd_path else ""
        if usd and not usd.lower().endswith(".usda"):
            raise UserError("tessd: the USD file must end in .usda, got %s" % usd)
        requests = []
        for obj in objs:
            arrays, extra = common.arrays_of(context, obj, self.use_modifiers)
            params = dict(base, **extra)
            requests.append(Request("lod", params, arrays, label=obj.name, object_name=obj.name))
            if usd:
                path = common.per_object_path(usd, obj.name, len(objs))
                os.makedirs(os.path.dirname(path), exist_ok=True)
                requests.append(Request(
                    "lod", dict(params, output=path, name=common.usd_name(obj.name),
                                lod_schema=self.lod_schema.lower(), **common.stage_metadata(context)),
                    arrays, label=obj.name + " (USD)", object_name=obj.name, usd_file=path))
        return requests

    def apply(self, context, requests, created):
        results = []
        depsgraph = context.evaluated_depsgraph_get()
        usd_files = [(common.get_object(r.object_name), r.usd_file)
                     for r in requests if getattr(r, "usd_file", None)]
        for req in (r for r in requests if not getattr(r, "usd_file", None)):
            src = common.get_object(req.object_name)
            coll = created.add(bpy.data.collections.new(src.name + "_LODs"))
            parent = src.users_collection[0] if src.users_collection else context.scene.collection
            parent.children.link(coll)
            if self.use_modifiers:
                lod0 = bpy.data.meshes.new_from_object(src.evaluated_get(depsgraph),
                                                       preserve_all_data_layers=True,
                                                       depsgraph=depsgraph)
            else:
                lod0 = src.data.copy()
            lod0.name = src.name + "_LOD0"
            meshes = [created.add(lod0)]
            for i, _level in enumerate(req.result.get("levels", []), start=1):
                meshes.append(created.add(convert.mesh_from_arrays(
                    "%s_LOD%d" % (src.name, i), req.arrays_out, prefix="lod%d." % i,
                    materials=common.materials_of(src), uv_name=common.uv_name_of(src))))
            width = max(src.dimensions.x, 1e-6) * 1.25
            for i, mesh in enumerate(meshes):
                obj = common.new_object(created, "%s_LOD%d" % (src.name, i), mesh, src, [coll])
                if self.side_by_side and i:
                    m = obj.matrix_world.copy()
                    m.translation.x += i * width
                    obj.matrix_world = m
                results.append(obj)
        if len(usd_files) > 1:
            common.write_assembly(common.abs_path(self.usd_path), context, usd_files)
        common.select_only(context, results)
        return "tessd LODs: %d object(s) in %d collection(s)" % (
            len(results), len(requests) - len(usd_files))


def register():
    bpy.utils.register_class(TESSD_OT_generate_lods)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_generate_lods)
