"""Simplify…: the dialog of paper 004's AutoCAD add-on (section 6, figure 7).

A method (regular subdivision / quality goal / complexity goal), the parameters of that
method, where a cell's vertices merge to, and "Show partition", which adds a wireframe
object of the cells (`<name>_partition`, with the source's transform, in the same
collections as the result). One `simplify` request per selected object; results are new
objects `<name>_simplified` unless `replace` swaps the object's mesh data (the object keeps
its name, transform and modifiers).
"""

import bpy

from . import common, convert
from .jobs import JobOperator, Request, UserError

METHODS = [
    ('GRID', "Regular subdivision", "Cells along each axis of the bounding box (or cubic cells "
             "of a given size); every non-empty cell becomes one vertex"),
    ('QUALITY', "Quality goal", "No vertex moves more than the maximum deviation"),
    ('COMPLEXITY', "Complexity goal", "Keep a target number of vertices"),
]
REPRESENTATIVES = [
    ('BARYCENTER', "Barycentre", "Weighted average of the cell's vertices"),
    ('HEAVIEST', "Heaviest vertex", "The cell's vertex with the largest weight (keeps corners)"),
    ('QUADRIC', "Quadric", "The point closest to the planes of the cell's faces"),
]


def simplify_params(op):
    """The daemon's `simplify` params for the operator's properties."""
    params = {"method": op.method.lower(), "representative": op.representative.lower(),
              "triangulate": bool(op.triangulate),
              "preserve_boundaries": bool(op.preserve_boundaries)}
    if op.method == 'GRID':
        if op.use_cell_size:
            params["cell_size"] = float(op.cell_size)
        else:
            params["cells"] = int(op.cells)
    elif op.method == 'QUALITY':
        params["max_error"] = ("%g%%" % op.max_error) if op.max_error_relative else float(op.max_error)
    else:
        if op.target_is_percent:
            params["target_vertices"] = "%g%%" % op.target
        else:
            params["target_vertices"] = max(1, int(round(op.target)))
    if op.show_partition:
        params["partition"] = True
    return params


class TESSD_OT_simplify(JobOperator, bpy.types.Operator):
    """Simplify the selected meshes by vertex clustering (tessd)"""

    bl_idname = "tessd.simplify"
    bl_label = "Simplify"
    title = "tessd simplify"

    method: bpy.props.EnumProperty(name="Method", items=METHODS, default='QUALITY')
    cells: bpy.props.IntProperty(name="Cells per axis", default=16, min=1, soft_max=1024)
    use_cell_size: bpy.props.BoolProperty(name="Cell size", default=False,
                                          description="Give the side of cubic cells instead")
    cell_size: bpy.props.FloatProperty(name="Cell size", default=0.1, min=1e-9,
                                       subtype='DISTANCE', precision=4)
    max_error: bpy.props.FloatProperty(name="Maximum deviation", default=1.0, min=1e-9,
                                       precision=4)
    max_error_relative: bpy.props.BoolProperty(
        name="% of size", default=True,
        description="Maximum deviation as a percentage of the largest side of the bounding box")
    target: bpy.props.FloatProperty(name="Target vertices", default=20.0, min=1e-6)
    target_is_percent: bpy.props.BoolProperty(name="% of vertices", default=True)
    representative: bpy.props.EnumProperty(name="Representative", items=REPRESENTATIVES,
                                           default='BARYCENTER')
    show_partition: bpy.props.BoolProperty(
        name="Show partition", default=False,
        description="Add a wireframe object of the partition's cells beside the result")
    replace: bpy.props.BoolProperty(name="Replace mesh", default=False,
                                    description="Replace the object's mesh data instead of "
                                                "adding a new object")
    use_modifiers: bpy.props.BoolProperty(name="Apply modifiers", default=True,
                                          description="Simplify the evaluated mesh (with "
                                                      "modifiers); not with Replace mesh")
    triangulate: bpy.props.BoolProperty(name="Triangulate", default=False)
    preserve_boundaries: bpy.props.BoolProperty(name="Preserve boundaries", default=False)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "method")
        if self.method == 'GRID':
            layout.prop(self, "use_cell_size")
            layout.prop(self, "cell_size" if self.use_cell_size else "cells")
        elif self.method == 'QUALITY':
            layout.prop(self, "max_error")
            layout.prop(self, "max_error_relative")
        else:
            layout.prop(self, "target")
            layout.prop(self, "target_is_percent")
        layout.prop(self, "representative")
        layout.prop(self, "show_partition")
        layout.separator()
        layout.prop(self, "replace")
        row = layout.row()
        row.enabled = not self.replace
        row.prop(self, "use_modifiers")
        layout.prop(self, "triangulate")
        layout.prop(self, "preserve_boundaries")

    def prepare(self, context):
        params = simplify_params(self)
        requests = []
        for obj in common.require_meshes(context):
            arrays, extra = common.arrays_of(context, obj, self.use_modifiers and not self.replace)
            requests.append(Request("simplify", dict(params, **extra), arrays, label=obj.name,
                                    object_name=obj.name))
        return requests

    def apply(self, context, requests, created):
        results, swaps = [], []
        for req in requests:
            src = common.get_object(req.object_name)
            if req.result.get("output_faces", 0) == 0:
                raise UserError("tessd simplify: nothing is left of %s (%s); choose a finer "
                                "goal" % (src.name, req.result.get("note") or "every face collapsed"))
            results.append(common.result_object(created, src, req.arrays_out, "_simplified",
                                                self.replace, swaps))
            if self.show_partition and "cells_min" in req.arrays_out:
                part = created.add(convert.partition_mesh(
                    src.name + "_partition", req.arrays_out["cells_min"], req.arrays_out["cells_max"]))
                obj = common.new_object(created, src.name + "_partition", part, src)
                obj.display_type = 'WIRE'
                obj.hide_render = False
        for src, mesh in swaps:  # last: nothing can fail after the scene's objects change
            src.data = mesh
        common.select_only(context, results)
        r = [req.result for req in requests]
        summary = "tessd simplify: %d object(s), %d -> %d vertices" % (
            len(r), sum(x["input_vertices"] for x in r), sum(x["output_vertices"] for x in r))
        # The verified distance between each input and its result (null for polygon results).
        errors = [x["surface_error"] for x in r if x.get("surface_error") is not None]
        if errors:
            summary += ", surfaces within %.4g of the input" % max(errors)
        return summary


def register():
    bpy.utils.register_class(TESSD_OT_simplify)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_simplify)
