"""Progress, cancellation, connection loss, and the daemon's lifecycle (ensure_daemon, a second
daemon on a live socket, stale sockets, socket permissions)."""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import threading
import time
from pathlib import Path

import pytest

import tessd
from daemon_util import DaemonProcess, wait_until
from tessd import TessdError
from tessd.daemon import DaemonStartError, ensure_daemon, stop_daemon


# ------------------------------------------------------------------------------------------
# Progress


def test_progress_fractions_are_monotone(daemon):
    seen = []
    with tessd.Client(daemon.socket, timeout=30) as c:
        result, _ = c.call("debug.sleep", {"seconds": 0.4, "steps": 8},
                           progress=lambda f, stage, msg: seen.append((f, stage, msg)))
    assert result["steps"] == 8
    fractions = [f for f, _, _ in seen]
    assert len(fractions) >= 8, seen
    assert all(0.0 <= f <= 1.0 for f in fractions), seen
    assert fractions == sorted(fractions), "fractions go backwards: %r" % fractions
    assert fractions[-1] == 1.0
    assert all(isinstance(stage, str) and isinstance(msg, str) for _, stage, msg in seen)


def test_job_poll_never_blocks(daemon):
    with tessd.Client(daemon.socket, timeout=30) as c:
        job = c.submit("debug.sleep", {"seconds": 0.6, "steps": 6})
        assert job.progress is None or job.progress.fraction < 1.0
        polls, slowest, fractions = 0, 0.0, []
        while True:
            t = time.monotonic()
            done = job.poll()
            slowest = max(slowest, time.monotonic() - t)
            polls += 1
            if job.progress is not None:
                fractions.append(job.progress.fraction)
            if done:
                break
            time.sleep(0.01)
        assert slowest < 0.05, "poll() blocked for %.3fs" % slowest
        assert polls > 10
        assert fractions == sorted(fractions) and fractions[-1] == 1.0
        assert job.done and job.result(0)[0]["steps"] == 6
        assert job.cancel() is False  # already finished
        # The daemon's own time: the sleep it did, less than the client's wall time.
        assert 600 <= job.elapsed_ms < polls * 10 + 1000, job.elapsed_ms


def test_job_cancel(daemon):
    with tessd.Client(daemon.socket, timeout=30) as c:
        job = c.submit("debug.sleep", {"seconds": 20, "steps": 200})
        deadline = time.monotonic() + 10
        while job.progress is None:
            assert time.monotonic() < deadline, "no progress frame"
            time.sleep(0.01)
        t = time.monotonic()
        assert job.cancel() is True
        with pytest.raises(TessdError) as info:
            job.result(timeout=10)
        assert info.value.code == "cancelled"
        assert time.monotonic() - t < 2, "cancel took too long"
        assert job.progress.fraction < 1.0
        assert c.ping("after-cancel") == "after-cancel"


def test_cancel_op_reports_whether_it_stopped_something(daemon):
    with tessd.Client(daemon.socket, timeout=30) as c:
        job = c.submit("debug.sleep", {"seconds": 20, "steps": 200})
        while job.progress is None:
            time.sleep(0.01)
        result, _ = c.call("cancel", {"id": job.id})
        assert result == {"cancelled": True}
        with pytest.raises(TessdError) as info:
            job.result(timeout=10)
        assert info.value.code == "cancelled"
        result, _ = c.call("cancel", {"id": job.id})
        assert result == {"cancelled": False}


def test_progress_callback_returning_false_cancels_the_call(daemon):
    calls = []

    def progress(fraction, stage, message):
        calls.append(fraction)
        return len(calls) < 3

    with tessd.Client(daemon.socket, timeout=30) as c:
        t = time.monotonic()
        with pytest.raises(TessdError) as info:
            c.call("debug.sleep", {"seconds": 20, "steps": 200}, progress=progress)
        assert info.value.code == "cancelled"
        assert time.monotonic() - t < 5
        assert 3 <= len(calls) < 50
        assert c.ping(1) == 1


def test_call_timeout_cancels(daemon):
    with tessd.Client(daemon.socket) as c:
        with pytest.raises(TimeoutError):
            c.call("debug.sleep", {"seconds": 20, "steps": 200}, timeout=0.3)
        assert c.ping(2) == 2


