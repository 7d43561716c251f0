"""Clients that die (issue 18, part 2): a client SIGKILLed mid-request and one SIGKILLed
mid-upload. The daemon frees the job (its thread ends, the op saw the cancel, the upload's
buffers are returned) and serves on.

The clients are real processes (the venv's python with the tessd client, or a raw socket)
killed with SIGKILL, so nothing of theirs closes the connection politely: the kernel does.
The daemon is watched from outside through /proc (its threads by name, its resident memory)
and its log.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

import tessd
from daemon_util import DaemonProcess, REPO, wait_until

#: A client that starts one request, says so once the daemon reports progress, then hangs.
CLIENT = r"""
import sys, time
sys.path.insert(0, %(python)r)
import tessd
op, params = sys.argv[2], __import__("json").loads(sys.argv[3])
c = tessd.Client(sys.argv[1], timeout=60)
job = c.submit(op, params)
while job.progress is None:
    time.sleep(0.005)
print("running", flush=True)
time.sleep(600)
"""

#: A client that sends the header, JSON and the first half of a large payload, then hangs.
UPLOADER = r"""
import json, socket, struct, sys, time
path, total, sent = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
body = json.dumps({"id": 1, "op": "mesh.stats", "arrays": [
    {"name": "positions", "dtype": "f32", "shape": [total // 12, 3], "offset": 0,
     "length": total}]}).encode()
s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
s.connect(path)
s.sendall(struct.pack("<4sHHIIQ", b"TSSD", 1, 0, len(body), 0, total) + body)
chunk = b"\x00" * (1 << 20)
for _ in range(sent >> 20):
    s.sendall(chunk)
print("half", flush=True)
time.sleep(600)
"""


def start_client(script: str, *args: str) -> subprocess.Popen:
    """Runs a client script (CLIENT or UPLOADER) in its own python process."""
    code = script % {"python": str(REPO / "python")} if "%(python)" in script else script
    return subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)


def wait_line(proc: subprocess.Popen, expected: str) -> None:
    """Waits for the client to print `expected` (its request is under way)."""
    line = proc.stdout.readline().decode().strip()
    if line != expected:
        proc.kill()
        raise AssertionError(f"client said {line!r}: {proc.stderr.read().decode()}")


def sigkill(proc: subprocess.Popen) -> None:
    """SIGKILLs the client and reaps it."""
    proc.kill()
    proc.wait()
    proc.stdout.close()
    proc.stderr.close()


@pytest.fixture
def daemon(tessd_bin, tmpdir_short):
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "c.sock")).start()
    try:
        yield d
        assert d.alive(), "the daemon died:\n" + d.log_tail()
    finally:
        d.stop()


def settled_threads(d: DaemonProcess) -> list:
    """The daemon's thread names once two looks 100 ms apart agree (at most 5 s)."""
    before = d.threads()
    for _ in range(50):
        time.sleep(0.1)
        now = d.threads()
        if now == before:
            return now
        before = now
    return before


def serves_on(d: DaemonProcess, mesh_dir) -> None:
    """The daemon answers `ping` and completes a real request."""
    with tessd.Client(d.socket, timeout=30) as c:
        assert c.ping("after") == "after"
        result, _ = c.call("mesh.stats", {"input": str(mesh_dir / "suzanne.obj")})
        assert result["faces"] == 500


@pytest.mark.parametrize("op, params, quick, thread", [
    ("debug.sleep", {"seconds": 30, "steps": 300}, {"seconds": 0}, "tessd-debug.sle"),
    ("subdivide", {"input": "suzanne.obj", "levels": 6}, {"levels": 1}, "tessd-subdivide"),
], ids=["debug.sleep", "subdivide"])
def test_client_killed_mid_request_frees_the_job(daemon, mesh_dir, op, params, quick, thread):
    if "input" in params:
        params = dict(params, input=str(mesh_dir / params["input"]))
    # A quick run first, so that worker pools the op starts (whose threads inherit the job
    # thread's name and stay) exist before the threads are counted.
    with tessd.Client(daemon.socket, timeout=30) as c:
        c.call(op, dict(params, **quick))
    assert wait_until(lambda: "tessd-conn" not in daemon.threads(), 5), daemon.threads()
    # The quick job's own thread may outlive its connection's by a few milliseconds.
    idle = settled_threads(daemon)
    rounds = 3
    freed_ms = []
    for k in range(rounds):
        client = start_client(CLIENT, daemon.socket, op, json.dumps(params))
        try:
            wait_line(client, "running")
            running = daemon.threads()
            assert running.count(thread) == idle.count(thread) + 1, running
            assert running.count("tessd-conn") == 1, running
        finally:
            sigkill(client)
        t = time.monotonic()
        # The job's thread and the connection's are gone.
        assert wait_until(lambda: daemon.threads() == idle, 10), (
            f"round {k}: the job kept running after its client died: {daemon.threads()}")
        freed_ms.append((time.monotonic() - t) * 1e3)
        # The op itself stopped at its next checkpoint (it did not run to its end).
        assert wait_until(lambda: daemon.log_text().count(f"{op} #1 failed: cancelled") == k + 1,
                          2), daemon.log_tail()
    assert f"{op} #1 failed" not in daemon.log_text().replace(f"{op} #1 failed: cancelled", "")
    serves_on(daemon, mesh_dir)
    print(f"\n{op}: {rounds} clients SIGKILLed mid-request: each job cancelled and its thread "
          f"gone after {', '.join('%.0f' % ms for ms in freed_ms)} ms; daemon serves on")


def test_client_killed_mid_upload_frees_the_buffers(daemon, mesh_dir):
    total, sent = 384 << 20, 192 << 20  # a 384 MiB payload (32 Mi vertices), killed halfway
    assert wait_until(lambda: "tessd-conn" not in daemon.threads(), 5), daemon.threads()
    baseline = daemon.rss()
    threads = daemon.threads()
    uploader = start_client(UPLOADER, daemon.socket, str(total), str(sent))
    try:
        wait_line(uploader, "half")
        # The daemon holds what arrived (its buffers fill as the bytes come).
        assert wait_until(lambda: daemon.rss() > baseline + sent * 0.9, 10), (
            baseline, daemon.rss())
        peak = daemon.rss()
        assert daemon.threads().count("tessd-conn") == threads.count("tessd-conn") + 1
    finally:
        sigkill(uploader)
    t = time.monotonic()
    # The connection ends at the truncated frame and its buffers go back to the system.
    assert wait_until(lambda: daemon.rss() < baseline + (32 << 20), 10), (
        baseline, peak, daemon.rss())
    freed_ms = (time.monotonic() - t) * 1e3
    assert wait_until(lambda: daemon.threads() == threads, 5), (threads, daemon.threads())
    assert (f"frame truncated in the payload: expected {total} bytes, got {sent}"
            in daemon.log_text()), daemon.log_tail()
    serves_on(daemon, mesh_dir)
    print(f"\nupload of {total >> 20} MiB killed after {sent >> 20} MiB: RSS {baseline >> 20} "
          f"-> {peak >> 20} -> {daemon.rss() >> 20} MiB ({freed_ms:.0f} ms after the kill), "
          f"connection thread gone; daemon serves on")
