"""End-to-end mesh intake through the daemon (issue 15, point 0).

Sends the arrays of a generated torus (f32 positions [V, 3], u32 face_indices [T, 3], as numpy
holds them) to a fresh ``tessd serve`` started with ``RAYON_NUM_THREADS=1``, and reads the
daemon's own ``elapsed_ms`` (the job's time, not the transfer) for

* ``mesh.convert`` without ``output`` (the mesh in, validated, and back as arrays), and
* ``simplify`` ``method=grid`` with ``cells=2`` (an output of a few vertices: the fixed cost of
  the pipeline beyond intake).

Usage: ``python bench/intake_daemon.py TESSD_BIN [TRIANGLES_M] [RUNS]`` (defaults 4 and 7).
Prints one Markdown table row per op: median and best ``elapsed_ms`` and M triangles/s.
"""

import os
import statistics
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python"))
import tessd  # noqa: E402
from tessd.daemon import stop_daemon  # noqa: E402


def torus(triangles):
    """A closed torus of nu × nv quads split in two, vertices in row order (as
    `core/tessd/examples/bench_intake.rs` builds it)."""
    nv = max(3, round((triangles / 5.0) ** 0.5))
    nu = max(3, round(triangles / (2.0 * nv)))
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False, dtype=np.float32)[:, None]
    v = np.linspace(0, 2 * np.pi, nv, endpoint=False, dtype=np.float32)[None, :]
    ring = 1.0 + 0.4 * np.cos(v)
    pos = np.stack(np.broadcast_arrays(ring * np.cos(u), ring * np.sin(u), 0.4 * np.sin(v) + 0 * u),
                   axis=-1).reshape(-1, 3).astype(np.float32)
    i = np.arange(nu, dtype=np.uint32)[:, None]
    j = np.arange(nv, dtype=np.uint32)[None, :]
    i1, j1 = (i + 1) % nu, (j + 1) % nv
    a, b, c, d = i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1
    faces = np.stack([np.stack(np.broadcast_arrays(a, b, c), -1),
                      np.stack(np.broadcast_arrays(a, c, d), -1)], axis=2).reshape(-1, 3)
    return pos, np.ascontiguousarray(faces, dtype=np.uint32)


def main():
    binary = sys.argv[1]
    tris_m = float(sys.argv[2]) if len(sys.argv) > 2 else 4.0
    runs = int(sys.argv[3]) if len(sys.argv) > 3 else 7
    pos, faces = torus(tris_m * 1e6)
    arrays = {"positions": pos, "face_indices": faces}
    ops = [("mesh.convert", {}), ("simplify", {"method": "grid", "cells": 2})]
    os.environ["RAYON_NUM_THREADS"] = "1"
    with tempfile.TemporaryDirectory() as tmp:
        sock = os.path.join(tmp, "intake.sock")
        path = tessd.ensure_daemon(sock, binary=binary)
        try:
            with tessd.Client(path) as client:
                for op, params in ops:
                    times = []
                    for _ in range(runs + 1):
                        job = client.submit(op, params, arrays)
                        job.result()
                        times.append(job.elapsed_ms)
                    times = times[1:]  # the first run warms the daemon up
                    med = statistics.median(times)
                    print("| `%s` %s | %d | %.1f | %.1f | %.0f |" % (
                        op, params or "", len(faces), med, min(times), len(faces) / med / 1e3))
        finally:
            stop_daemon(path)


if __name__ == "__main__":
    main()