def test_jobs_from_several_threads_on_one_client(daemon):
    results = {}
    with tessd.Client(daemon.socket, timeout=30) as c:
        def run(k):
            results[k] = c.call("debug.sleep", {"seconds": 0.2, "steps": k + 1})[0]["steps"]
        threads = [threading.Thread(target=run, args=(k,)) for k in range(10)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert results == {k: k + 1 for k in range(10)}


# ------------------------------------------------------------------------------------------
# Connection loss


def test_closing_the_connection_mid_job_cancels_it_and_daemon_keeps_serving(tessd_bin, tmpdir_short):
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "c.sock")).start()
    try:
        c = tessd.Client(d.socket, timeout=30)
        job = c.submit("debug.sleep", {"seconds": 30, "steps": 300})
        while job.progress is None:
            time.sleep(0.01)
        assert "tessd-debug.sle" in d.threads()
        c.close()
        with pytest.raises(tessd.DaemonUnavailable):
            job.result(timeout=5)
        # The abandoned 30 s job was cancelled: its thread ends at its next step.
        assert wait_until(lambda: "tessd-debug.sle" not in d.threads(), 5), d.threads()
        assert "debug.sleep #1 failed: cancelled" in d.log_text(), d.log_tail()
        with tessd.Client(d.socket, timeout=10) as c2:
            assert c2.ping("still") == "still"
            c2.call("shutdown")
        d.proc.wait(timeout=8)
        assert d.proc.returncode == 0, d.log_tail()
    finally:
        d.stop()


def test_client_sees_daemon_exit(tessd_bin, tmpdir_short):
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "k.sock")).start()
    try:
        c = tessd.Client(d.socket, timeout=10)
        job = c.submit("debug.sleep", {"seconds": 30, "steps": 300})
        while job.progress is None:
            time.sleep(0.01)
        d.kill()
        with pytest.raises(tessd.DaemonUnavailable):
            job.result(timeout=5)
        with pytest.raises(tessd.DaemonUnavailable):
            c.call("ping")
        c.close()
        with pytest.raises(tessd.DaemonUnavailable):
            tessd.Client(d.socket, timeout=2)
    finally:
        d.stop()


# ------------------------------------------------------------------------------------------
# ensure_daemon / stop_daemon


def test_ensure_daemon_starts_then_reuses(tessd_bin, tmpdir_short):
    path = os.path.join(tmpdir_short, "e.sock")
    with pytest.raises(tessd.DaemonUnavailable):
        tessd.Client(path)
    try:
        assert ensure_daemon(path, binary=tessd_bin, timeout=20) == path
        with tessd.Client(path, timeout=10) as c:
            pid = c.hello()["pid"]
        assert ensure_daemon(path, binary=tessd_bin, timeout=20) == path
        with tessd.Client(path, timeout=10) as c:
            assert c.hello()["pid"] == pid, "a second daemon was started"
        assert os.path.exists(os.path.join(tmpdir_short, "e.log"))
    finally:
        assert stop_daemon(path) is True
    assert stop_daemon(path) is False
    with pytest.raises(tessd.DaemonUnavailable):
        tessd.Client(path)


