"""Reaching the daemon from the installed extension: a stopped daemon or a missing binary is a
clean, artist-worded error that leaves the scene unchanged; "start automatically" starts the
daemon bundled in the zip (bin/tessd, made executable after Blender's installer dropped the
bit), else $TESSD_BIN; the add-on holds the daemons it uses and, on exit, stops only one it
started that no other program holds; `hello`'s version check replaces a daemon of another
version unless another program holds it. Real bpy, real daemons, real sockets."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

import locate
import scenes
from addon_env import ADDON, REPO, install_addon, uninstall_addon
from daemon_util import DaemonProcess, short_tmpdir
from scenes import scene_state, select

import tessd


@pytest.fixture
def sock():
    with short_tmpdir() as d:
        yield os.path.join(d, "t.sock")


@pytest.fixture
def bare(addon_zip, tmp_path, sock):
    """The add-on on a socket where nothing listens yet."""
    mod = install_addon(addon_zip[0], tmp_path / "repo", sock)
    import bpy

    try:
        yield bpy, bpy.context.preferences.addons[ADDON].preferences, mod
    finally:
        uninstall_addon()


@pytest.fixture
def other_program():
    """A live process standing for another program that uses the daemon (FreeCAD, a script)."""
    proc = subprocess.Popen(["sleep", "120"])
    try:
        yield proc
    finally:
        proc.kill()
        proc.wait()


@pytest.fixture
def own_daemon(sock):
    """A daemon started by the test, i.e. by someone else than the add-on."""
    proc = DaemonProcess(str(locate.tessd_bin()), sock).start()
    try:
        yield proc
    finally:
        proc.stop()


def _attempt(bpy, match):
    src = scenes.suzanne()
    select(src)
    before = scene_state()
    with pytest.raises(RuntimeError, match=match) as info:
        bpy.ops.tessd.simplify(method='GRID', cells=8)
    assert scene_state() == before
    return str(info.value)


def _simplify_suzanne(bpy):
    select(scenes.suzanne())
    assert bpy.ops.tessd.simplify(method='GRID', cells=8) == {'FINISHED'}
    assert "Suzanne_simplified" in bpy.data.objects


def _hello(sock):
    with tessd.Client(sock, timeout=5.0) as c:
        return c.hello()


def _exe(pid):
    return os.path.realpath("/proc/%d/exe" % pid)


def _gone(pid, timeout=10.0):
    """Whether process `pid` exits within `timeout` (a daemon the add-on started is not our
    child, so we poll /proc rather than wait)."""
    import time

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with open("/proc/%d/stat" % pid) as f:
                if f.read().rsplit(")", 1)[1].split()[0] == "Z":
                    return True
        except OSError:
            return True
        time.sleep(0.02)
    return False


def test_daemon_not_running(bare):
    bpy, prefs, _ = bare
    prefs.auto_start = False
    _attempt(bpy, r"no tessd daemon answers on .*t\.sock.*Start the daemon automatically")


def test_binary_in_preferences_missing(bare):
    bpy, prefs, _ = bare
    prefs.auto_start = True
    prefs.binary_path = "/nonexistent/tessd"
    _attempt(bpy, r"tessd program chosen in Preferences › Add-ons › tessd, /nonexistent/tessd, "
                  r"is not a program file.*scene is unchanged")


def test_binary_nowhere_is_worded_for_the_artist(bare, monkeypatch):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    os.remove(mod.daemon.BUNDLED_BINARY)  # an extension built without the daemon
    monkeypatch.delenv("TESSD_BIN", raising=False)
    monkeypatch.setenv("PATH", "/nonexistent")
    plat = mod.daemon.this_platform()
    message = _attempt(bpy, r"tessd could not start: the tessd program is not in this add-on\. "
                            r"Reinstall the tessd extension built for %s, or choose the tessd "
                            r"program in Preferences › Add-ons › tessd; the scene is "
                            r"unchanged" % plat)
    assert message.startswith("Error: tessd could not start")  # Blender's report prefix
    for api_word in ("binary=", "TESSD_BIN", "PATH", "Python", "Traceback", "Exception"):
        assert api_word not in message, message
    # The failure offers the preferences: the error says so, and the button's operator exists.
    with pytest.raises(mod.daemon.DaemonError) as info:
        mod.daemon.connect()
    assert info.value.offer_preferences
    assert hasattr(bpy.ops.tessd, "open_preferences")
    assert bpy.ops.tessd.open_preferences.get_rna_type().name == "Open tessd Preferences"
    with pytest.raises(RuntimeError, match="Preferences need a Blender window"):
        bpy.ops.tessd.open_preferences()  # background Blender: no window to open them in
    # Without a window (scripts, background mode) there is no popup: the report is all.
    assert mod.daemon.offer_preferences(bpy.context, str(info.value)) is False


def test_auto_start_bundled_binary_and_stop_on_disable(bare, monkeypatch, sock):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    prefs.stop_on_exit = True
    monkeypatch.delenv("TESSD_BIN", raising=False)
    bundled = mod.daemon.BUNDLED_BINARY
    assert not os.access(bundled, os.X_OK)  # Blender's installer dropped the bit
    assert not tessd.daemon.ping(sock)
    _simplify_suzanne(bpy)
    assert os.access(bundled, os.X_OK)  # made executable by the add-on
    hello = _hello(sock)
    assert _exe(hello["pid"]) == os.path.realpath(bundled)
    assert hello["held_by"] == [{"pid": os.getpid(), "host": "blender"}]
    assert bpy.ops.tessd.generate_lods(levels="50%") == {'FINISHED'}
    assert _hello(sock)["pid"] == hello["pid"]  # still serving, held once
    uninstall_addon()  # disabling the add-on releases and stops the daemon it started
    assert not tessd.daemon.ping(sock)
    assert _gone(hello["pid"])


def test_tessd_bin_when_nothing_is_bundled(bare, monkeypatch, sock):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    os.remove(mod.daemon.BUNDLED_BINARY)
    monkeypatch.setenv("TESSD_BIN", str(locate.tessd_bin()))
    _simplify_suzanne(bpy)
    assert _exe(_hello(sock)["pid"]) == os.path.realpath(locate.tessd_bin())
    uninstall_addon()
    assert not tessd.daemon.ping(sock)


def test_held_by_another_program_survives_exit(bare, sock, other_program):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    prefs.stop_on_exit = True
    _simplify_suzanne(bpy)
    with tessd.Client(sock, timeout=5.0) as c:
        assert c.hold("freecad", pid=other_program.pid) == 2  # Blender and "FreeCAD"
    pid = _hello(sock)["pid"]
    mod.daemon.stop_started()  # Blender exits
    hello = _hello(sock)
    assert hello["pid"] == pid  # left running for the other program
    assert hello["held_by"] == [{"pid": other_program.pid, "host": "freecad"}]
    # The other program is gone without releasing: its hold is pruned, and the daemon is
    # nobody's now; the add-on no longer counts it as its own (it stopped managing it).
    other_program.kill()
    other_program.wait()
    assert _hello(sock)["holders"] == 0
    assert tessd.stop_daemon(sock, only_if_unheld=True)
    assert _gone(pid)


def test_unheld_daemon_the_addon_started_is_stopped_and_dead_holders_do_not_count(
        bare, sock, other_program):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    prefs.stop_on_exit = True
    _simplify_suzanne(bpy)
    with tessd.Client(sock, timeout=5.0) as c:
        assert c.hold("script", pid=other_program.pid) == 2
    other_program.kill()
    other_program.wait()  # reaped: the pid no longer exists
    pid = _hello(sock)["pid"]
    mod.daemon.stop_started()
    assert not tessd.daemon.ping(sock)
    assert _gone(pid)


def test_stop_on_exit_off_leaves_it_running(bare, sock):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    prefs.stop_on_exit = False
    _simplify_suzanne(bpy)
    pid = _hello(sock)["pid"]
    mod.daemon.stop_started()
    hello = _hello(sock)
    assert hello["pid"] == pid and hello["holders"] == 0  # released, not stopped
    assert tessd.stop_daemon(sock)


def test_daemon_started_by_someone_else_is_never_stopped(bare, own_daemon, sock):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    prefs.stop_on_exit = True
    _simplify_suzanne(bpy)
    assert _hello(sock)["holders"] == 1
    uninstall_addon()
    assert own_daemon.alive()
    assert _hello(sock)["holders"] == 0  # released on disable


def test_other_version_unheld_is_replaced(bare, own_daemon, sock, monkeypatch):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    monkeypatch.setattr(mod.daemon, "EXPECTED_VERSION", "9.9.9")
    warned = len(mod.daemon.warned)
    _simplify_suzanne(bpy)
    own_daemon.proc.wait(10)  # the old daemon was shut down ...
    hello = _hello(sock)  # ... and the add-on's bundled one serves now
    assert hello["pid"] != own_daemon.pid
    assert _exe(hello["pid"]) == os.path.realpath(mod.daemon.BUNDLED_BINARY)
    assert mod.daemon.warned[warned:] == []
    uninstall_addon()  # the add-on started the replacement, so it stops it
    assert not tessd.daemon.ping(sock)


def test_other_version_held_is_left_running_with_a_warning(bare, own_daemon, sock, monkeypatch,
                                                           other_program):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    monkeypatch.setattr(mod.daemon, "EXPECTED_VERSION", "9.9.9")
    with tessd.Client(sock, timeout=5.0) as c:
        c.hold("freecad", pid=other_program.pid)
    warned = len(mod.daemon.warned)
    _simplify_suzanne(bpy)
    client = mod.daemon.connect()  # what the operators connect through: no new warning
    client.close()
    assert client.tessd_warnings == []
    assert _hello(sock)["pid"] == own_daemon.pid
    assert mod.daemon.warned[warned:] == [
        "the running tessd daemon is version 0.1.0; this add-on expects 9.9.9; it is shared "
        "with another program, so it was left running"]  # once, not per action
    uninstall_addon()
    assert own_daemon.alive()


def test_daemon_lacking_an_op_is_replaced_like_another_version(bare, own_daemon, sock,
                                                                monkeypatch):
    bpy, prefs, mod = bare
    prefs.auto_start = True
    monkeypatch.setattr(mod.daemon, "REQUIRED_OPS", mod.daemon.REQUIRED_OPS | {"mesh.future"})
    _simplify_suzanne(bpy)
    own_daemon.proc.wait(10)
    assert _hello(sock)["pid"] != own_daemon.pid


INSTALLED_RUN = textwrap.dedent("""
    import json, os, sys
    sys.path[:0] = [sys.argv[1]]
    from addon_env import install_addon
    import bpy
    mod = install_addon(sys.argv[2], sys.argv[3], sys.argv[4], auto_start=True)
    tessd = mod.client.tessd
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16)
    src = bpy.context.object
    src.name = "Sphere"
    result = bpy.ops.tessd.simplify(method='GRID', cells=6)
    out = bpy.data.objects.get("Sphere_simplified")
    with tessd.Client(sys.argv[4], timeout=5.0) as c:
        hello = c.hello()
    report = {"result": sorted(result), "made": out is not None,
              "before": len(src.data.vertices), "after": len(out.data.vertices) if out else None,
              "pid": hello["pid"], "exe": os.path.realpath("/proc/%d/exe" % hello["pid"]),
              "bundled": os.path.realpath(mod.daemon.BUNDLED_BINARY), "path": os.environ["PATH"],
              "tessd_bin": os.environ.get("TESSD_BIN")}
    print("REPORT " + json.dumps(report))
    # Exit as Blender does, add-on enabled: its atexit hook stops the daemon it started.
