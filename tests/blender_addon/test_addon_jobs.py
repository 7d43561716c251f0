"""Long jobs: cancel mid-way through the tick function, a crashing daemon, an animation
subdivided frame by frame into a USD point cache."""

from __future__ import annotations

import os
import signal
import sys

import numpy as np
import pytest

import scenes
from addon_env import ADDON
from scenes import scene_state, select


@pytest.fixture
def bpy(addon):
    import bpy as _bpy

    scenes.empty_scene()
    return _bpy


@pytest.fixture
def hooks(addon):
    """The add-on's TICK_HOOKS list, emptied afterwards."""
    jobs = sys.modules[ADDON + ".jobs"]
    try:
        yield jobs.TICK_HOOKS
    finally:
        jobs.TICK_HOOKS.clear()


def test_cancel_midway_leaves_the_scene_unchanged(bpy, hooks):
    src = scenes.suzanne()
    select(src)
    before = scene_state()
    seen = []

    def cancel_at_first_tick(job):
        seen.append((job.state, job.ticks))
        if job.ticks == 1:
            assert job.state == "RUNNING"  # the daemon is still working on the request
            job.cancel()

    hooks.append(cancel_at_first_tick)
    # level 6: 2 M faces, far longer than one tick
    assert bpy.ops.tessd.subdivide(levels=6) == {'CANCELLED'}
    assert scene_state() == before
    assert seen[-1][0] == "CANCELLED"
    # the daemon itself stopped the request (its reply was `cancelled`)
    states = [s for s, _ in seen]
    assert states[0] == "RUNNING" and states[-1] == "CANCELLED"


def test_cancel_reports_the_daemon_stopped(bpy, hooks):
    src = scenes.suzanne()
    select(src)
    jobs = []
    hooks.append(lambda job: (jobs.append(job), job.cancel()) if job.ticks == 1 else None)
    assert bpy.ops.tessd.subdivide(levels=6) == {'CANCELLED'}
    assert jobs and jobs[0].cancelled_by_daemon


def test_daemon_crash_is_a_clean_error(bpy, hooks):
    """A daemon killed mid-request: the operator reports it and changes nothing."""
    from daemon_util import DaemonProcess, short_tmpdir

    import locate

    prefs = bpy.context.preferences.addons[ADDON].preferences
    old = prefs.socket
    with short_tmpdir() as d:
        proc = DaemonProcess(str(locate.tessd_bin()), os.path.join(d, "crash.sock")).start()
        try:
            prefs.socket = proc.socket
            src = scenes.suzanne()
            select(src)
            before = scene_state()
            hooks.append(lambda job: os.kill(proc.pid, signal.SIGKILL) if job.ticks == 1 else None)
            with pytest.raises(RuntimeError, match="lost the tessd daemon.*scene is unchanged"):
                bpy.ops.tessd.subdivide(levels=6)
            assert scene_state() == before
        finally:
            prefs.socket = old
            proc.kill()


def test_animation_to_usd_point_cache(bpy, tmp_path):
    from pxr import Usd, UsdGeom

    b = bpy
    b.ops.mesh.primitive_cube_add()
    cage = b.context.object
    cage.name = "Jelly"
    basis = cage.shape_key_add(name="Basis")
    key = cage.shape_key_add(name="Squash")
    co = np.empty(len(cage.data.vertices) * 3, np.float32)
    basis.data.foreach_get("co", co)
    co = co.reshape(-1, 3)
    co[:, 2] *= 0.5
    key.data.foreach_set("co", co.reshape(-1))
    for frame, value in ((2, 0.0), (5, 1.0)):
        key.value = value
        key.keyframe_insert("value", frame=frame)
    select(cage)
    cache = tmp_path / "jelly.usda"
    assert b.ops.tessd.subdivide(levels=2, use_animation=True, frame_start=2, frame_end=5,
                                 cache_path=str(cache)) == {'FINISHED'}
    assert b.context.scene.frame_current == 1  # restored
    out = b.data.objects["Jelly_subdiv"]
    mod = out.modifiers["tessd animation"]
    assert mod.type == 'MESH_SEQUENCE_CACHE' and mod.object_path == "/Root/Jelly"
    stage = Usd.Stage.Open(str(cache))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/Jelly"))
    times = mesh.GetPointsAttr().GetTimeSamples()
    assert times == [1.0, 2.0, 3.0, 4.0]
    assert len(mesh.GetPointsAttr().Get(1.0)) == len(out.data.vertices) == 98
    # frame 5 of the scene shows time code 4 (the squashed pose), frame 2 the rest pose
    top = {}
    for frame, code in ((2, 1.0), (5, 4.0)):
        b.context.scene.frame_set(frame)
        ev_obj = out.evaluated_get(b.context.evaluated_depsgraph_get())
        ev = ev_obj.to_mesh()
        got = np.empty(len(ev.vertices) * 3, np.float32)
        ev.vertices.foreach_get("co", got)
        ev_obj.to_mesh_clear()
        want = np.array(mesh.GetPointsAttr().Get(code), dtype=np.float32).reshape(-1)
        assert np.allclose(got, want, atol=1e-5), frame
        top[frame] = got.reshape(-1, 3)[:, 2].max()
    assert top[5] == pytest.approx(0.5 * top[2], rel=1e-4)
