#!/usr/bin/env python3
"""End to end through the daemon, beside the library call, in the simplification benchmark.

    e2e_daemon.py run [--manifest bench/results/simplify_inputs.json]
        [--jsonl bench/results/simplify_raw.jsonl] [--harness target/release/bench-simplify]
        [--tessd target/release/tessd] [--work /tmp/tessd-bench-simplify] [--repeat 3]
        [--budget 12] [--meshes a,b] [--fractions 0.5,0.1,0.01]

For every generated torus of the manifest (triangles only, so the arrays are the mesh the
library call got) and every tessd record of the jsonl on it (the parameter its search found),
sends the mesh as arrays (`positions` f32 [V, 3], `face_indices` u32 [T, 3], written raw by
`bench-simplify arrays`) to one `tessd serve` started with `RAYON_NUM_THREADS=1`, with the
same method, goal and representative, and reads the daemon's own `elapsed_ms` (the job: intake,
validation, simplification, the output encoded as arrays; not the transfer). Median of
`--repeat` runs (fewer when one run exceeds the `--budget` seconds, as for the library call).
Appends one line per (mesh, method, target) with `"record": "e2e"` to the jsonl: the times,
the daemon's `output_vertices` and whether it equals the library call's.

Run with a Python that has numpy (the bench venv); the `tessd` client comes from `python/`.
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
import tessd  # noqa: E402
from tessd.daemon import stop_daemon  # noqa: E402


def mesh_arrays(harness, path, adir):
    """The mesh file `path` as the arrays a client sends (`positions` f32 [V, 3], `face_indices`
    u32 [T, 3]), written by the harness's `arrays` into `adir` and read back; and its shape."""
    shape = json.loads(subprocess.run([harness, "arrays", str(path), str(adir)], check=True,
                                      capture_output=True, text=True).stdout)
    pos = np.fromfile(Path(adir) / "positions.f32", dtype="<f4").reshape(-1, 3)
    faces = np.fromfile(Path(adir) / "faces.u32", dtype="<u4").reshape(-1, 3)
    shutil.rmtree(adir, ignore_errors=True)
    return shape, {"positions": pos, "face_indices": faces}


def params_of(rec):
    """The daemon's `simplify` params for a harness record (`methods.rs`'s settings)."""
    _, mode, rep = rec["method"].split("-")
    p = {"method": mode, "representative": {"bary": "barycenter", "quadric": "quadric"}[rep]}
    if mode == "grid":
        p["cell_size"] = rec["param"]
    elif mode == "quality":
        p["max_error"] = rec["param"]
    else:
        p["target_vertices"] = int(round(rec["param"]))
    return p


def load_records(jsonl):
    by = {}
    for line in open(jsonl):
        if line.strip():
            r = json.loads(line)
            if r.get("record") is None and r.get("family") == "tessd" and "time_s" in r:
                by[(r["mesh"], r["method"], r["fraction"])] = r
    return by


def run(args):
    manifest = json.loads(Path(args.manifest).read_text())
    work = Path(args.work or manifest["meta"].get("work", "/tmp/tessd-bench-simplify"))
    only = set(args.meshes.split(",")) if args.meshes else None
    fractions = [float(f) for f in args.fractions.split(",")] if args.fractions else None
    recs = load_records(args.jsonl)
    meshes = [e for e in manifest["meshes"] if e["generated"] and (not only or e["mesh"] in only)]
    os.environ["RAYON_NUM_THREADS"] = "1"
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, open(args.jsonl, "a") as out_f:
        sock = tessd.ensure_daemon(os.path.join(tmp, "e2e.sock"), binary=args.tessd)
        try:
            with tessd.Client(sock) as client:
                for e in meshes:
                    todo = sorted(((k, r) for k, r in recs.items() if k[0] == e["mesh"]
                                   and (fractions is None or k[2] in fractions)),
                                  key=lambda kr: (-kr[0][2], kr[0][1]))
                    if not todo:
                        continue
                    shape, arrays = mesh_arrays(args.harness, e["path"], work / "arrays" / e["mesh"])
                    pos, faces = arrays["positions"], arrays["face_indices"]
                    assert len(faces) == shape["triangles"] == e["input_triangles"], (shape, e["mesh"])
                    print(f"== {e['mesh']} (e2e: {len(pos)} vertices, {len(faces)} triangles)", file=sys.stderr)
                    for (mesh, method, frac), r in todo:
                        params = params_of(r)
                        rec = {"record": "e2e", "mesh": mesh, "method": method, "fraction": frac,
                               "params": params, "library_time_s": r["time_s"]}
                        try:
                            times, result, t0 = [], None, time.perf_counter()
                            while len(times) < args.repeat:
                                if times and time.perf_counter() - t0 + times[-1] / 1e3 > args.budget:
                                    break
                                job = client.submit("simplify", params, arrays)
                                result, _ = job.result()
                                times.append(job.elapsed_ms)
                            med = statistics.median(times)
                            lib_v = r.get("report_output_vertices")
                            rec.update({
                                "elapsed_ms": times, "e2e_ms": med, "repeats": len(times),
                                "ratio": med / (r["time_s"] * 1e3),
                                "mtris_per_s": e["input_triangles"] / med / 1e3,
                                "out_vertices": result.get("output_vertices"),
                                "same_count": result.get("output_vertices") == lib_v,
                            })
                            print(f"   {method:<25} {frac * 100:>5g}% daemon {med:9.1f} ms x{len(times)}  "
                                  f"library {r['time_s'] * 1e3:9.1f} ms  ratio {rec['ratio']:.2f}"
                                  + ("" if rec["same_count"] else
                                     f"  OUTPUT COUNT DIFFERS ({rec['out_vertices']} vs {lib_v})"),
                                  file=sys.stderr)
                        except Exception as ex:  # noqa: BLE001 - record and go on
                            rec["error"] = f"{type(ex).__name__}: {ex}"[:500]
                            print(f"   {method} {frac}: FAILED {rec['error']}", file=sys.stderr)
                        out_f.write(json.dumps(rec) + "\n")
                        out_f.flush()
                    del arrays, pos, faces
        finally:
            stop_daemon(sock)
    print(f"e2e done in {time.perf_counter() - t_all:.1f} s", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["run"])
    ap.add_argument("--manifest", default="bench/results/simplify_inputs.json")
    ap.add_argument("--jsonl", default="bench/results/simplify_raw.jsonl")
    ap.add_argument("--harness", default="target/release/bench-simplify")
    ap.add_argument("--tessd", default="target/release/tessd")
    ap.add_argument("--work", default=None)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--budget", type=float, default=12.0)
    ap.add_argument("--meshes", default=None)
    ap.add_argument("--fractions", default=None, help="default: every target of the harness")
    run(ap.parse_args())


if __name__ == "__main__":
    main()
