"""`shutdown` (and SIGTERM, the same path) with requests in flight (issue 18, part 2): the
running requests are cancelled, each gets its final answer (error `cancelled`) before the
daemon exits, and it exits within a few seconds (not after the 10 s grace period, nor after
the requests' own 30 s).
"""

from __future__ import annotations

import os
import signal
import time

import pytest

import tessd
from daemon_util import DaemonProcess, wait_until


@pytest.mark.parametrize("how", ["shutdown", "SIGTERM"])
def test_shutdown_cancels_and_answers_jobs_in_flight(how, tessd_bin, mesh_dir, tmpdir_short):
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "s.sock")).start()
    clients = []
    try:
        a = tessd.Client(d.socket, timeout=30)
        b = tessd.Client(d.socket, timeout=30)
        clients += [a, b]
        jobs = [
            a.submit("debug.sleep", {"seconds": 30, "steps": 300}),
            a.submit("debug.sleep", {"seconds": 30, "steps": 30}),  # a checkpoint a second
            b.submit("debug.sleep", {"seconds": 30, "steps": 100}),
            b.submit("subdivide", {"input": str(mesh_dir / "suzanne.obj"), "levels": 6}),
        ]
        assert wait_until(lambda: all(j.progress is not None for j in jobs), 10), \
            [j.progress for j in jobs]
        t0 = time.monotonic()
        if how == "shutdown":
            with tessd.Client(d.socket, timeout=10) as c:
                assert c.call("shutdown")[0] == {"ok": True}
        else:
            os.kill(d.pid, signal.SIGTERM)
        answers = []
        for job in jobs:
            with pytest.raises(tessd.TessdError) as info:
                job.result(timeout=10)
            answers.append(info.value.code)
        answered = time.monotonic() - t0
        d.proc.wait(10)
        exited = time.monotonic() - t0
        assert answers == ["cancelled"] * len(jobs), answers
        assert d.proc.returncode == 0, d.log_tail()
        assert exited < 5, exited
        log = d.log_text()
        assert "cancelling 4 running request(s)" in log and "stopped" in log, d.log_tail()
        assert not os.path.exists(d.socket), "the socket file outlived the daemon"
        print(f"\n{how}: {len(jobs)} requests in flight on 2 connections, each answered "
              f"`cancelled` within {answered * 1e3:.0f} ms; daemon exited (status 0) after "
              f"{exited * 1e3:.0f} ms")
    finally:
        for c in clients:
            c.close()
        d.stop()
