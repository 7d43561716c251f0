"""Simplify…: the dialog of paper 004's AutoCAD add-on (section 6, figure 7).

A method (regular subdivision / quality goal / complexity goal), the parameters of that
method, where a cell's vertices merge to, the vertex weighting, and "Show partition", which
adds a wireframe object of the cells (`<name>_partition`, with the source's transform, in
the same collections as the result). Distances (cell size, an absolute maximum deviation)
are world-space lengths in the scene's units: the object's scale is taken out before they
reach the daemon, which works in object space. The complexity goal takes a vertex count, a
percentage of vertices, a face count or a ratio of faces (the Decimate modifier's "Ratio").

One `simplify` request per selected object (objects sharing a mesh: one for all, and the
result mesh is shared again); results are new objects `<name>_simplified` unless `replace`
swaps the object's mesh data (the object keeps its name, transform and modifiers). An object
that fails or is already below the target is skipped and reported; the others finish. The
report and the redo panel say what was achieved per object: vertices, faces, the maximum
deviation in scene units and in % of the object's size, the daemon's note.

Twisted polygons (issue 32): the quality and complexity goals bound the distance to the fan
triangulation of each polygon (first corner to the others), which for quads is Blender's own
split (its loop triangles take the first-to-third diagonal unless that folds the quad over).
When the daemon reports input polygons twisted by more than the tolerance (or the error
reached), another split of them (another tool's diagonal, Blender's ear-clipping of an n-gon)
may lie up to `polygon_twist` farther: that is reported as a WARNING and shown in the redo
panel (:func:`twist_line`). Polygons are sent as they are, not as Blender's loop triangles;
docs/simplify.md ("Twisted polygons") says why.
"""

import bpy
import numpy as np

from . import attributes, common, convert
from .jobs import JobOperator, Request, Task, UserError, skipped_task

METHODS = [
    ('GRID', "Regular subdivision", "Cells along each axis of the bounding box (or cubic cells "
             "of a given size); every non-empty cell becomes one vertex"),
    ('QUALITY', "Quality goal", "The result's surface stays within the maximum deviation of "
                "the input's"),
    ('COMPLEXITY', "Complexity goal", "Keep a target number of vertices or faces"),
]
REPRESENTATIVES = [
    ('BARYCENTER', "Barycentre", "Weighted average of the cell's vertices"),
    ('HEAVIEST', "Heaviest vertex", "The cell's vertex with the largest weight (keeps corners)"),
    ('QUADRIC', "Quadric", "The point closest to the planes of the cell's faces"),
]
WEIGHTINGS = [
    ('LONGEST_EDGE', "Longest edge", "A vertex weighs its longest edge (the paper's choice: "
                     "keeps the silhouette of sparse regions)"),
    ('CURVATURE', "Curvature", "A vertex weighs how sharply its faces turn (keeps details)"),
    ('UNIFORM', "Uniform", "Every vertex weighs the same"),
]
TARGET_MODES = [
    ('VERTICES', "Vertices", "A vertex count, or a percentage of the vertices"),
    ('FACES', "Faces", "A face (triangle) count"),
    ('RATIO', "Ratio", "A ratio of the faces, as the Decimate modifier's"),
]
NORMALS = [
    ('BLENDER', "Blender", "Blender's normals: flat where the input's faces were flat, sharp "
                "edges kept"),
    ('CUSTOM', "Custom", "The input's corner normals averaged per cell, as custom normals"),
]


def simplify_params(op, scale=1.0):
    """The daemon's `simplify` params for the operator's properties; `scale` turns
    world-space lengths into the object's space."""
    params = {"method": op.method.lower(), "representative": op.representative.lower(),
              "weighting": op.weighting.lower(),
              "triangulate": bool(op.triangulate),
              "preserve_boundaries": bool(op.preserve_boundaries)}
    if op.method == 'GRID':
        if op.use_cell_size:
            params["cell_size"] = float(op.cell_size) / scale
        else:
            params["cells"] = int(op.cells)
    elif op.method == 'QUALITY':
        params["max_error"] = (("%g%%" % op.max_error) if op.max_error_relative
                               else float(op.max_error) / scale)
    if op.show_partition:
        params["partition"] = True
    return params


def target_vertices(op, arrays):
    """The complexity goal as the daemon's `target_vertices`, or raise UserError when the
    object is already at or below it (nothing to simplify). A percentage of the vertices goes
    as it is (the daemon resolves it); counts are checked here, one object at a time."""
    if op.target_mode == 'VERTICES' and op.target_is_percent:
        return "%g%%" % op.target
    fi = arrays["face_indices"].reshape(-1)
    n = int(np.count_nonzero(np.bincount(fi, minlength=len(arrays["positions"]))))
    triangles = convert.triangle_count(arrays)
    if op.target_mode == 'VERTICES':
        want, what, have = max(1, int(round(op.target))), "vertices", n
    elif op.target_mode == 'FACES':
        want, what, have = max(1, int(op.target_faces)), "faces", triangles
    else:
        want, what, have = max(1, int(round(op.ratio * triangles))), "faces", triangles
    if want >= have:
        raise UserError("already at or below the target (%d ≤ %d %s)" % (have, want, what))
    if what == "vertices":
        return want
    return max(1, int(round(n * want / max(triangles, 1))))


