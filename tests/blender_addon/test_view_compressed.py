"""View compressed mesh live (`bpy.ops.tessd.view_compressed`, issue 35) in real headless
Blender against the real daemon: a camera keyframed to approach one end of a moved, rotated
and scaled bunny refines the object frame by frame (`scene.frame_set`), through one view
session; removing the object stops the handlers; bad files are refused naming them."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

import locate
import scenes
from scenes import cli, counts, scene_state

FRAMES = 6
#: Camera distances (world units) to the approached end at frames 1..FRAMES; the bunny is
#: about 1.5 units tall once scaled.
DISTANCES = [30.0, 8.0, 3.0, 1.5, 0.8, 0.5]
#: Radius (world units) around the approached end within which triangles are counted.
RADIUS = 0.3
SIZE = (640, 480)
FOV = 40.0


@pytest.fixture
def bpy(addon):
    import bpy as _bpy

    scenes.empty_scene()
    yield _bpy
    addon.ops_view_compressed.stop_all()  # no live object left for the next test


@pytest.fixture
def bunny_tsc(tmp_path):
    """The dense bunny scan in many nSP-cells, a new file per test (the daemon keeps view
    sessions by path, so each test starts from a fresh session)."""
    tsc = tmp_path / "bunny.tsc"
    info = cli("compress", str(locate.shared_data() / "mesh" / "bun_zipper.ply"), str(tsc),
               "--bits", "12", "--min-cell", "3000")
    assert info["nsp_cells"] >= 20 and info["triangles"] > 60000
    return tsc


def ours(bpy):
    """Our handlers still registered."""
    lists = (bpy.app.handlers.frame_change_post, bpy.app.handlers.depsgraph_update_post)
    return [h for lst in lists for h in lst
            if getattr(h, "__module__", "").endswith(".ops_view_compressed")]


def camera(bpy):
    """A perspective camera, vertical field of view FOV at SIZE, the scene's camera."""
    data = bpy.data.cameras.new("Cam")
    data.sensor_fit = 'VERTICAL'
    data.angle = math.radians(FOV)
    cam = bpy.data.objects.new("Cam", data)
    bpy.context.scene.collection.objects.link(cam)
    scene = bpy.context.scene
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    return cam


def world_positions(obj):
    me = obj.data
    co = np.empty(len(me.vertices) * 3, np.float64)
    me.vertices.foreach_get("co", co)
    m = np.array(obj.matrix_world, dtype=np.float64)
    co = co.reshape(-1, 3)
    return co @ m[:3, :3].T + m[:3, 3]


def triangles_near(obj, point, radius):
    """Triangles of the object whose centroid (world space) lies within `radius` of `point`."""
    me = obj.data
    sizes = np.empty(len(me.polygons), np.int32)
    me.polygons.foreach_get("loop_total", sizes)
    assert (sizes == 3).all()
    tri = np.empty(len(me.loops), np.int64)
    me.loops.foreach_get("vertex_index", tri)
    centroids = world_positions(obj)[tri.reshape(-1, 3)].mean(axis=1)
    return int((np.linalg.norm(centroids - np.asarray(point), axis=1) <= radius).sum())


