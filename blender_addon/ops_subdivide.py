"""Subdivide…: uniform refinement by the daemon (Catmull–Clark = Blender's Subdivision
Surface modifier with "limit surface" off; Loop, Butterfly, Doo–Sabin, √3, bilinear), using
Blender's edge creases. The result is a new object `<name>_subdiv` (or the object's mesh data
replaced).

Animation (`use_animation`): the evaluated cage of every frame in [frame_start, frame_end]
goes to the daemon as the `frames` array of one `subdivide` request (one topology phase,
one apply per frame), which writes a .usda with the refined points as time samples. The new
object gets the refined mesh of frame_start as its data and a Mesh Sequence Cache modifier
reading the points of that file (`read_data = {'VERT'}`), with the cache's frame offset set
so that time code 1 is frame_start.

Why a cache and not shape keys: this is what Blender users expect of baked per-frame
geometry (simulation and Alembic/USD caches all work this way); the points stream from disk
per frame, so the .blend stays small even for dense meshes at many frames (shape keys would
store frames × vertices in the .blend and slow down every depsgraph update), and the same
file is read by every USD tool. The file lives next to the .blend (`//tessd_cache/`), or in
the temporary folder for an unsaved file, unless `cache_path` names it.
"""

import os
import tempfile

import bpy

from . import attributes, common, convert
from .jobs import JobOperator, Request, Task, UserError, skipped_task

SCHEMES = [
    ('CATMULL_CLARK', "Catmull-Clark", "Quads; any polygons (as Blender's modifier)"),
    ('LOOP', "Loop", "Smooth, for triangle meshes"),
    ('BUTTERFLY', "Butterfly", "Interpolating, for triangle meshes"),
    ('DOO_SABIN', "Doo-Sabin", "Dual scheme, any polygons"),
    ('SQRT3', "√3", "Slow-growing, for triangle meshes"),
    ('BILINEAR', "Bilinear", "Split faces, no smoothing (Blender's Simple)"),
]
BOUNDARIES = [
    ('EDGE_ONLY', "Smooth", "Boundary corners are smoothed (Blender's 'All')"),
    ('EDGE_AND_CORNER', "Keep corners", "Corners of a single face stay in place"),
]
UV_SMOOTH = [
    ('PRESERVE_CORNERS', "Keep corners", "Blender's default", "corners"),
    ('NONE', "None", "UVs linear", "linear"),
    ('PRESERVE_CORNERS_AND_JUNCTIONS', "Keep corners, junctions", "", "corners-junctions"),
    ('PRESERVE_CORNERS_JUNCTIONS_AND_CONCAVE', "Keep corners, junctions, concave", "",
     "corners-junctions-concave"),
    ('PRESERVE_BOUNDARIES', "Keep boundaries", "", "boundaries"),
    ('SMOOTH_ALL', "All", "", "smooth"),
]


def cache_file_path(op, obj):
    if op.cache_path:
        return common.abs_path(op.cache_path)
    name = common.usd_name(obj.name) + "_subdiv.usda"
    if bpy.data.filepath:
        return common.abs_path("//tessd_cache/" + name)
    return os.path.join(tempfile.gettempdir(), "tessd_cache", name)