class TESSD_OT_simplify(JobOperator, bpy.types.Operator):
    """Simplify the selected meshes by vertex clustering (tessd)"""

    bl_idname = "tessd.simplify"
    bl_label = "Simplify"
    bl_options = {'REGISTER', 'UNDO', 'PRESET'}
    title = "tessd simplify"

    method: bpy.props.EnumProperty(name="Method", items=METHODS, default='QUALITY')
    cells: bpy.props.IntProperty(name="Cells per axis", default=16, min=1, soft_max=1024)
    use_cell_size: bpy.props.BoolProperty(name="Cell size", default=False,
                                          description="Give the side of cubic cells instead")
    cell_size: bpy.props.FloatProperty(name="Cell size", default=0.1, min=1e-9,
                                       subtype='DISTANCE', unit='LENGTH', precision=4,
                                       description="Side of the cubic cells, in world space")
    max_error: bpy.props.FloatProperty(
        name="Maximum deviation", default=1.0, min=1e-9, precision=4,
        description="Largest distance between the result's surface and the input's: a "
                    "percentage of the object's size, or a world-space length in scene units")
    max_error_relative: bpy.props.BoolProperty(
        name="% of size", default=True,
        description="Maximum deviation as a percentage of the largest side of the bounding box")
    target_mode: bpy.props.EnumProperty(name="Target", items=TARGET_MODES, default='VERTICES')
    target: bpy.props.FloatProperty(name="Target vertices", default=20.0, min=1e-6)
    target_is_percent: bpy.props.BoolProperty(name="% of vertices", default=True)
    target_faces: bpy.props.IntProperty(name="Target faces", default=1000, min=1)
    ratio: bpy.props.FloatProperty(name="Ratio", default=0.5, min=0.0, max=1.0,
                                   subtype='FACTOR', description="Ratio of faces to keep")
    representative: bpy.props.EnumProperty(name="Representative", items=REPRESENTATIVES,
                                           default='BARYCENTER')
    weighting: bpy.props.EnumProperty(name="Weighting", items=WEIGHTINGS,
                                      default='LONGEST_EDGE')
    normals: bpy.props.EnumProperty(name="Normals", items=NORMALS, default='BLENDER')
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
    achieved: bpy.props.StringProperty(name="Achieved", default="",
                                       options={'HIDDEN', 'SKIP_SAVE'})

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "method")
        if self.method == 'GRID':
            layout.prop(self, "use_cell_size")
            layout.prop(self, "cell_size" if self.use_cell_size else "cells")
        elif self.method == 'QUALITY':
            if self.max_error_relative:
                layout.prop(self, "max_error", text="Max deviation (% of size)")
            else:
                layout.prop(self, "max_error", text="Max deviation (world)")
                layout.label(text="= " + common.length_text(context, self.max_error))
            layout.prop(self, "max_error_relative")
        else:
            layout.prop(self, "target_mode")
            if self.target_mode == 'VERTICES':
                layout.prop(self, "target")
                layout.prop(self, "target_is_percent")
            elif self.target_mode == 'FACES':
                layout.prop(self, "target_faces")
            else:
                layout.prop(self, "ratio")
        layout.prop(self, "representative")
        layout.prop(self, "weighting")
        layout.prop(self, "normals")
        layout.prop(self, "show_partition")
        layout.separator()
        layout.prop(self, "replace")
        row = layout.row()
        row.enabled = not self.replace
        row.prop(self, "use_modifiers")
        layout.prop(self, "triangulate")
        layout.prop(self, "preserve_boundaries")
        if self.achieved:
            box = layout.box()
            for line in self.achieved.split("\n"):
                box.label(text=line)

    def prepare(self, context):
        self.achieved = ""
        evaluated = self.use_modifiers and not self.replace
        units, skipped = common.require_units(context, evaluated, self.replace)
        tasks = [skipped_task(name, why) for name, why in skipped]
        for unit in units:
            tasks.append(Task(unit.label, self._steps(context, unit, evaluated), unit=unit))
        return tasks

    def _steps(self, context, unit, evaluated):
        yield 0.0
        scale = unit.scale()
        arrays, extra, sent = common.arrays_of(context, unit.objects[0], evaluated,
                                               normals=self.normals == 'CUSTOM',
                                               uniform_sharp_face=False)
        params = dict(simplify_params(self, scale), **extra)
        if self.method == 'COMPLEXITY':
            params["target_vertices"] = target_vertices(self, arrays)
        # The report counts faces as Blender shows them (polygons), not the triangles the
        # daemon splits them into.
        return [Request("simplify", params, arrays, label=unit.label, sent=sent, scale=scale,
                        input_polygons=convert.face_count(arrays))]

    def apply_task(self, context, task, created):
        req = task.requests[0]
        src = task.unit.objects[0]
        if req.result.get("output_faces", 0) == 0:
            raise UserError("nothing is left (%s); choose a finer goal"
                            % (req.result.get("note") or "every face collapsed"))
        mesh = common.result_mesh(created, src.name if self.replace else src.name + "_simplified",
                                  req.arrays_out, src, req.sent, self.normals)
        results = common.unit_results(created, task.unit, mesh, "_simplified", self.replace)
        if self.show_partition and "cells_min" in req.arrays_out:
            part = created.add(convert.partition_mesh(
                src.name + "_partition", req.arrays_out["cells_min"], req.arrays_out["cells_max"]))
            obj = common.new_object(created, src.name + "_partition", part, src)
            obj.display_type = 'WIRE'
            obj.hide_render = False
        task.dropped = attributes.describe_dropped(req.sent, req.result.get("dropped_attributes"))
        return results

    def summary(self, context, tasks):
        lines, panel = [], []
        for t in tasks:
            result, scale = t.requests[0].result, t.requests[0].scale
            twist = twist_line(context, t.label, result, scale)
            # A twist note goes out as a warning of its own, not inside the summary too.
            note = result.get("note") or ""
            if twist:
                note = note.split(TWIST_NOTE)[0].rstrip("; ")
            line = achieved_line(context, t.label, result, t.unit.objects[0], scale, note,
                                 input_polygons=t.requests[0].input_polygons)
            lines.append(line)
            panel.append(line)
            if twist:
                self.report({'WARNING'}, "tessd simplify: " + twist)
                panel.append("⚠ " + twist)
        self.achieved = "\n".join(panel)
        dropped = ["%s: %s" % (t.label, ", ".join(t.dropped)) for t in tasks if t.dropped]
        if dropped:
            self.report({'WARNING'}, "tessd simplify: not carried to the result: "
                        + "; ".join(dropped))
        return "tessd simplify: " + "; ".join(lines)