def test_live_view_refines_near_an_approaching_camera(bpy, addon, bunny_tsc, capfd):
    from mathutils import Euler, Matrix, Vector

    live = addon.ops_view_compressed
    scene = bpy.context.scene
    cam = camera(bpy)
    cam.location = (0.0, -40.0, 0.0)  # looking along +Y at the bunny from afar
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc), pixel_error=1.0) == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    assert obj["tessd_tsc"] == str(bunny_tsc) and obj["tessd_pixel_error"] == 1.0
    assert len(ours(bpy)) == 2
    state = live.live_state(obj)
    assert state is not None and state.requests == 0

    # The file's frame is not the world's: moved, stood up (the scan is Y-up) and scaled.
    # A camera left in world coordinates would see a far-away bunny and never refine it.
    stand_up = Euler((math.pi / 2, 0.0, 0.0)).to_matrix().to_4x4()
    obj.matrix_world = Matrix.Translation((3.0, -2.0, 1.0)) @ stand_up @ Matrix.Scale(10.0, 4)
    # The approached end: the scan's -x end (in the file's frame), from the first view.
    co = np.array([v.co for v in obj.data.vertices])
    lo, hi = co.min(axis=0), co.max(axis=0)
    end_file = co[co[:, 0] < lo[0] + 0.2 * (hi[0] - lo[0])].mean(axis=0)
    m = obj.matrix_world
    end = m @ Vector(end_file)
    away = (m.to_3x3() @ Vector((-1.0, 0.0, 0.4))).normalized()  # from outside that end
    rot = (-away).to_track_quat('-Z', 'Y').to_euler()
    for f, d in enumerate(DISTANCES, start=1):
        cam.location = end + away * d
        cam.rotation_euler = rot
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_euler", frame=f)

    near, results = [], []
    for f in range(1, FRAMES + 1):
        scene.frame_set(f)  # refines synchronously (background mode)
        near.append(triangles_near(obj, end, RADIUS))
        results.append(dict(state.result))
    report = ["triangles within %.1f of the approached end, frames 1..%d: %s"
              % (RADIUS, FRAMES, near),
              "triangles in all: %s" % [r["triangles"] for r in results],
              "new bytes read per view: %s" % [r["bytes_read"] for r in results]]
    assert state.requests == FRAMES  # one per frame: the camera moved every time
    assert state.problem is None
    assert counts(obj)[1] == results[-1]["triangles"]
    assert near[0] > 0
    assert near[-1] > 8 * near[0]
    # Growing as the camera comes (up to the file's full precision: a few triangles more or
    # less where a cell's border moves).
    assert all(b >= 0.98 * a for a, b in zip(near, near[1:])), near

    # The camera in the file's frame, computed here, gives the same mesh through the CLI.
    inv = obj.matrix_world.inverted()
    eye = inv @ cam.matrix_world.translation
    target = inv @ (cam.matrix_world.translation - cam.matrix_world.col[2].xyz)
    up = (inv.to_3x3() @ cam.matrix_world.col[1].xyz).normalized()
    fresh = cli("view-decode", str(bunny_tsc), str(bunny_tsc.with_suffix(".ply")),
                "--eye", "%r,%r,%r" % tuple(eye), "--target", "%r,%r,%r" % tuple(target),
                "--up", "%r,%r,%r" % tuple(up), "--fov", str(FOV), "--size", "%dx%d" % SIZE,
                "--pixel-error", "1")
    report.append("last view: live %d triangles, %d new bytes; fresh decode %d triangles, %d bytes"
                  % (results[-1]["triangles"], results[-1]["bytes_read"], fresh["triangles"],
                     fresh["bytes_read"]))
    assert (results[-1]["cells"], results[-1]["triangles"]) == (fresh["cells"], fresh["triangles"])
    # The session refined from the previous view: it read less than a fresh decode does.
    assert results[-1]["bytes_read"] < fresh["bytes_read"]

    # Debounced: a frame whose camera did not move sends nothing and keeps the mesh.
    before = counts(obj)
    scene.frame_set(FRAMES + 1)
    bpy.context.view_layer.update()
    assert state.requests == FRAMES and counts(obj) == before

    # The same object, mesh and name all along.
    assert obj.name == "bunny" and obj.data.name == "bunny"
    assert [m.name for m in bpy.data.meshes] == ["bunny"]

    # Removing the object stops the handlers, quietly.
    bpy.data.objects.remove(obj)
    scene.frame_set(2)
    assert ours(bpy) == []
    assert not live._LIVE
    err = capfd.readouterr().err
    assert "Traceback" not in err, err
    print("\n".join(report))  # after readouterr: shown with -s or -rP


def test_live_view_follows_the_object_and_a_rename(bpy, addon, bunny_tsc):
    """Moving the object (not the camera) refines it too, and a renamed object stays live."""
    live = addon.ops_view_compressed
    cam = camera(bpy)
    cam.location = (0.0, 0.0, 30.0)  # looking down -Z at the origin from afar
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    far = counts(obj)[1]
    # What the artist set on the mesh survives the swaps: a material, flat shading.
    mat = bpy.data.materials.new("Clay")
    obj.data.materials.append(mat)
    obj.data.shade_flat()
    mesh = obj.data
    obj.name = "renamed"
    obj.location = (0.0, 0.0, 29.7)  # the bunny brought to the camera
    bpy.context.view_layer.update()  # the depsgraph handler refines (background: at once)
    state = live.live_state(obj)
    assert state.requests == 1 and state.problem is None
    assert counts(obj)[1] > 4 * far
    assert obj.data == mesh and list(mesh.materials) == [mat]
    assert not any(p.use_smooth for p in mesh.polygons)
    # Not live any more once its token is gone: the handlers go at the next update.
    del obj["tessd_live"]
    obj.location.x += 1.0
    bpy.context.view_layer.update()
    assert ours(bpy) == [] and not live._LIVE


