"""The daemon's configurable limits (`tessd serve --max-payload --max-jobs --max-mesh-elements
--max-job-memory`): each refuses what is over it with a clear `too_large` error naming the limit
and its flag, lets through what is under it, and the daemon serves on afterwards.
"""

from __future__ import annotations


import numpy as np
import pytest

import tessd
from daemon_util import RawConn, raw_frame, serving
from tessd import TessdError


@pytest.fixture(scope="module")
def limited(tessd_bin):
    """A daemon with small limits: 2 jobs at once, 3 000 mesh elements, 1 MB per job, 64 KiB
    payloads."""
    with serving(tessd_bin, ("--max-jobs", "2", "--max-mesh-elements", "3000",
                             "--max-job-memory", "1000000", "--max-payload", "65536")) as proc:
        yield proc


def grid(n):
    """An n × n vertex grid of 2 (n − 1)² triangles, as arrays."""
    xs, ys = np.meshgrid(np.arange(n, dtype=np.float32), np.arange(n, dtype=np.float32))
    positions = np.stack([xs.ravel(), ys.ravel(), np.zeros(n * n, np.float32)], axis=1)
    faces = []
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            faces += [[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]
    return tessd.mesh_to_arrays(positions, np.asarray(faces, dtype=np.uint32))


def too_large(excinfo, *words):
    e = excinfo.value
    assert e.code == "too_large", e
    for w in words:
        assert w in e.message, e.message


def test_mesh_elements_over_the_limit_are_refused_and_under_it_served(limited, shared_data):
    with tessd.Client(limited.socket) as c:
        small = grid(20)  # 400 vertices, 722 triangles, 2 166 corners
        assert c.call("mesh.stats", arrays=small)[0]["triangles"] == 722
        with pytest.raises(TessdError) as e:
            c.call("mesh.stats", arrays=grid(33))  # 1 089 vertices, 2 048 faces, 6 144 corners
        too_large(e, "face corners", "3000", "--max-mesh-elements")
        # a file is refused while it is read: spot has 2 930 vertices, 5 856 faces
        with pytest.raises(TessdError) as e:
            c.call("mesh.stats", {"input": str(shared_data / "mesh" / "spot_triangulated.obj")})
        assert e.value.code == "too_large", e.value
        assert "3000" in e.value.message, e.value.message
        assert c.ping("after") == "after"


def test_a_job_whose_working_set_is_over_the_memory_limit_is_refused(limited):
    with tessd.Client(limited.socket) as c:
        # 400 vertices, 722 triangles: a working set of about 8 × 16 KB, under 1 MB; three
        # levels of subdivision make about 35 000 faces, over it
        cage = grid(20)
        assert c.call("mesh.stats", arrays=cage)[0]["triangles"] == 722
        with pytest.raises(TessdError) as e:
            c.call("subdivide", {"levels": 3}, arrays=cage)
        too_large(e, "1000000")
        r, _ = c.call("subdivide", {"levels": 1}, arrays=grid(8))
        assert r["faces"] > 0


def test_more_jobs_than_the_daemon_runs_at_once_are_refused(limited):
    with tessd.Client(limited.socket) as a, tessd.Client(limited.socket) as b:
        first = a.submit("debug.sleep", {"seconds": 3, "steps": 30})
        second = b.submit("debug.sleep", {"seconds": 3, "steps": 30})
        # both are admitted once their first progress frame arrives
        for job in (first, second):
            while job.progress is None and not job.done:
                job.wait(0.05)
        with pytest.raises(TessdError) as e:
            a.call("debug.sleep", {"seconds": 0})
        too_large(e, "2 requests", "--max-jobs")
        first.cancel()
        second.cancel()
        for job in (first, second):
            with pytest.raises(TessdError) as e:
                job.result(timeout=10)
            assert e.value.code == "cancelled"
        # the slots are free again
        assert a.call("debug.sleep", {"seconds": 0})[0] is not None


def test_a_payload_over_the_limit_is_refused_before_it_is_read(limited):
    with RawConn(limited.socket) as conn:
        body = {"id": 7, "op": "ping", "arrays": []}
        conn.send(raw_frame(body, b"\0" * 70000))
        reply = conn.final()
        assert reply["error"]["code"] == "too_large", reply
        assert "65536" in reply["error"]["message"], reply
    with tessd.Client(limited.socket) as c:
        assert c.ping(1) == 1


def test_no_limit_flag_is_needed_for_ordinary_work(daemon, shared_data):
    """The defaults let the shared meshes through."""
    with tessd.Client(daemon.socket) as c:
        r, _ = c.call("mesh.stats", {"input": str(shared_data / "mesh" / "stanford_bunny.obj")})
        assert r["triangles"] == 69451
