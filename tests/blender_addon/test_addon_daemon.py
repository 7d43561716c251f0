"""Reaching the daemon: a stopped daemon or a missing binary is a clean error that leaves
the scene unchanged; with "start automatically" the add-on starts the daemon it finds
through $TESSD_BIN (or PATH) and stops it again when it is disabled."""

from __future__ import annotations

import os

import pytest

import locate
import scenes
from addon_env import ADDON, install_addon, uninstall_addon
from daemon_util import short_tmpdir
from scenes import scene_state, select


@pytest.fixture
def sock():
    with short_tmpdir() as d:
        yield os.path.join(d, "t.sock")


@pytest.fixture
def bare(addon_zip, tmp_path, sock):
    """The add-on on a socket where nothing listens yet."""
    install_addon(addon_zip[0], tmp_path / "repo", sock)
    import bpy

    try:
        yield bpy, bpy.context.preferences.addons[ADDON].preferences
    finally:
        uninstall_addon()


def _attempt(bpy, match):
    src = scenes.suzanne()
    select(src)
    before = scene_state()
    with pytest.raises(RuntimeError, match=match):
        bpy.ops.tessd.simplify(method='GRID', cells=8)
    assert scene_state() == before


def test_daemon_not_running(bare):
    bpy, prefs = bare
    prefs.auto_start = False
    _attempt(bpy, r"no tessd daemon answers on .*t\.sock.*Start the daemon automatically")


def test_binary_in_preferences_missing(bare):
    bpy, prefs = bare
    prefs.auto_start = True
    prefs.binary_path = "/nonexistent/tessd"
    _attempt(bpy, r"/nonexistent/tessd, is not an executable file.*scene is unchanged")


def test_binary_nowhere(bare, monkeypatch):
    bpy, prefs = bare
    prefs.auto_start = True
    monkeypatch.delenv("TESSD_BIN", raising=False)
    monkeypatch.setenv("PATH", "/nonexistent")
    _attempt(bpy, r"cannot find the tessd executable")


def test_auto_start_through_tessd_bin_and_stop_on_disable(bare, monkeypatch, sock):
    bpy, prefs = bare
    import tessd

    prefs.auto_start = True
    prefs.stop_on_exit = True
    monkeypatch.setenv("TESSD_BIN", str(locate.tessd_bin()))
    assert not tessd.daemon.ping(sock)
    src = scenes.suzanne()
    select(src)
    assert bpy.ops.tessd.simplify(method='GRID', cells=8) == {'FINISHED'}
    assert "Suzanne_simplified" in bpy.data.objects
    assert tessd.daemon.ping(sock)  # started, and still serving for the next action
    assert bpy.ops.tessd.generate_lods(levels="50%") == {'FINISHED'}
    uninstall_addon()  # disabling the add-on stops the daemon it started
    assert not tessd.daemon.ping(sock)