def test_ensure_daemon_with_a_bare_name_and_env_binary(tessd_bin, tmpdir_short, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", tmpdir_short)
    monkeypatch.setenv("TESSD_BIN", tessd_bin)
    try:
        path = ensure_daemon("named", timeout=20)
        assert path == os.path.join(tmpdir_short, "named.sock")
        with tessd.Client("named", timeout=10) as c:
            assert c.ping("by-name") == "by-name"
    finally:
        stop_daemon("named")


def test_ensure_daemon_reports_a_daemon_that_dies(tmpdir_short):
    script = os.path.join(tmpdir_short, "fake-tessd")
    with open(script, "w") as f:
        f.write("#!/bin/sh\necho 'fake tessd: cannot start: disk on fire' >&2\nexit 7\n")
    os.chmod(script, 0o755)
    with pytest.raises(DaemonStartError) as info:
        ensure_daemon(os.path.join(tmpdir_short, "f.sock"), binary=script, timeout=10)
    text = str(info.value)
    assert "status 7" in text and "disk on fire" in text, text


def test_ensure_daemon_times_out_on_a_silent_daemon(tmpdir_short):
    script = os.path.join(tmpdir_short, "slow-tessd")
    with open(script, "w") as f:
        f.write("#!/bin/sh\necho 'starting slowly'\nexec sleep 30\n")
    os.chmod(script, 0o755)
    t = time.monotonic()
    with pytest.raises(DaemonStartError) as info:
        ensure_daemon(os.path.join(tmpdir_short, "s.sock"), binary=script, timeout=1.0)
    assert time.monotonic() - t < 5
    assert "did not answer" in str(info.value) and "starting slowly" in str(info.value)


def test_ensure_daemon_without_a_binary(tmpdir_short, monkeypatch):
    monkeypatch.delenv("TESSD_BIN", raising=False)
    monkeypatch.setenv("PATH", tmpdir_short)
    with pytest.raises(DaemonStartError) as info:
        ensure_daemon(os.path.join(tmpdir_short, "n.sock"), timeout=2)
    assert "TESSD_BIN" in str(info.value)


# ------------------------------------------------------------------------------------------
# Socket file handling by `tessd serve`


def test_second_daemon_on_a_live_socket_is_refused(daemon):
    out = subprocess.run([daemon.binary, "serve", "--socket", daemon.socket],
                         stdin=subprocess.DEVNULL, capture_output=True, timeout=20)
    text = (out.stdout + out.stderr).decode("utf-8", "replace")
    assert out.returncode == 3, (out.returncode, text)
    assert "already serving" in text and daemon.socket in text, text
    with tessd.Client(daemon.socket, timeout=10) as c:
        assert c.hello()["pid"] == daemon.pid
        assert c.ping("first-still-serves") == "first-still-serves"


def test_stale_socket_is_replaced(tessd_bin, tmpdir_short):
    path = os.path.join(tmpdir_short, "stale.sock")
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.bind(path)
    s.close()  # the file stays, nobody listens
    assert stat.S_ISSOCK(os.lstat(path).st_mode)
    with pytest.raises(tessd.DaemonUnavailable):
        tessd.Client(path)
    d = DaemonProcess(tessd_bin, path).start()
    try:
        with tessd.Client(path, timeout=10) as c:
            assert c.ping("fresh") == "fresh"
    finally:
        d.stop()


def test_socket_file_mode_is_0600(daemon):
    mode = os.stat(daemon.socket).st_mode
    assert stat.S_ISSOCK(mode)
    assert stat.S_IMODE(mode) == 0o600, oct(stat.S_IMODE(mode))


def test_shutdown_cancels_running_requests(tessd_bin, tmpdir_short):
    """(tests/reliability/test_shutdown.py checks this with several jobs and SIGTERM.)"""
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "g.sock")).start()
    try:
        with tessd.Client(d.socket, timeout=30) as c:
            job = c.submit("debug.sleep", {"seconds": 20.0, "steps": 200})
            while job.progress is None:
                time.sleep(0.01)
            with tessd.Client(d.socket, timeout=10) as c2:
                assert c2.call("shutdown")[0] == {"ok": True}
            with pytest.raises(TessdError) as info:
                job.result(timeout=5)
            assert info.value.code == "cancelled"
        d.proc.wait(timeout=5)
        assert d.proc.returncode == 0, d.log_tail()
    finally:
        d.stop()


def test_cancel_stops_a_tessellation_between_faces(daemon, tmp_path):
    """A cancelled `tessellate` stops starting faces (the faces in progress finish): OCCT's bottle
    at 0.1 um (~1.9 M triangles, a few seconds) cancelled at its first face ends `cancelled` in
    well under the time the whole job takes, and writes no file."""
    bottle = Path(__file__).resolve().parents[2] / "core/tessellate/tests/data/bottle.json"
    params = {"input": str(bottle), "tolerance": "0.0001mm"}
    with tessd.Client(daemon.socket, timeout=120) as c:
        t = time.monotonic()
        whole = c.call("tessellate", {**params, "output": str(tmp_path / "whole.ply")})[0]
        full = time.monotonic() - t
        assert whole["triangles"] > 1_000_000
        out = tmp_path / "never.ply"
        job = c.submit("tessellate", {**params, "output": str(out)})
        deadline = time.monotonic() + 30
        while job.progress is None or job.progress.stage != "faces":
            assert time.monotonic() < deadline, "no per-face progress"
            time.sleep(0.005)
        t = time.monotonic()
        assert job.cancel() is True
        with pytest.raises(TessdError) as info:
            job.result(timeout=60)
        stopped = time.monotonic() - t
        assert info.value.code == "cancelled", info.value
        assert stopped < 0.5 * full, (stopped, full)
        assert not out.exists()
        print(f"tessellate: whole {full:.2f} s, stopped {stopped:.2f} s after the cancel")