#: How the daemon's note about twisted polygons begins (after any other note and "; ").
TWIST_NOTE = "the bound holds for tessd's fan triangulation"


def twist_line(context, label, result, scale):
    """The warning for input polygons twisted by more than the tolerance (quality goal) or
    the error reached (complexity goal), with lengths in scene units; None when there are
    none (or the method does not bound the surfaces)."""
    n = result.get("twisted_polygons") or 0
    twist = result.get("polygon_twist")
    if n <= 0 or not twist:
        return None
    limit = result.get("tolerance")
    what = "the tolerance"
    if limit is None:
        limit, what = result.get("surface_error"), "the deviation reached"
    ratio = " (%.3g× %s)" % (twist / limit, what) if limit else ""
    return ("%s: %d polygon%s twisted by up to %s%s; the deviation holds for tessd's split of "
            "each polygon (first corner to the others, as Blender splits quads), another "
            "split (another tool's diagonal, an n-gon's triangulation) may lie up to that "
            "much farther" % (label, n, " is" if n == 1 else "s are",
                              common.length_text(context, twist * scale), ratio))


def achieved_line(context, label, result, obj, scale, note=None, input_polygons=None):
    """One object's figures: vertices, faces (the input's as Blender counts them, polygons,
    when `input_polygons` is given: `500 faces (968 triangles) → 278 faces`), the deviation
    (world space, scene units, and % of the object's largest side), clusters, and `note`
    (default: the daemon's)."""
    faces_in = "%d" % result["input_faces"]
    if input_polygons is not None and input_polygons != result["input_faces"]:
        faces_in = "%d faces (%d triangles)" % (input_polygons, result["input_faces"])
    text = "%s: %d → %d vertices, %s → %d faces" % (
        label, result["input_vertices"], result["output_vertices"], faces_in,
        result["output_faces"])
    bound = result.get("surface_error")
    dev = bound if bound is not None else result.get("max_displacement")
    if dev is not None:
        world = dev * scale
        size = max(obj.dimensions) if max(obj.dimensions) > 0 else 1.0
        what = "max deviation" if bound is not None else "vertices moved at most"
        text += ", %s %s (%.3g%% of size)" % (what, common.length_text(context, world),
                                             100.0 * world / size)
    if result.get("clusters") is not None:
        text += ", %d clusters" % result["clusters"]
    note = result.get("note") if note is None else note
    if note:
        text += " (%s)" % note
    return text


def register():
    bpy.utils.register_class(TESSD_OT_simplify)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_simplify)
