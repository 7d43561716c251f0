"""`session.hold` / `session.release`: which programs share the daemon, counted by live
process, and `shutdown` with `if_unheld` (docs/protocol.md, "Sharing one daemon"). Real
daemon, real processes standing for the holding programs."""

from __future__ import annotations

import os
import subprocess

import pytest

import tessd
from daemon_util import DaemonProcess


@pytest.fixture
def client(daemon):
    with tessd.Client(daemon.socket, timeout=10.0) as c:
        yield c
        # Leave the module's daemon unheld for the next test.
        for h in c.hello()["held_by"]:
            c.release(h["pid"])


@pytest.fixture
def program():
    """A live process standing for a host program (FreeCAD, Blender, a script)."""
    procs = []

    def start():
        p = subprocess.Popen(["sleep", "120"])
        procs.append(p)
        return p

    yield start
    for p in procs:
        p.kill()
        p.wait()


def test_hello_reports_holders_and_the_ops(client):
    hello = client.hello()
    assert hello["holders"] == 0 and hello["held_by"] == []
    assert {"session.hold", "session.release", "hello", "shutdown"} <= set(hello["ops"])


def test_hold_and_release_count_live_processes(client, program):
    a, b = program(), program()
    assert client.call("session.hold", {"pid": a.pid, "host": "freecad"})[0] == {"holders": 1}
    assert client.hold("blender", pid=b.pid) == 2
    # Holding again is the same hold (a host reconnecting need not remember); host updated.
    assert client.hold("freecad-1.0", pid=a.pid) == 2
    assert client.hello()["held_by"] == sorted(
        [{"pid": a.pid, "host": "freecad-1.0"}, {"pid": b.pid, "host": "blender"}],
        key=lambda h: h["pid"])
    assert client.release(a.pid) == 1
    assert client.release(a.pid) == 1  # releasing twice is not an error
    assert client.release(b.pid) == 0


def test_holds_are_per_process_not_per_connection(daemon, client, program):
    p = program()
    with tessd.Client(daemon.socket, timeout=10.0) as other:
        assert other.hold("script", pid=p.pid) == 1
    # The connection is closed; the process lives on, so it still holds.
    assert client.hello()["holders"] == 1
    # This process, by default.
    assert client.hold("pytest") == 2
    assert {"pid": os.getpid(), "host": "pytest"} in client.hello()["held_by"]


def test_dead_holders_are_pruned(client, program):
    live, dead = program(), program()
    assert client.hold("a", pid=live.pid) == 1
    assert client.hold("b", pid=dead.pid) == 2
    dead.kill()
    dead.wait()  # reaped: the pid no longer exists
    assert client.hello()["holders"] == 1
    assert client.hello()["held_by"] == [{"pid": live.pid, "host": "a"}]


def test_a_zombie_holder_is_pruned(client):
    """A holder that exited but whose parent has not reaped it (a zombie) uses nothing."""
    z = subprocess.Popen(["true"])
    try:
        assert client.hold("zombie", pid=z.pid) in (0, 1)
        import time

        deadline = time.monotonic() + 10
        while client.hello()["holders"] and time.monotonic() < deadline:
            time.sleep(0.02)
        assert client.hello()["holders"] == 0
    finally:
        z.wait()


@pytest.mark.parametrize("op", ["session.hold", "session.release"])
@pytest.mark.parametrize("params,words", [
    ({}, "needs `params.pid`"),
    ({"pid": -3}, "`pid` must be a positive integer (a process id), got -3"),
    ({"pid": 0}, "`pid` must be a positive integer (a process id), got 0"),
    ({"pid": 1.5}, "`pid` must be a positive integer (a process id), got 1.5"),
    ({"pid": "123"}, "`pid` must be a positive integer (a process id), got a string"),
    ({"pid": 2 ** 31}, "`pid` must be a positive integer (a process id), got 2147483648"),
    ({"pid": None}, "`pid` must be a positive integer (a process id), got null"),
])
def test_bad_pid_is_invalid_request_naming_it(client, op, params, words):
    with pytest.raises(tessd.TessdError) as info:
        client.call(op, dict(params, host="x") if op == "session.hold" else params)
    assert info.value.code == "invalid_request"
    assert words in info.value.message, info.value.message
    assert op in info.value.message or "`pid`" in info.value.message
    assert client.ping("still here") == "still here"  # the connection stays usable


def test_bad_host_is_invalid_request(client):
    with pytest.raises(tessd.TessdError) as info:
        client.call("session.hold", {"pid": os.getpid(), "host": 7})
    assert info.value.code == "invalid_request" and "`host` must be a string" in info.value.message
    assert client.call("session.hold", {"pid": os.getpid()})[0] == {"holders": 1}  # host optional


def test_shutdown_if_unheld(tessd_bin, tmpdir_short, program):
    sock = os.path.join(tmpdir_short, "h.sock")
    proc = DaemonProcess(tessd_bin, sock).start()
    try:
        p = program()
        with tessd.Client(sock, timeout=10.0) as c:
            c.hold("freecad", pid=p.pid)
            with pytest.raises(tessd.TessdError) as info:
                c.call("shutdown", {"if_unheld": "yes"})
            assert info.value.code == "invalid_request" and "if_unheld" in info.value.message
        # Held: the daemon refuses to stop and says why.
        assert tessd.stop_daemon(sock, only_if_unheld=True) is False
        with tessd.Client(sock, timeout=10.0) as c:
            assert c.call("shutdown", {"if_unheld": True})[0] == {
                "ok": False, "stopping": False, "holders": 1}
        assert proc.alive()
        # Once the holder is gone (exited without releasing), it stops.
        p.kill()
        p.wait()
        assert tessd.stop_daemon(sock, only_if_unheld=True) is True
        assert proc.proc.wait(10) == 0
    finally:
        proc.stop()


def test_plain_shutdown_stops_a_held_daemon(tessd_bin, tmpdir_short):
    sock = os.path.join(tmpdir_short, "h.sock")
    proc = DaemonProcess(tessd_bin, sock).start()
    try:
        with tessd.Client(sock, timeout=10.0) as c:
            c.hold("pytest")
        assert tessd.stop_daemon(sock) is True
        assert proc.proc.wait(10) == 0
    finally:
        proc.stop()


def test_binary_version_matches_hello(client, tessd_bin):
    assert tessd.daemon.binary_version(tessd_bin) == client.hello()["version"]
