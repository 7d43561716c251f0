"""The add-on screenshots of the README, rendered by Blender itself (Workbench engine).

    .venv/bin/python docs/screenshots/make_screenshots.py [--out docs/screenshots]

Builds the extension zip, installs and enables it in a throw-away Blender user folder (as the
tests do, `tests/blender_addon/addon_env.py`), starts `tessd serve` (target/release/tessd or
$TESSD_BIN), runs the add-on's real operators on real meshes and renders:

- lod_chain.png: the Stanford bunny's LOD chain from `tessd.generate_lods`, LOD0 (the input,
  shaded smooth) .. LOD3, side by side, each labelled with its triangle count, shaded with
  Blender's own normals (faces whose corners would face away from them are flat);
- partition.png: `tessd.simplify(method='QUALITY', show_partition=True)`: the input with the
  partition's cells, the result with the cells, the result alone;
- subdivided_cage.png: `tessd.subdivide` (Catmull-Clark, level 3): a cube cage with four
  creased edges (red) and the Spot cage, each as a wireframe beside its result.

The shared meshes come from $TESSD_SHARED_DATA (default ../shared/data, see tests/locate.py).
Wire objects (partition, cages) are rendered as thin tubes (the mesh converted to a curve with
a bevel), since a render has no wireframe overlay.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "tests" / "blender_addon"), str(REPO / "tests"),
                str(REPO / "tests" / "daemon"), str(REPO / "python")]
_USER = tempfile.mkdtemp(prefix="tessd-blender-user-")
os.environ.setdefault("BLENDER_USER_RESOURCES", _USER)

import numpy as np  # noqa: E402

WIDTH, HEIGHT = 1200, 500
BACKGROUND = (0.92, 0.92, 0.93)
SURFACE = (0.80, 0.80, 0.78, 1.0)
RESULT = (0.55, 0.72, 0.90, 1.0)
WIRE = (0.10, 0.25, 0.60, 1.0)
PARTITION = (0.95, 0.45, 0.05, 1.0)
CREASE = (0.85, 0.10, 0.10, 1.0)
TEXT = (0.08, 0.08, 0.08, 1.0)


# ---------------------------------------------------------------------------------------------
# Scene helpers


def bpy():
    import bpy as _bpy

    return _bpy


def clear_scene():
    b = bpy()
    for coll in (b.data.objects, b.data.collections, b.data.meshes, b.data.curves,
                 b.data.cameras, b.data.materials):
        for block in list(coll):
            coll.remove(block)


def select(*objs):
    b = bpy()
    for o in b.context.view_layer.objects:
        o.select_set(False)
    for o in objs:
        o.select_set(True)
    b.context.view_layer.objects.active = objs[0] if objs else None


def tris(obj):
    """Triangles of a mesh object once triangulated (sum of n - 2 over its faces)."""
    sizes = np.empty(len(obj.data.polygons), dtype=np.int32)
    obj.data.polygons.foreach_get("loop_total", sizes)
    return int((sizes - 2).sum())


def group(n):
    return "{:,}".format(n).replace(",", " ")


def colour(obj, rgba):
    obj.color = rgba
    return obj


def move(obj, dx=0.0, dy=0.0, dz=0.0):
    m = obj.matrix_world.copy()
    m.translation.x += dx
    m.translation.y += dy
    m.translation.z += dz
    obj.matrix_world = m
    bpy().context.view_layer.update()
    return obj


def world_corners(obj):
    from mathutils import Vector

    return [obj.matrix_world @ Vector(c) for c in obj.bound_box]


def bounds(objs):
    pts = np.array([tuple(p) for o in objs for p in world_corners(o)])
    return pts.min(axis=0), pts.max(axis=0)


def wire_object(name, mesh_obj, edges_mask=None, radius=0.002, rgba=WIRE):
    """A renderable wireframe of `mesh_obj` (or of the edges where `edges_mask` is true):
    an edge-only copy converted to a curve with a round bevel of `radius`, same transform."""
    b = bpy()
    src = mesh_obj.data
    co = np.empty(len(src.vertices) * 3, dtype=np.float32)
    src.vertices.foreach_get("co", co)
    ev = np.empty(len(src.edges) * 2, dtype=np.int32)
    src.edges.foreach_get("vertices", ev)
    ev = ev.reshape(-1, 2)
    if edges_mask is not None:
        ev = ev[edges_mask]
    mesh = b.data.meshes.new(name)
    mesh.vertices.add(len(co) // 3)
    mesh.vertices.foreach_set("co", co)
    mesh.edges.add(len(ev))
    mesh.edges.foreach_set("vertices", np.ascontiguousarray(ev.reshape(-1)))
    mesh.update()
    obj = b.data.objects.new(name, mesh)
    b.context.scene.collection.objects.link(obj)
    obj.matrix_world = mesh_obj.matrix_world.copy()
    select(obj)
    b.ops.object.convert(target='CURVE')
    obj = b.context.object
    obj.data.bevel_depth = radius / max(obj.matrix_world.to_scale())
    obj.data.bevel_resolution = 2
    return colour(obj, rgba)


def label(text, x, z, y, size, rotation):
    b = bpy()
    curve = b.data.curves.new("label", 'FONT')
    curve.body = text
    curve.size = size
    curve.align_x = 'CENTER'
    curve.align_y = 'TOP'
    obj = b.data.objects.new("label", curve)
    b.context.scene.collection.objects.link(obj)
    obj.location = (x, y, z)
    obj.rotation_euler = rotation
    return colour(obj, TEXT)


def labels_under(objs, texts, size, rotation, gap=0.08):
    """One text under each object (centred on its X), all on one line below the lowest one."""
    lo, hi = bounds(objs)
    z = lo[2] - gap * (hi[2] - lo[2])
    out = []
    for o, t in zip(objs, texts):
        olo, ohi = bounds([o])
        out.append(label(t, 0.5 * (olo[0] + ohi[0]), z, 0.5 * (olo[1] + ohi[1]), size, rotation))
    return out


def render(path, objs, rotation, margin=1.08):
    """Renders `objs` (everything else hidden) with an orthographic camera of Euler
    `rotation`, fitted to their bounds, Workbench studio lighting, cavity and outline."""
    from mathutils import Euler, Vector

    b = bpy()
    scene = b.context.scene
    keep = set(objs)
    for o in scene.objects:
        o.hide_render = o not in keep
    b.context.view_layer.update()

    rot = Euler(rotation).to_matrix()
    inv = rot.transposed()
    pts = [inv @ p for o in objs for p in world_corners(o)]
    xs = [p.x for p in pts]
    ys = [p.y for p in pts]
    zs = [p.z for p in pts]
    cx, cy = 0.5 * (min(xs) + max(xs)), 0.5 * (min(ys) + max(ys))
    w, h = max(xs) - min(xs), max(ys) - min(ys)
    aspect = WIDTH / HEIGHT
    cam_data = b.data.cameras.new("Camera")
    cam_data.type = 'ORTHO'
    cam_data.ortho_scale = max(w, h * aspect) * margin
    cam_data.clip_start = 0.001
    depth = max(zs) - min(zs)
    cam_data.clip_end = 10.0 * (depth + w + h)
    cam = b.data.objects.new("Camera", cam_data)
    scene.collection.objects.link(cam)
    cam.rotation_euler = rotation
    cam.location = rot @ Vector((cx, cy, max(zs) + depth + 1.0))
    scene.camera = cam

    scene.render.engine = 'BLENDER_WORKBENCH'
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.render.image_settings.file_format = 'PNG'
    scene.render.image_settings.color_mode = 'RGB'
    scene.display.render_aa = '16'
    scene.view_settings.view_transform = 'Standard'
    if scene.world is None:
        scene.world = b.data.worlds.new("World")
    scene.world.color = BACKGROUND
    sh = scene.display.shading
    sh.light = 'STUDIO'
    sh.color_type = 'OBJECT'
    sh.show_cavity = True
    sh.cavity_type = 'BOTH'
    sh.cavity_ridge_factor = 1.0
    sh.cavity_valley_factor = 1.0
    sh.show_object_outline = True
    sh.object_outline_color = (0.15, 0.15, 0.15)
    sh.show_specular_highlight = True
    scene.render.filepath = str(path)
    b.ops.render.render(write_still=True)
    b.data.objects.remove(cam)
    print("wrote", path)


# ---------------------------------------------------------------------------------------------
# The three pictures

FRONT = (math.radians(82), 0.0, math.radians(18))


def import_bunny(data):
    b = bpy()
    b.ops.wm.ply_import(filepath=str(data / "bun_zipper.ply"), forward_axis='Y', up_axis='Z')
    obj = b.context.object
    obj.name = obj.data.name = "Bunny"
    obj.data.shade_smooth()  # a scan is shown smooth (the importer makes every face flat)
    obj.rotation_euler = (math.radians(90), 0.0, 0.0)  # the scan is Y-up
    obj.scale = (10.0, 10.0, 10.0)
    b.context.view_layer.update()
    lo, _hi = bounds([obj])
    move(obj, dz=-lo[2])
    return colour(obj, SURFACE)


def lod_chain(data, out):
    b = bpy()
    clear_scene()
    bunny = import_bunny(data)
    select(bunny)
    assert b.ops.tessd.generate_lods(levels="20%,5%,1%", method='COMPLEXITY',
                                     representative='QUADRIC', side_by_side=True) == {'FINISHED'}
    lods = [b.data.objects["Bunny_LOD%d" % i] for i in range(4)]
    for o in lods:
        colour(o, SURFACE if o.name.endswith("0") else RESULT)
    goals = ["input", "20 % of vertices", "5 %", "1 %"]
    texts = ["LOD%d  %s\n%s triangles" % (i, g, group(tris(o))) for i, (o, g) in enumerate(zip(lods, goals))]
    size = 0.09 * (bounds([bunny])[1][2] - bounds([bunny])[0][2])
    texts_objs = labels_under(lods, texts, size, FRONT)
    render(out / "lod_chain.png", lods + texts_objs, FRONT)
    return [(o.name, tris(o)) for o in lods]


MAX_ERROR = 5.0  # % of the largest side


def partition(data, out):
    b = bpy()
    clear_scene()
    bunny = import_bunny(data)
    select(bunny)
    assert b.ops.tessd.simplify(method='QUALITY', max_error=MAX_ERROR, max_error_relative=True,
                                representative='QUADRIC', show_partition=True) == {'FINISHED'}
    result = b.data.objects["Bunny_simplified"]
    part = b.data.objects["Bunny_partition"]
    cells = len(part.data.vertices) // 8
    width = bunny.dimensions.x * 1.3
    colour(result, RESULT)
    move(result, dx=width)
    alone = colour(result.copy(), RESULT)
    b.context.scene.collection.objects.link(alone)
    move(alone, dx=width)
    radius = 0.0018 * max(bunny.dimensions)
    wires = [wire_object("cells_on_input", part, radius=radius, rgba=PARTITION)]
    w2 = wire_object("cells_on_result", part, radius=radius, rgba=PARTITION)
    move(w2, dx=width)
    wires.append(w2)
    size = 0.08 * bunny.dimensions.z
    texts = ["input, %s triangles\n+ partition: %d cells" % (group(tris(bunny)), cells),
             "quality goal %g %%: %s triangles\n+ partition" % (MAX_ERROR, group(tris(result))),
             "result, %s triangles" % group(tris(alone))]
    texts_objs = labels_under([bunny, result, alone], texts, size, FRONT)
    render(out / "partition.png", [bunny, result, alone] + wires + texts_objs, FRONT)
    return cells, tris(bunny), tris(result)


def creased_cube():
    b = bpy()
    b.ops.mesh.primitive_cube_add()
    obj = b.context.object
    obj.name = obj.data.name = "Cube"
    mesh = obj.data
    mesh.shade_smooth()  # Blender's cube is flat, and a subdivided flat cage stays flat
    verts = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", verts)
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    top = co.reshape(-1, 3)[:, 2] > 0
    values = top[verts.reshape(-1, 2)].all(axis=1).astype(np.float32)
    attr = mesh.attributes.new("crease_edge", "FLOAT", "EDGE")
    attr.data.foreach_set("value", values)
    return obj, values > 0


def subdivided_cage(data, out):
    b = bpy()
    clear_scene()
    cube, creased = creased_cube()
    b.ops.wm.obj_import(filepath=str(data / "spot_control_mesh.obj"), forward_axis='Y', up_axis='Z')
    spot = b.context.object
    spot.name = spot.data.name = "Spot"
    spot.rotation_euler = (math.radians(90), 0.0, math.radians(90))  # Y-up; side view
    b.context.view_layer.update()
    s = 2.0 / max(spot.dimensions)
    spot.scale = (s, s, s)
    b.context.view_layer.update()
    select(cube, spot)
    assert b.ops.tessd.subdivide(scheme='CATMULL_CLARK', levels=3, use_creases=True) == {'FINISHED'}
    cube_s, spot_s = b.data.objects["Cube_subdiv"], b.data.objects["Spot_subdiv"]
    # cube cage | cube result | spot cage | spot result, all standing on z = -1
    step = 2.6
    placed = []
    for i, obj in enumerate((cube, cube_s, spot, spot_s)):
        lo, hi = bounds([obj])
        move(obj, dx=i * step - 0.5 * (lo[0] + hi[0]), dy=-0.5 * (lo[1] + hi[1]), dz=-1.0 - lo[2])
        placed.append(obj)
    radius = 0.012
    cube_wire = wire_object("cube_cage", cube, edges_mask=~creased, radius=radius, rgba=WIRE)
    cube_crease = wire_object("cube_creases", cube, edges_mask=creased, radius=1.6 * radius, rgba=CREASE)
    spot_wire = wire_object("spot_cage", spot, radius=radius, rgba=WIRE)
    colour(cube_s, RESULT)
    colour(spot_s, RESULT)
    n_cube, n_spot = len(cube.data.polygons), len(spot.data.polygons)
    texts = ["cage: %d quads,\n4 top edges creased (red)" % n_cube,
             "Catmull-Clark level 3:\n%s quads" % group(len(cube_s.data.polygons)),
             "Spot cage: %d faces" % n_spot,
             "Catmull-Clark level 3:\n%s quads" % group(len(spot_s.data.polygons))]
    texts_objs = labels_under(placed, texts, 0.17, FRONT)
    render(out / "subdivided_cage.png", [cube_s, spot_s, cube_wire, cube_crease, spot_wire] + texts_objs,
           FRONT)
    return n_cube, len(cube_s.data.polygons), n_spot, len(spot_s.data.polygons)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(REPO / "docs" / "screenshots"))
    args = ap.parse_args()
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)

    import locate
    from addon_env import install_addon, uninstall_addon
    from daemon_util import DaemonProcess, short_tmpdir

    data = locate.shared_data() / "mesh"
    dist = Path(tempfile.mkdtemp(prefix="tessd-dist-"))
    try:
        subprocess.run([sys.executable, str(REPO / "blender_addon" / "build.py"), "--out", str(dist),
                        "--no-validate"], check=True, stdout=subprocess.DEVNULL)
        with short_tmpdir() as d:
            proc = DaemonProcess(str(locate.tessd_bin()), os.path.join(d, "t.sock")).start()
            try:
                install_addon(next(dist.glob("tessd-*.zip")), dist / "repo", proc.socket)
                print("lod chain:", lod_chain(data, out))
                print("partition (cells, input tris, result tris):", partition(data, out))
                print("subdivided (cube cage, cube result, spot cage, spot result faces):",
                      subdivided_cage(data, out))
                uninstall_addon()
            finally:
                proc.stop()
    finally:
        shutil.rmtree(dist, ignore_errors=True)
        shutil.rmtree(_USER, ignore_errors=True)


if __name__ == "__main__":
    main()