def test_live_view_without_camera_is_quiet(bpy, addon, bunny_tsc, capfd):
    """A live object whose scene loses its camera refines nothing and says so once."""
    live = addon.ops_view_compressed
    camera(bpy).location = (0.0, 0.0, 5.0)
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    shown = counts(obj)
    bpy.context.scene.camera = None
    for f in range(2, 6):
        bpy.context.scene.frame_set(f)
    state = live.live_state(obj)
    assert "no active camera" in state.problem and state.requests == 0
    assert counts(obj) == shown
    err = capfd.readouterr()
    assert (err.out + err.err).count("no active camera") == 1
    assert "Traceback" not in err.err


def test_bad_path_names_the_file(bpy, tmp_path):
    camera(bpy).location = (0.0, 0.0, 5.0)
    missing = tmp_path / "nowhere" / "missing.tsc"
    before = scene_state()
    with pytest.raises(RuntimeError, match="no .tsc file at .*missing.tsc"):
        bpy.ops.tessd.view_compressed(filepath=str(missing))
    assert scene_state() == before and ours(bpy) == []


def test_corrupt_file_names_the_file(bpy, tmp_path):
    camera(bpy).location = (0.0, 0.0, 5.0)
    junk = tmp_path / "junk.tsc"
    junk.write_bytes(b"this is not a compressed mesh" * 10)
    before = scene_state()
    with pytest.raises(RuntimeError, match=r"junk\.tsc: codec\.view failed"):
        bpy.ops.tessd.view_compressed(filepath=str(junk))
    assert scene_state() == before and ours(bpy) == []


def run_timer(bpy, fn):
    """Runs a registered timer as Blender's event loop does (headless Blender has none): it is
    taken off, called, and registered again for the interval it returns."""
    assert bpy.app.timers.is_registered(fn)
    bpy.app.timers.unregister(fn)
    interval = fn()
    if interval is not None:
        bpy.app.timers.register(fn, first_interval=interval)
    return interval


def test_ui_path_coalesces_moves_and_never_blocks(bpy, addon, bunny_tsc, monkeypatch):
    """The UI's path, with Blender's event loop played by hand: camera moves only schedule
    the timer; its first run sends one request for the latest view and returns at once; the
    reply swaps the mesh on a later run."""
    live = addon.ops_view_compressed
    monkeypatch.setattr(live, "SYNCHRONOUS", False)
    cam = camera(bpy)
    cam.location = (0.0, 0.0, 30.0)
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    state = live.live_state(obj)
    far = counts(obj)[1]
    for z in (20.0, 10.0, 3.0, 1.0, 0.3):  # a camera being dragged: five depsgraph updates
        cam.location.z = z
        bpy.context.view_layer.update()
    assert state.requests == 0 and counts(obj)[1] == far
    assert bpy.app.timers.is_registered(live._tick)
    interval = run_timer(bpy, live._tick)  # the timer's first run: sends, does not wait
    assert interval == live.TICK_INTERVAL and state.job is not None and state.requests == 1
    assert counts(obj)[1] == far
    deadline = time.monotonic() + 60
    while bpy.app.timers.is_registered(live._tick) and time.monotonic() < deadline:
        time.sleep(interval)
        interval = run_timer(bpy, live._tick)
    assert interval is None and state.job is None and state.problem is None
    assert state.requests == 1  # the five moves coalesced into one request
    assert state.result["triangles"] == counts(obj)[1] > 4 * far
    bpy.context.view_layer.update()  # our own swap: nothing new to send
    assert not bpy.app.timers.is_registered(live._tick)

    bpy.data.objects.remove(obj)
    bpy.context.view_layer.update()
    # Headless the handlers go at once (in the UI a timer removes them a moment later).
    assert not live._LIVE and ours(bpy) == []


def test_new_file_stops_the_live_view(bpy, addon, bunny_tsc):
    live = addon.ops_view_compressed
    camera(bpy).location = (0.0, 0.0, 5.0)
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    assert live._LIVE and len(ours(bpy)) == 2
    bpy.ops.wm.read_homefile(use_empty=True)
    assert not live._LIVE and ours(bpy) == []
    assert not any(h.__module__.endswith(".ops_view_compressed") for h in bpy.app.handlers.load_pre)


