"""Import compressed mesh (view-dependent): what the active camera needs of a `.tsc` file.

The daemon decodes each cell of the file's nSP-tree only as far as the scene camera needs
(`codec.view`, paper 003 §6.2): a vertex's error, projected through the camera at the render
resolution, stays within `pixel_error` pixels; cells outside the camera's view are left out.
The daemon keeps the file's decoder state, so importing again after moving the camera refines
from the previous view. The result is a new object in world space.
"""

import math
import os

import bpy
from bpy_extras.io_utils import ImportHelper

from . import common, convert
from .jobs import JobOperator, Request, Task, UserError


def camera_params(scene):
    """The scene camera as `codec.view` takes it: eye, target, up, vertical field of view in
    degrees, and the render size in pixels."""
    cam = scene.camera
    if cam is None or cam.type != 'CAMERA':
        raise UserError("tessd: the scene has no active camera to decode for")
    if cam.data.type != 'PERSP':
        raise UserError("tessd: the camera is %s; view-dependent import needs a perspective "
                        "camera" % cam.data.type.lower())
    r = scene.render
    w = max(1, round(r.resolution_x * r.resolution_percentage / 100))
    h = max(1, round(r.resolution_y * r.resolution_percentage / 100))
    w_eff, h_eff = w * r.pixel_aspect_x, h * r.pixel_aspect_y
    fit = cam.data.sensor_fit
    if fit == 'AUTO':
        fit = 'HORIZONTAL' if w_eff >= h_eff else 'VERTICAL'
    angle = cam.data.angle
    fov_v = angle if fit == 'VERTICAL' else 2.0 * math.atan(math.tan(angle / 2.0) * h_eff / w_eff)
    m = cam.matrix_world
    eye = m.translation
    forward = -m.col[2].xyz.normalized()
    up = m.col[1].xyz.normalized()
    target = eye + forward
    return dict(eye=list(eye), target=list(target), up=list(up), fov=math.degrees(fov_v),
                size=[w, h])


class TESSD_OT_import_compressed(JobOperator, ImportHelper, bpy.types.Operator):
    """Import what the active camera needs of a compressed .tsc mesh"""

    bl_idname = "tessd.import_compressed"
    bl_label = "Import compressed mesh (view-dependent)"
    title = "tessd import"
    dialog = False

    filename_ext = ".tsc"
    filter_glob: bpy.props.StringProperty(default="*.tsc", options={'HIDDEN'})
    pixel_error: bpy.props.FloatProperty(
        name="Pixel error", default=1.0, min=0.01, soft_max=16.0,
        description="Largest error of a vertex on screen, in pixels of the render resolution")

    @classmethod
    def poll(cls, context):
        return context.mode == 'OBJECT'

    def invoke(self, context, event):
        self._modal = context.window is not None
        return ImportHelper.invoke(self, context, event)

    def prepare(self, context):
        path = common.abs_path(self.filepath) if self.filepath else ""
        if not os.path.isfile(path):
            raise UserError("tessd: no .tsc file at %r" % path)
        params = dict(camera_params(context.scene), input=path, pixel_error=self.pixel_error)
        name = os.path.splitext(os.path.basename(path))[0]
        return [Task(name, self._steps(params, name), name=name)]

    def _steps(self, params, name):
        yield 0.0
        return [Request("codec.view", params, None, label=name)]

    def apply_task(self, context, task, created):
        req = task.requests[0]
        mesh = created.add(convert.mesh_from_arrays(task.name, req.arrays_out))
        obj = created.add(bpy.data.objects.new(task.name, mesh))
        context.scene.collection.objects.link(obj)
        obj["tessd_tsc"] = req.params["input"]
        obj["tessd_pixel_error"] = req.params["pixel_error"]
        return [obj]

    def summary(self, context, tasks):
        r = tasks[0].requests[0].result
        return "tessd: %s: %d triangles from %d cells (%d of %d bytes read)" % (
            tasks[0].name, r["triangles"], r["cells"], r["bytes_read"], r["file_bytes"])


def register():
    bpy.utils.register_class(TESSD_OT_import_compressed)


def unregister():
    bpy.utils.unregister_class(TESSD_OT_import_compressed)
