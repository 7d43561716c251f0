"""Many clients and many in-flight requests against one daemon, every answer checked exactly.

Expected mesh statistics come from /work/shared/data/MANIFEST.md (spot_triangulated: 2930
vertices, 5856 triangles, closed; stanford_bunny: 35947 stored vertices of which 1113 are
unreferenced, 69451 triangles, 223 boundary edges in 5 loops); bounds come from an
independent OBJ parser.
"""

from __future__ import annotations

import threading
import uuid

import numpy as np
import pytest

import tessd
from daemon_util import read_obj

CLIENTS = 32
REQUESTS = 200


def expected_stats(positions, stored, referenced, faces, boundary_edges, boundary_loops):
    p = np.asarray(positions, dtype=np.float32)
    return {
        "vertices": referenced,
        "stored_vertices": stored,
        "unreferenced_vertices": stored - referenced,
        "faces": faces,
        "triangles": faces,
        "face_sizes": {"3": faces},
        "boundary_edges": boundary_edges,
        "boundary_loops": boundary_loops,
        "non_manifold_edges": 0,
        "bounds_f32": (p.min(axis=0), p.max(axis=0)),
    }


@pytest.fixture(scope="module")
def meshes(shared_data):
    spot_path = shared_data / "mesh" / "spot_triangulated.obj"
    bunny_path = shared_data / "mesh" / "stanford_bunny.obj"
    spot_pos, spot_faces = read_obj(spot_path)
    bunny_pos, _ = read_obj(bunny_path)  # its unreferenced vertices lie inside the bounds
    spot_arrays = tessd.mesh_to_arrays(np.asarray(spot_pos, dtype=np.float32),
                                       np.asarray(spot_faces, dtype=np.uint32))
    return {
        "spot_path": str(spot_path),
        "bunny_path": str(bunny_path),
        "spot_arrays": spot_arrays,
        "spot": expected_stats(spot_pos, 2930, 2930, 5856, 0, 0),
        "bunny": expected_stats(bunny_pos, 35947, 34834, 69451, 223, 5),
    }


def check_stats(result, expected, where):
    for key in ("vertices", "stored_vertices", "unreferenced_vertices", "faces", "triangles",
                "face_sizes", "boundary_edges", "boundary_loops", "non_manifold_edges"):
        assert result.get(key) == expected[key], "%s: %s = %r, expected %r" % (
            where, key, result.get(key), expected[key])
    lo, hi = expected["bounds_f32"]
    bounds = result["bounds"]
    assert np.array_equal(np.float32(bounds["min"]), lo), (where, bounds, lo)
    assert np.array_equal(np.float32(bounds["max"]), hi), (where, bounds, hi)


def test_manifest_counts_single(daemon, meshes):
    """The expectations themselves, once, before hammering (clearer failures)."""
    with tessd.Client(daemon.socket, timeout=60) as c:
        check_stats(c.call("mesh.stats", {"input": meshes["spot_path"]})[0], meshes["spot"], "spot path")
        check_stats(c.call("mesh.stats", arrays=meshes["spot_arrays"])[0], meshes["spot"], "spot arrays")
        check_stats(c.call("mesh.stats", {"input": meshes["bunny_path"]})[0], meshes["bunny"], "bunny path")


def test_32_clients_x_200_requests(daemon, meshes):
    errors = []
    counts = [0] * CLIENTS
    start = threading.Barrier(CLIENTS)

    def worker(k):
        try:
            with tessd.Client(daemon.socket, timeout=120) as c:
                start.wait()
                for i in range(REQUESTS):
                    if i % 2 == 0:
                        echo = {"client": k, "request": i, "token": uuid.uuid4().hex}
                        result, arrays = c.call("ping", {"echo": echo})
                        assert result == {"pong": True, "echo": echo}, result
                        assert arrays == {}
                    else:
                        j = i // 2
                        if j % 50 == 7:
                            result, _ = c.call("mesh.stats", {"input": meshes["bunny_path"]})
                            check_stats(result, meshes["bunny"], "client %d request %d bunny" % (k, i))
                        elif j % 2 == 0:
                            result, _ = c.call("mesh.stats", {"input": meshes["spot_path"]})
                            check_stats(result, meshes["spot"], "client %d request %d spot path" % (k, i))
                        else:
                            result, _ = c.call("mesh.stats", arrays=meshes["spot_arrays"])
                            check_stats(result, meshes["spot"], "client %d request %d spot arrays" % (k, i))
                    counts[k] += 1
        except BaseException as e:  # reported below with the client number
            errors.append((k, repr(e)))

    threads = [threading.Thread(target=worker, args=(k,)) for k in range(CLIENTS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[:5]
    assert counts == [REQUESTS] * CLIENTS
    assert daemon.alive()


def test_one_client_shared_by_threads_with_pipelining(daemon, meshes):
    """8 threads share one Client; each keeps up to 6 requests in flight at once."""
    errors = []
    with tessd.Client(daemon.socket, timeout=120) as c:

        def worker(k):
            try:
                for batch in range(10):
                    jobs = []
                    for i in range(6):
                        if i % 2 == 0:
                            echo = "%d-%d-%d" % (k, batch, i)
                            jobs.append(("ping", echo, c.submit("ping", {"echo": echo})))
                        else:
                            jobs.append(("stats", None, c.submit("mesh.stats", arrays=meshes["spot_arrays"])))
                    for kind, echo, job in reversed(jobs):
                        result, _ = job.result(timeout=120)
                        if kind == "ping":
                            assert result["echo"] == echo, (result, echo)
                        else:
                            check_stats(result, meshes["spot"], "shared client")
            except BaseException as e:
                errors.append((k, repr(e)))

        threads = [threading.Thread(target=worker, args=(k,)) for k in range(8)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert c.in_flight == 0
    assert not errors, errors[:5]


def test_progress_frames_interleave_with_other_replies(daemon):
    """Replies to different ids interleave on one connection and are routed to their jobs."""
    with tessd.Client(daemon.socket, timeout=60) as c:
        seen = {}
        jobs = {steps: c.submit("debug.sleep", {"seconds": 0.3, "steps": steps},
                                progress=lambda f, s, m, steps=steps: seen.setdefault(steps, []).append(m))
                for steps in (3, 5, 7)}
        for _ in range(20):
            assert c.ping("between") == "between"
        for steps, job in jobs.items():
            result, _ = job.result(timeout=30)
            assert result["steps"] == steps
            assert all(("of %d" % steps) in m for m in seen[steps] if m.startswith("step")), seen[steps]