def test_saved_live_object_refines_again_when_opened(bpy, addon, bunny_tsc, tmp_path):
    """A live object saved in a .blend goes on refining once the file is opened again (a
    command-line render of it refines each frame)."""
    live = addon.ops_view_compressed
    cam = camera(bpy)
    cam.location = (0.0, 0.0, 30.0)
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    far = counts(bpy.data.objects["bunny"])[1]
    blend = tmp_path / "live.blend"
    assert bpy.ops.wm.save_as_mainfile(filepath=str(blend)) == {'FINISHED'}
    bpy.ops.wm.read_homefile(use_empty=True)
    assert not live._LIVE and ours(bpy) == []
    assert bpy.ops.wm.open_mainfile(filepath=str(blend)) == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    state = live.live_state(obj)
    assert state is not None and len(ours(bpy)) == 2 and counts(obj)[1] == far
    bpy.data.objects["Cam"].location.z = 0.3
    bpy.context.scene.frame_set(2)
    assert state.requests == 1 and state.problem is None
    assert counts(obj)[1] > 4 * far


def test_undo_brings_a_removed_live_object_back_to_life(bpy, addon, bunny_tsc):
    live = addon.ops_view_compressed
    cam = camera(bpy)
    cam.location = (0.0, 0.0, 30.0)
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    far = counts(bpy.data.objects["bunny"])[1]
    bpy.ops.ed.undo_push(message="imported")
    bpy.data.objects.remove(bpy.data.objects["bunny"])
    bpy.context.view_layer.update()
    assert not live._LIVE and ours(bpy) == []
    bpy.ops.ed.undo_push(message="removed")
    assert bpy.ops.ed.undo() == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    state = live.live_state(obj)
    assert state is not None and len(ours(bpy)) == 2
    # The undo's own update sent the (unchanged) view once: an adopted object has sent none.
    assert state.requests == 1 and counts(obj)[1] == far
    bpy.data.objects["Cam"].location.z = 0.3
    bpy.context.view_layer.update()
    assert state.requests == 2 and counts(obj)[1] > 4 * far


def _cli_triangles(tsc, tmp_path, eye, size):
    """Triangles of a fresh CLI decode for a camera at `eye` looking down -Z, +Y up."""
    target = (eye[0], eye[1], eye[2] - 1.0)
    return cli("view-decode", str(tsc), str(tmp_path / "ref.ply"),
               "--eye", "%r,%r,%r" % eye, "--target", "%r,%r,%r" % target, "--up", "0,1,0",
               "--fov", str(FOV), "--size", "%dx%d" % size, "--pixel-error", "1")["triangles"]


def _pixels(bpy, path):
    img = bpy.data.images.load(str(path))
    px = np.empty(img.size[0] * img.size[1] * img.channels, np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px


def test_animation_render_refines_each_frame(bpy, addon, bunny_tsc, tmp_path):
    """A headless animation render (Cycles on the CPU) refines the live object for each
    frame's camera, read from the render's own depsgraph, and renders that mesh."""
    scene = bpy.context.scene
    size = (160, 120)
    cam = camera(bpy)
    scene.render.resolution_x, scene.render.resolution_y = size
    eyes = [(0.0, 0.1, 3.0), (0.0, 0.1, 0.35)]
    cam.location = eyes[0]
    assert bpy.ops.tessd.view_compressed(filepath=str(bunny_tsc)) == {'FINISHED'}
    obj = bpy.data.objects["bunny"]
    for f, eye in enumerate(eyes, start=1):
        cam.location = eye
        cam.keyframe_insert("location", frame=f)
    scene.render.engine = 'CYCLES'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = 1
    scene.frame_start, scene.frame_end = 1, len(eyes)
    scene.render.image_settings.file_format = 'PNG'
    scene.render.filepath = str(tmp_path / "frame_")
    rendered = []

    def record(scene, *_):
        rendered.append(len(bpy.data.objects["bunny"].data.polygons))

    bpy.app.handlers.render_post.append(record)
    try:
        assert bpy.ops.render.render(animation=True) == {'FINISHED'}
    finally:
        bpy.app.handlers.render_post.remove(record)
    expected = [_cli_triangles(bunny_tsc, tmp_path, eye, size) for eye in eyes]
    assert rendered == expected and expected[1] > 4 * expected[0] > 0
    # The picture of frame 2 is that of its refined mesh: the same as a still render after
    # frame_set(2), which refines through the path the first test checks.
    scene.frame_set(2)
    assert counts(obj)[1] == expected[1]
    scene.render.filepath = str(tmp_path / "still.png")
    assert bpy.ops.render.render(write_still=True) == {'FINISHED'}
    animated = _pixels(bpy, tmp_path / "frame_0002.png")
    still = _pixels(bpy, tmp_path / "still.png")
    assert np.abs(animated - still).max() < 1e-6