class TESSD_OT_subdivide(JobOperator, bpy.types.Operator):
    """Subdivide the selected meshes (tessd)"""

    bl_idname = "tessd.subdivide"
    bl_label = "Subdivide"
    title = "tessd subdivide"

    scheme: bpy.props.EnumProperty(name="Scheme", items=SCHEMES, default='CATMULL_CLARK')
    levels: bpy.props.IntProperty(name="Levels", default=2, min=1, max=10, soft_max=6)
    use_gpu: bpy.props.BoolProperty(name="GPU", default=False,
                                    description="Evaluate on the GPU (Vulkan compute)")
    boundary: bpy.props.EnumProperty(name="Boundary", items=BOUNDARIES, default='EDGE_ONLY')
    uv_smooth: bpy.props.EnumProperty(name="UV Smooth",
                                      items=[x[:3] for x in UV_SMOOTH], default='PRESERVE_CORNERS')
    use_creases: bpy.props.BoolProperty(name="Use creases", default=True,
                                        description="Send the edge creases (crease_edge)")
    replace: bpy.props.BoolProperty(name="Replace mesh", default=False)
    use_modifiers: bpy.props.BoolProperty(name="Apply modifiers", default=True)
    use_animation: bpy.props.BoolProperty(
        name="Animation", default=False,
        description="Subdivide every frame of the range into a USD point cache read by a "
                    "Mesh Sequence Cache modifier")
    frame_start: bpy.props.IntProperty(name="Start", default=1)
    frame_end: bpy.props.IntProperty(name="End", default=250)
    cache_path: bpy.props.StringProperty(name="Cache file", default="", subtype='FILE_PATH',
                                         description=".usda for the animation (empty: "
                                                     "//tessd_cache/<name>_subdiv.usda)")

    def invoke(self, context, event):
        if not self.properties.is_property_set("frame_start"):
            self.frame_start = context.scene.frame_start
        if not self.properties.is_property_set("frame_end"):
            self.frame_end = context.scene.frame_end
        return super().invoke(context, event)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        for name in ("scheme", "levels", "use_gpu", "boundary", "uv_smooth", "use_creases",
                     "replace", "use_modifiers", "use_animation"):
            layout.prop(self, name)
        col = layout.column()
        col.enabled = self.use_animation
        col.prop(self, "frame_start")
        col.prop(self, "frame_end")
        col.prop(self, "cache_path")

    def _params(self):
        # normals: the result gets Blender's normals from the carried sharp faces and edges,
        # as Blender's own Subdivision Surface modifier gives them.
        return {"scheme": self.scheme.lower().replace("_", "-"), "levels": int(self.levels),
                "gpu": bool(self.use_gpu), "boundary": self.boundary.lower().replace("_", "-"),
                "uv_interpolation": {x[0]: x[3] for x in UV_SMOOTH}[self.uv_smooth],
                "normals": False}

    def prepare(self, context):
        evaluated = self.use_modifiers and not self.replace
        units, skipped = common.require_units(context, evaluated, self.replace)
        if self.use_animation:
            if self.frame_end < self.frame_start:
                raise UserError("tessd: the frame range %d..%d is empty"
                                % (self.frame_start, self.frame_end))
            if self.replace:
                raise UserError("tessd: an animation makes a new object; turn off Replace mesh")
        tasks = [skipped_task(name, why) for name, why in skipped]
        for unit in units:
            tasks.append(Task(unit.label, self._steps(context, unit, evaluated), unit=unit))
        return tasks

    def _steps(self, context, unit, evaluated):
        """The requests of one object: its refined mesh, and with an animation the frames,
        baked one frame per step (progress and Esc between frames)."""
        yield 0.0
        obj = unit.objects[0]
        scene = context.scene
        current = scene.frame_current, scene.frame_subframe
        try:
            if self.use_animation:
                scene.frame_set(self.frame_start)  # the rest pose: the first frame
            # The result comes back to Blender (the animation cache keeps points only).
            arrays, extra, sent = common.arrays_of(context, obj, evaluated,
                                                   creases=self.use_creases,
                                                   uniform_sharp_face=False)
            params = dict(self._params(), **extra)
            frames = None
            if self.use_animation:
                frames = yield from convert.frames_of(obj, scene, context.evaluated_depsgraph_get(),
                                                      self.frame_start, self.frame_end)
                if frames.shape[1] != len(arrays["positions"]):
                    raise ValueError("its modifiers change the vertex count between frames")
            arrays, frames = convert.drop_loose(arrays, frames)
        except ValueError as e:
            raise UserError("%s cannot be sent: %s" % (obj.name, e)) from e
        finally:
            if self.use_animation:
                scene.frame_set(current[0], subframe=current[1])
        requests = [Request("subdivide", params, arrays, label=unit.label, sent=sent)]
        if not self.use_animation:
            return requests
        path = cache_file_path(self, obj)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        # The cache carries points only (read_data = {'VERT'}).
        anim = {k: v for k, v in arrays.items()
                if k in ("positions", "face_indices", "face_sizes", "crease_edges",
                         "crease_values")}
        anim["frames"] = frames
        requests.append(Request(
            "subdivide", dict(params, output=path, name=common.usd_name(obj.name),
                              **common.stage_metadata(context)),
            anim, label=unit.label + " (%d frames)" % len(frames), cache=path))
        return requests

    def apply_task(self, context, task, created):
        req = task.requests[0]
        src = task.unit.objects[0]
        mesh = common.result_mesh(created, src.name if self.replace else src.name + "_subdiv",
                                  req.arrays_out, src, req.sent, 'BLENDER')
        results = common.unit_results(created, task.unit, mesh, "_subdiv", self.replace)
        cache = next((r.cache for r in task.requests if getattr(r, "cache", None)), None)
        if cache and not self.replace:
            for obj in results:
                self._add_cache(created, obj, cache, src.name)
        task.dropped = attributes.describe_dropped(req.sent, req.result.get("dropped_attributes"))
        return results

    def summary(self, context, tasks):
        dropped = ["%s: %s" % (t.label, ", ".join(t.dropped)) for t in tasks if t.dropped]
        if dropped:
            self.report({'WARNING'}, "tessd subdivide: not carried to the result: "
                        + "; ".join(dropped))
        r = [(t.requests[0].result, len(t.unit.names)) for t in tasks]
        return "tessd subdivide: %d object(s), %d vertices, %d faces" % (
            sum(n for _, n in r), sum(x["vertices"] * n for x, n in r),
            sum(x["faces"] * n for x, n in r))

    def _add_cache(self, created, obj, path, src_name):
        # bpy.data.cache_files has no load(); the Cache File "open" operator adds one.
        before = set(bpy.data.cache_files)
        bpy.ops.cachefile.open(filepath=path)
        cache = created.add(next(c for c in bpy.data.cache_files if c not in before))
        cache.frame_offset = self.frame_start - 1  # time code 1 = frame_start
        mod = obj.modifiers.new("tessd animation", 'MESH_SEQUENCE_CACHE')
        mod.cache_file = cache
        mod.object_path = "/Root/" + common.usd_name(src_name)
        mod.read_data = {'VERT'}


def register():
    bpy.utils.register_class(TESSD_OT_subdivide)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_subdivide)
