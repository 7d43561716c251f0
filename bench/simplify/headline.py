#!/usr/bin/env python3
"""Issue 33's headline table: tessd through the daemon against meshoptimizer in process.

    headline.py run --tessd target/release/tessd --harness target/release/bench-simplify
                    --out bench/results/simplify_headline.json [--work /tmp/tessd-bench-simplify]
                    [--triangles 4e6] [--repeat 5] [--budget 60] [--label after]

On a generated noisy torus (`bench-simplify gen`, the harness's bumpy torus: 4 M triangles,
2 M vertices by default), one thread: each tessd mode is sent to one `tessd serve` started with
`RAYON_NUM_THREADS=1`, the mesh as arrays (`positions` f32 [V, 3], `face_indices` u32 [T, 3]),
and timed by the daemon's own `elapsed_ms` (intake, validation, simplification, encoding the
output as arrays; not the socket transfer). Its peer is matched to the daemon's output vertex
count by an untimed search and timed in process (`bench-simplify peer`; meshoptimizer's
`target_index_count` is its parameter, so simplifySloppy's own grid-size search is timed).
The two are interleaved: rounds of one daemon job then one peer run (a child that loads the
mesh and times one call), so that a slow spell of the machine hits both.
Rows (the issue's): grid barycentre (150 cells per axis) and grid quadric vs simplifySloppy,
quality 0.5 % barycentre vs simplifySloppy, complexity barycentre at grid barycentre's count
vs simplifySloppy, complexity quadric at the same count vs meshoptimizer `simplify`. Medians
of `--repeat` rounds (fewer, but 3 at least, once a further round would pass `--budget` s).
*ratio* = peer time ÷ tessd time (> 1: tessd is faster). Writes the JSON and a Markdown
table beside it (same name, `.md`).

Run with a Python that has numpy (the bench venv); the `tessd` client comes from `python/`.
"""

import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "python"))
sys.path.insert(0, HERE)
import tessd  # noqa: E402
from tessd.daemon import stop_daemon  # noqa: E402
from e2e_daemon import mesh_arrays  # noqa: E402
from tables import headline_table  # noqa: E402

# (row, daemon params (None for a count filled in from the grid's), peer method)
ROWS = [
    ("grid, barycentre (150 cells)", {"method": "grid", "representative": "barycenter", "cells": 150},
     "meshopt-sloppy"),
    ("grid, quadric (150 cells)", {"method": "grid", "representative": "quadric", "cells": 150},
     "meshopt-sloppy"),
    ("quality 0.5 %, barycentre", {"method": "quality", "representative": "barycenter", "max_error": "0.5%"},
     "meshopt-sloppy"),
    ("complexity, barycentre (grid's count)", {"method": "complexity", "representative": "barycenter",
                                               "target_vertices": None}, "meshopt-sloppy"),
    ("complexity, quadric (grid's count)", {"method": "complexity", "representative": "quadric",
                                            "target_vertices": None}, "meshopt-simplify"),
]


def peer_call(args, peer, path, count, param=None):
    """One `bench-simplify peer` call (one timed run; the search too unless `param` is given)."""
    cmd = [args.harness, "peer", peer, str(path), str(count), "--repeat", "1"]
    if param is not None:
        cmd += ["--param", repr(param)]
    return json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True,
                                     env={**os.environ, "RAYON_NUM_THREADS": "1"}).stdout)


def interleaved(args, client, params, arrays, peer, path):
    """Rounds of one daemon job then one peer run, `--repeat` rounds (fewer, but 3 at least, once
    a further round would pass the budget): the daemon's elapsed_ms, the peer's times, the daemon's
    output count and the peer's last record. The first round's peer call searches the parameter
    landing at the daemon's output count; later rounds reuse it."""
    tessd_ms, peer_ms, count, p, t0 = [], [], None, None, time.perf_counter()
    while len(tessd_ms) < args.repeat:
        if len(tessd_ms) >= 3 and time.perf_counter() - t0 + (tessd_ms[-1] + peer_ms[-1]) / 1e3 > args.budget:
            break
        job = client.submit("simplify", params, arrays)
        result, _ = job.result()
        tessd_ms.append(job.elapsed_ms)
        if count is None:
            count = result.get("output_vertices")
        elif result.get("output_vertices") != count:
            raise RuntimeError(f"the daemon's output count changed: {count} then {result.get('output_vertices')}")
        p = peer_call(args, peer, path, count, None if p is None else p["param"])
        peer_ms.append(p["time_s"] * 1e3)
    return tessd_ms, peer_ms, count, p


