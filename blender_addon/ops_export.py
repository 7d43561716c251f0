"""Export USD via tessd…: the selected objects as USD written by the daemon.

Each object becomes `<stem>_<name>.usda` beside `filepath` (its mesh in object space, with
materials as GeomSubsets, UVs and normals; or, with `as_lods`, its LOD chain as a `LOD`
variant set), and `filepath` is a stage that references them, one Xform per object carrying
its world matrix, so the transforms survive without being baked into the points.
"""

import os

import bpy
from bpy_extras.io_utils import ExportHelper

from . import common
from .jobs import JobOperator, Request, UserError
from .ops_lods import parse_levels


class TESSD_OT_export_usd(JobOperator, ExportHelper, bpy.types.Operator):
    """Export the selected meshes as USD through tessd"""

    bl_idname = "tessd.export_usd"
    bl_label = "Export USD via tessd"
    title = "tessd USD export"
    dialog = False

    filename_ext = ".usda"
    filter_glob: bpy.props.StringProperty(default="*.usda", options={'HIDDEN'})
    as_lods: bpy.props.BoolProperty(name="As LOD chains", default=False,
                                    description="Write each object's LOD chain as a LOD "
                                                "variant set")
    levels: bpy.props.StringProperty(name="Levels", default="50%,20%,5%")
    use_modifiers: bpy.props.BoolProperty(name="Apply modifiers", default=True)

    def invoke(self, context, event):
        self._modal = context.window is not None
        return ExportHelper.invoke(self, context, event)

    def prepare(self, context):
        if not self.filepath:
            raise UserError("tessd: no file name given")
        path = common.abs_path(self.filepath)
        if not path.lower().endswith(".usda"):
            raise UserError("tessd: tessd writes .usda files, got %s" % path)
        objs = common.require_meshes(context)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        stem = os.path.splitext(path)[0]
        meta = common.stage_metadata(context)
        requests = []
        for obj in objs:
            arrays, extra = common.arrays_of(context, obj, self.use_modifiers)
            out = "%s_%s.usda" % (stem, common.usd_name(obj.name))
            params = dict(extra, output=out, name=common.usd_name(obj.name), **meta)
            if self.as_lods:
                params["levels"] = parse_levels(self.levels)
                requests.append(Request("lod", params, arrays, label=obj.name,
                                        object_name=obj.name, out=out))
            else:
                requests.append(Request("mesh.convert", params, arrays, label=obj.name,
                                        object_name=obj.name, out=out))
        return requests

    def apply(self, context, requests, created):
        path = common.abs_path(self.filepath)
        entries = [(common.get_object(r.object_name), r.out) for r in requests]
        common.write_assembly(path, context, entries)
        return "tessd: wrote %s (%d object(s))" % (path, len(entries))


def register():
    bpy.utils.register_class(TESSD_OT_export_usd)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_export_usd)