""")


def test_zip_in_a_fresh_profile_without_path(addon_zip, tmp_path, sock):
    """The artist's case: Blender from a desktop launcher (no PATH, no TESSD_BIN), a fresh
    profile, the zip installed, auto-start on: Simplify works with the bundled daemon, which
    is stopped again when the process exits. Run in a child process so this process's env stays as it is."""
    env = {k: v for k, v in os.environ.items() if k not in ("TESSD_BIN", "PATH")}
    env.update(PATH="", BLENDER_USER_RESOURCES=str(tmp_path / "profile"),
               PYTHONPATH="")  # nothing of python/ either: the zip's vendored client is used
    proc = subprocess.run([sys.executable, "-c", INSTALLED_RUN, str(REPO / "tests" / "blender_addon"),
                           str(addon_zip[0]), str(tmp_path / "repo"), sock],
                          env=env, cwd=str(tmp_path), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=300)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("REPORT ")]
    assert proc.returncode == 0 and lines, proc.stdout
    report = json.loads(lines[-1][len("REPORT "):])
    assert report["path"] == "" and report["tessd_bin"] is None
    assert report["result"] == ["FINISHED"] and report["made"], report
    assert report["after"] < report["before"], report
    assert report["exe"] == report["bundled"], report  # the daemon is the bundled one
    assert report["bundled"].startswith(str(tmp_path / "repo")), report
    assert _gone(report["pid"])
    assert not tessd.daemon.ping(sock)