def run(args):
    work = Path(args.work)
    tri = int(float(args.triangles))
    name = f"torus_{tri / 1e6:g}M"
    path = work / "inputs" / f"{name}.ply"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run([args.harness, "gen", str(tri), str(path)], check=True)
    shape, arrays = mesh_arrays(args.harness, path, work / "arrays" / f"headline_{name}")
    print(f"== headline {name}: {shape['vertices']} vertices, {shape['triangles']} triangles "
          f"({args.label or 'no label'}, {args.tessd})", file=sys.stderr)
    os.environ["RAYON_NUM_THREADS"] = "1"
    rows, grid_count = [], None
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        sock = tessd.ensure_daemon(os.path.join(tmp, "headline.sock"), binary=args.tessd)
        try:
            with tessd.Client(sock) as client:
                for label, params, peer in ROWS:
                    params = dict(params)
                    if params.get("target_vertices", 0) is None:
                        params["target_vertices"] = grid_count
                    row = {"row": label, "params": params, "peer": peer}
                    try:
                        times, peer_ms, count, p = interleaved(args, client, params, arrays, peer, path)
                        if grid_count is None:
                            grid_count = count
                        row.update({"tessd_runs_ms": times, "tessd_ms": statistics.median(times),
                                    "out_vertices": count, "peer_ms": statistics.median(peer_ms),
                                    "peer_runs_ms": peer_ms, "peer_out_vertices": p["out_vertices"],
                                    "peer_hit": p["hit"], "peer_param": p["param"]})
                        row["ratio"] = row["peer_ms"] / row["tessd_ms"]
                        print(f"   {label:<40} tessd {row['tessd_ms']:9.1f} ms ({count} vertices)  {peer} "
                              f"{row['peer_ms']:9.1f} ms ({p['out_vertices']})  ratio {row['ratio']:.2f}",
                              file=sys.stderr)
                    except Exception as ex:  # noqa: BLE001 - record and go on
                        row["error"] = f"{type(ex).__name__}: {ex}"[:500]
                        print(f"   {label}: FAILED {row['error']}", file=sys.stderr)
                    rows.append(row)
        finally:
            stop_daemon(sock)
    doc = {"meta": {"label": args.label, "tessd": os.path.abspath(args.tessd), "mesh": name,
                    "input_vertices": shape["vertices"], "input_triangles": shape["triangles"],
                    "repeat": args.repeat, "budget_s": args.budget, "threads": 1,
                    "unix_time": int(time.time()), "nproc": os.cpu_count(),
                    "wall_s": time.perf_counter() - t_all},
           "rows": rows}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1) + "\n")
    date = datetime.datetime.fromtimestamp(doc["meta"]["unix_time"], datetime.UTC).strftime("%Y-%m-%d %H:%M")
    md = [f"# Simplification headline ({args.label or 'unlabelled'}), {date} UTC", "",
          f"`{' '.join(sys.argv)}`", ""] + headline_table(doc if args.label != "before" else None,
                                                            doc if args.label == "before" else None)
    out.with_suffix(".md").write_text("\n".join(md) + "\n")
    print(f"headline done in {time.perf_counter() - t_all:.1f} s: {out}", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["run"])
    ap.add_argument("--tessd", default="target/release/tessd")
    ap.add_argument("--harness", default="target/release/bench-simplify")
    ap.add_argument("--work", default="/tmp/tessd-bench-simplify")
    ap.add_argument("--out", default="bench/results/simplify_headline.json")
    ap.add_argument("--triangles", default="4e6")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--budget", type=float, default=60.0)
    ap.add_argument("--label", default="")
    run(ap.parse_args())


if __name__ == "__main__":
    main()
