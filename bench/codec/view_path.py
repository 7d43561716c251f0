"""View-dependent refinement along a recorded camera path (paper 003 §6.2, Figure 9).

Compresses a mesh with ``tessd compress``, starts a daemon, and walks a camera path through
``codec.view`` on one socket: the daemon keeps the file's decoder states between requests, so
each frame refines (or coarsens) from the previous one, as the paper's viewer does. For every
frame it records the daemon's own ``decode_ms`` (the refinement and the border rule, not the
transfer), the triangles shown, the symbols decoded and the bytes of code read, and reports
triangles shown per second of refinement (the paper's "triangles par seconde" of Figure 9 counts
triangles displayed per second of its viewer; here no drawing happens, only decoding).

The path: a zoom from far to close along the view axis, then half an orbit at the closest
distance, then back out; positions relative to the mesh's bounding box.

Usage: ``python bench/codec/view_path.py TESSD_BIN MESH [--bits 12] [--frames 60]
[--pixel-error 1] [--jsonl OUT]``. Prints a Markdown table.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "python"))
import tessd  # noqa: E402
from tessd.daemon import stop_daemon  # noqa: E402


def path(centre, radius, frames):
    """(eye, target, up) per frame: zoom in from 20 radii to 1.2, orbit 180°, zoom back out."""
    third = max(1, frames // 3)
    out = []
    for k in range(third):
        d = radius * 20.0 * (1.2 / 20.0) ** (k / max(1, third - 1))
        out.append(((centre[0], centre[1], centre[2] + d), centre))
    for k in range(third):
        a = math.pi * k / max(1, third - 1)
        d = radius * 1.2
        out.append(((centre[0] + d * math.sin(a), centre[1], centre[2] + d * math.cos(a)), centre))
    for k in range(frames - 2 * third):
        d = radius * 1.2 * (20.0 / 1.2) ** (k / max(1, frames - 2 * third - 1))
        out.append(((centre[0], centre[1], centre[2] - d), centre))
    return [(list(e), list(t), [0.0, 1.0, 0.0]) for e, t in out]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("mesh")
    ap.add_argument("--bits", type=int, default=12)
    # several nSP-cells, so that the view refines some and not others: at the default N_min
    # (50 000, issue 34) the bunny and fandisk are one cell each
    ap.add_argument("--min-cell", type=int, default=8000)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--pixel-error", type=float, default=1.0)
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--jsonl")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tsc = os.path.join(tmp, "mesh.tsc")
        out = subprocess.run([a.binary, "compress", a.mesh, tsc, "--bits", str(a.bits),
                              "--min-cell", str(a.min_cell), "--json"],
                             check=True, stdout=subprocess.PIPE, text=True)
        info = json.loads(out.stdout)
        step, origin = info["step"], info["origin"]
        side = step * ((1 << a.bits) - 1)
        centre = [o + side / 2.0 for o in origin]
        radius = side / 2.0
        sock = os.path.join(tmp, "view.sock")
        sockpath = tessd.ensure_daemon(sock, binary=a.binary)
        rows = []
        try:
            with tessd.Client(sockpath) as client:
                for k, (eye, target, up) in enumerate(path(centre, radius, a.frames)):
                    r, _ = client.call("codec.view", {"input": tsc, "eye": eye, "target": target,
                                                      "up": up, "fov": 30, "size": a.size,
                                                      "pixel_error": a.pixel_error})
                    rows.append(dict(frame=k, eye=eye, triangles=r["triangles"], cells=r["cells"],
                                     decode_ms=r["decode_ms"], symbols=r["symbols"],
                                     bytes_read=r["bytes_read"]))
        finally:
            stop_daemon(sockpath)
    if a.jsonl:
        with open(a.jsonl, "w") as f:
            for r in rows:
                f.write(json.dumps(dict(r, mesh=os.path.basename(a.mesh), bits=a.bits,
                                        file_bytes=info["bytes"])) + "\n")
    total_tris = sum(r["triangles"] for r in rows)
    total_ms = sum(r["decode_ms"] for r in rows)
    per_frame = [r["triangles"] / (r["decode_ms"] / 1e3) for r in rows if r["decode_ms"] > 0]
    print("| mesh | frames | triangles shown (median / max) | decode ms per frame (median / max) "
          "| triangles shown per second of refinement (median) | bytes read along the path ÷ file |")
    print("|---|---:|---:|---:|---:|---:|")
    print("| %s | %d | %d / %d | %.1f / %.1f | %.2f M | %.2f |" % (
        os.path.basename(a.mesh), len(rows), statistics.median(r["triangles"] for r in rows),
        max(r["triangles"] for r in rows), statistics.median(r["decode_ms"] for r in rows),
        max(r["decode_ms"] for r in rows), statistics.median(per_frame) / 1e6,
        sum(r["bytes_read"] for r in rows) / info["bytes"]))
    print("\nall frames: %d triangles in %.0f ms of refinement (%.2f M triangles/s)" % (
        total_tris, total_ms, total_tris / total_ms / 1e3))


if __name__ == "__main__":
    main()
