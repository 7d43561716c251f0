"""Export USD via tessd…: the selected objects as USD written by the daemon.

Each object becomes `<stem>_<name>.usda` beside `filepath` (its mesh in object space, with
materials as GeomSubsets, UVs and normals; or, with `as_lods`, its LOD chain as a `LOD`
variant set), and `filepath` is a stage that references them, one Xform per object carrying
its world matrix, so the transforms survive without being baked into the points.
"""

import os

import bpy
from bpy_extras.io_utils import ExportHelper

from . import attributes, common
from .jobs import JobOperator, Request, Task, UserError, skipped_task
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
        units, skipped = common.require_units(context, self.use_modifiers)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        stem = os.path.splitext(path)[0]
        tasks = [skipped_task(name, why) for name, why in skipped]
        for unit in units:
            out = "%s_%s.usda" % (stem, common.usd_name(unit.names[0]))
            tasks.append(Task(unit.label, self._steps(context, unit, out), unit=unit, out=out))
        return tasks

    def _steps(self, context, unit, out):
        yield 0.0
        src = unit.objects[0]
        arrays, extra, sent = common.arrays_of(context, src, self.use_modifiers, normals=True)
        params = dict(extra, output=out, name=common.usd_name(src.name),
                      **common.stage_metadata(context))
        if self.as_lods:
            params["levels"] = parse_levels(self.levels)
            return [Request("lod", params, arrays, label=unit.label, sent=sent)]
        return [Request("mesh.convert", params, arrays, label=unit.label, sent=sent)]

    def apply_task(self, context, task, created):
        task.dropped = attributes.describe_dropped(
            task.requests[0].sent, task.requests[0].result.get("dropped_attributes"))
        return []

    def finish(self, context, tasks, results):
        # Every object of a unit references the unit's file, with its own transform.
        entries = [(obj, t.out) for t in tasks for obj in t.unit.objects]
        common.write_assembly(common.abs_path(self.filepath), context, entries)
        self._entries = len(entries)

    def summary(self, context, tasks):
        dropped = ["%s: %s" % (t.label, ", ".join(t.dropped)) for t in tasks if t.dropped]
        if dropped:
            self.report({'WARNING'}, "tessd USD export: not written: " + "; ".join(dropped))
        return "tessd: wrote %s (%d object(s))" % (common.abs_path(self.filepath), self._entries)


def register():
    bpy.utils.register_class(TESSD_OT_export_usd)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_export_usd)
