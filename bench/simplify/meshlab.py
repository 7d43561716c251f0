#!/usr/bin/env python3
"""MeshLab's vertex clustering (pymeshlab) in the simplification benchmark.

    meshlab.py run --manifest bench/results/simplify_inputs.json \
        --jsonl bench/results/simplify_raw.jsonl --harness target/release/bench-simplify \
        [--work /tmp/tessd-bench-simplify] [--repeat 3] [--budget 12] [--meshes a,b]
        [--max-output-vertices 1.5e6] [--max-input-triangles 2e7]
    meshlab.py one INPUT THRESHOLD OUT.ply   (child: one timed run, prints JSON)

For every input of the manifest written by `bench-simplify run` and every target vertex count
in it, `run` finds the absolute cell size (`threshold`) of `meshing_decimation_clustering`
that lands at the target (untimed, bisection on a loaded mesh), then times the filter alone in
fresh child processes (`one`: load, release freed heap, reset the peak RSS, run the filter,
read VmHWM; median of `--repeat` processes), saves the output and measures it against the
input with `bench-simplify compare` (the same tessd-compare options as every other method).
One JSON line per (mesh, target) is appended to the jsonl. Targets above
`--max-output-vertices` are skipped (and say so): MeshLab's clustering is superlinear in its
output size (measured: 36 s at 0.5 M and 362 s at 2.1 M output vertices from the 10 M torus).
Inputs above `--max-input-triangles` (the 50 M torus) are skipped too: its time grows as about
size^1.56 (0.1 M → 10 M tori at 10 %), ~200 s a call at 50 M, ~10 min with the search.

Run with /work/main/.venv-bench/bin/python.
"""

import argparse
import ctypes
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pymeshlab as pm

METHOD = "meshlab-clustering"


def status_kib(key):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    return 0


def reset_peak():
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except OSError:
        pass
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def referenced(mesh):
    f = mesh.face_matrix()
    return int(np.unique(f).size) if f.size else 0


def write_ply(path, vertices, faces):
    """Binary little-endian PLY with float positions and int triangles."""
    vertices = np.ascontiguousarray(vertices, dtype="<f4")
    faces = np.asarray(faces, dtype="<i4")
    rec = np.empty(len(faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    rec["n"] = 3
    rec["v"] = faces
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vertices.tobytes())
        f.write(rec.tobytes())


def one(argv):
    """Child: load, reset the peak, time the filter once, save, print JSON."""
    path, threshold, out = argv[0], float(argv[1]), argv[2]
    rss_start = status_kib("VmRSS")
    ms = pm.MeshSet()
    ms.load_new_mesh(path)
    m = ms.current_mesh()
    in_vertices, in_faces = m.vertex_number(), m.face_number()
    hwm_load = status_kib("VmHWM")
    reset_ok = reset_peak()
    rss_before = status_kib("VmRSS")
    t = time.perf_counter()
    ms.meshing_decimation_clustering(threshold=pm.PureValue(threshold))
    dt = time.perf_counter() - t
    hwm_run = status_kib("VmHWM")
    c = ms.current_mesh()
    out_vertices = referenced(c)
    if out:
        write_ply(out, c.vertex_matrix(), c.face_matrix())
    print(
        json.dumps(
            {
                "time_s": dt,
                "out_vertices": out_vertices,
                "out_faces": c.face_number(),
                "meshlab_input_vertices": in_vertices,
                "meshlab_input_faces": in_faces,
                "rss_start_kib": rss_start,
                "hwm_load_kib": hwm_load,
                "rss_before_run_kib": rss_before,
                "hwm_run_kib": hwm_run,
                "peak_reset_ok": reset_ok,
            }
        )
    )


def tolerance(target):
    return max(0.01 * target, 0.5)


def find(target, p0, slope, lo, hi, f, max_evals=40, deadline_s=120.0):
    """Same search as bench/simplify/src/search.rs: log-log steps, then bracketed secant."""
    tol = tolerance(target)
    lt = math.log(target)
    inc = slope > 0
    best = None
    a = b = last = prev = None
    tried = []
    p = min(max(p0, lo), hi)
    evals = 0
    t0 = time.perf_counter()
    while True:
        c = f(p)
        evals += 1
        tried.append(p)
        err = abs(c - target)
        if best is None or err < abs(best[1] - target):
            best = (p, c)
        if err <= tol or evals >= max_evals or time.perf_counter() - t0 > deadline_s:
            break
        pt = (math.log(p), math.log(max(c, 0.5)))
        need_larger = (c < target) == inc
        if need_larger:
            a = pt
        else:
            b = pt
        prev, last = last, pt
        if a and b:
            w = b[0] - a[0]
            x = a[0] + (lt - a[1]) * w / (b[1] - a[1]) if abs(b[1] - a[1]) > 1e-12 else a[0] + 0.5 * w
            x = min(max(x, a[0] + 0.1 * w), b[0] - 0.1 * w)
        else:
            k = slope
            if prev and abs(last[0] - prev[0]) > 1e-12:
                kk = (last[1] - prev[1]) / (last[0] - prev[0])
                if kk * slope > 0:
                    k = kk
            step = min(max((lt - pt[1]) / k, -math.log(16)), math.log(16))
            step = max(step, 0.01) if need_larger else min(step, -0.01)
            x = pt[0] + step
        np_ = min(max(math.exp(x), lo), hi)
        if np_ in tried or (a and b and not (a[0] < math.log(np_) < b[0])) or (a and b and b[0] - a[0] < 1e-9):
            break
        p = np_
    return best[0], best[1], evals, abs(best[1] - target) <= tol


def run(args):
    manifest = json.loads(Path(args.manifest).read_text())
    work = Path(args.work or manifest["meta"].get("work", "/tmp/tessd-bench-simplify"))
    (work / "outputs").mkdir(parents=True, exist_ok=True)
    only = set(args.meshes.split(",")) if args.meshes else None
    # tessd-grid's cell size at the same target: MeshLab clusters on a grid of cubic cells of
    # side `threshold` too, so it is a close first guess (MeshLab's calls are slow).
    grid_cell = {}
    if Path(args.jsonl).exists():
        for line in open(args.jsonl):
            r = json.loads(line)
            if r.get("method") == "tessd-grid-bary" and "param" in r:
                grid_cell[(r["mesh"], r["fraction"])] = r["param"]
    t_all = time.perf_counter()
    with open(args.jsonl, "a") as out_f:
        for entry in manifest["meshes"]:
            name, path = entry["mesh"], entry["path"]
            if only and name not in only:
                continue
            t_mesh = time.perf_counter()
            if entry["input_triangles"] > args.max_input_triangles:
                for t in entry["targets"]:
                    out_f.write(json.dumps({
                        "mesh": name, "generated": entry["generated"], "method": METHOD, "family": "meshlab",
                        "fraction": t["fraction"], "target_vertices": t["target"],
                        "input_vertices": entry["input_vertices"], "input_triangles": entry["input_triangles"],
                        "input_faces": entry["input_faces"], "input_bytes": entry["input_bytes"],
                        "param_name": "threshold",
                        "skipped": (f"input of {entry['input_triangles'] / 1e6:.3g} M triangles is above "
                                    f"{args.max_input_triangles / 1e6:g} M: MeshLab's clustering grows as about "
                                    "size^1.56 (16.6 s a call on the 10 M torus at 10 %), "
                                    f"~{16.6 * (entry['input_triangles'] / 1e7) ** 1.56:.0f} s a call here, "
                                    "beyond the run's budget"),
                    }) + "\n")
                out_f.flush()
                print(f"== {name}: skipped (MeshLab, {entry['input_triangles']} triangles)", file=sys.stderr)
                continue
            ms = pm.MeshSet()
            try:
                ms.load_new_mesh(path)
            except Exception as e:  # noqa: BLE001 - report and go on
                print(f"skipping {name}: {e}", file=sys.stderr)
                continue
            print(f"== {name} (meshlab: {ms.current_mesh().vertex_number()} vertices, "
                  f"{ms.current_mesh().face_number()} faces)", file=sys.stderr)

            def count(th):
                ms.set_current_mesh(0)
                ms.generate_copy_of_current_mesh()
                ms.meshing_decimation_clustering(threshold=pm.PureValue(th))
                n = referenced(ms.current_mesh())
                ms.delete_current_mesh()
                return n

            for t in entry["targets"]:
                frac, target = t["fraction"], t["target"]
                rec = {
                    "mesh": name,
                    "generated": entry["generated"],
                    "method": METHOD,
                    "family": "meshlab",
                    "fraction": frac,
                    "target_vertices": target,
                    "input_vertices": entry["input_vertices"],
                    "input_triangles": entry["input_triangles"],
                    "input_faces": entry["input_faces"],
                    "input_bytes": entry["input_bytes"],
                    "param_name": "threshold",
                }
                skip = None
                if target < 4 or target >= entry["input_vertices"]:
                    skip = f"target of {target} vertices is outside 4..{entry['input_vertices']}"
                elif target > args.max_output_vertices:
                    skip = (f"target of {target} vertices is above {args.max_output_vertices:g}: MeshLab's "
                            "clustering slows down superlinearly with output size (362 s for one call at "
                            "2.1 M output vertices from the 10 M torus), beyond the run's budget")
                if skip:
                    rec["skipped"] = skip
                    out_f.write(json.dumps(rec) + "\n")
                    out_f.flush()
                    continue
                try:
                    ts = time.perf_counter()
                    p0 = grid_cell.get((name, frac)) or math.sqrt(1.5 * entry["area"] / target)
                    size = entry["size"]
                    param, found, evals, hit = find(target, p0, -2.0, size * 1e-6, size * 2.0, count)
                    rec.update(param=param, search_evals=evals, search_s=time.perf_counter() - ts,
                               search_count=found, search_hit=hit, cells_per_axis=size / param)
                    pct = f"{frac * 100:g}"
                    out = work / "outputs" / f"{name}__{METHOD}__{pct}.ply"
                    runs = []
                    t_timed = time.perf_counter()
                    for k in range(max(args.repeat, 1)):
                        if runs and time.perf_counter() - t_timed + runs[-1]["time_s"] > args.budget:
                            break
                        cp = subprocess.run(
                            [sys.executable, __file__, "one", path, repr(param), str(out) if k == 0 else ""],
                            capture_output=True, text=True, check=True)
                        runs.append(json.loads(cp.stdout.strip().splitlines()[-1]))
                    times = [r["time_s"] for r in runs]
                    first = runs[0]
                    med = statistics.median(times)
                    extra = max(r["hwm_run_kib"] - r["rss_before_run_kib"] for r in runs) * 1024
                    ov = first["out_vertices"]
                    rec.update(
                        times_s=times, time_s=med, repeats=len(times),
                        mtris_per_s=entry["input_triangles"] / med / 1e6,
                        out_vertices=ov, out_faces=first["out_faces"], out_triangles=first["out_faces"],
                        meshlab_input_vertices=first["meshlab_input_vertices"],
                        meshlab_input_faces=first["meshlab_input_faces"],
                        rss_start_kib=first["rss_start_kib"], hwm_load_kib=first["hwm_load_kib"],
                        rss_before_run_kib=first["rss_before_run_kib"], hwm_run_kib=first["hwm_run_kib"],
                        peak_reset_ok=first["peak_reset_ok"], extra_peak_bytes=extra,
                        mem_ratio=extra / entry["input_bytes"],
                        process_hwm_kib=max(max(r["hwm_load_kib"], r["hwm_run_kib"]) for r in runs),
                        deviation=(ov - target) / target, hit=abs(ov - target) <= tolerance(target),
                        threads="1", output_path=str(out),
                    )
                    cp = subprocess.run(
                        [args.harness, "compare", str(out), path, "--samples", str(entry["face_samples"])],
                        capture_output=True, text=True)
                    if cp.returncode == 0:
                        cmp = json.loads(cp.stdout.strip().splitlines()[-1])
                        cmp.pop("out_vertices", None)
                        cmp.pop("out_faces", None)
                        rec.update(cmp)
                    else:
                        rec["compare_error"] = cp.stderr.strip()[-500:]
                    print(f"   {METHOD:<25} {pct:>5}% target {target:>8} got {ov:>8} ({evals} evals, "
                          f"{rec['search_s']:.1f} s search) {med * 1e3:9.2f} ms x{len(times)} "
                          f"{rec['mtris_per_s']:7.2f} Mtri/s mem {rec['mem_ratio']:.2f}x  "
                          f"H {rec.get('hausdorff', float('nan')):.3e} RMS {rec.get('rms', float('nan')):.3e}",
                          file=sys.stderr)
                except Exception as e:  # noqa: BLE001 - record and go on
                    rec["error"] = str(e)[-500:]
                    print(f"   {METHOD} {target}: FAILED {e}", file=sys.stderr)
                out_f.write(json.dumps(rec) + "\n")
                out_f.flush()
            print(f"   {name} done in {time.perf_counter() - t_mesh:.1f} s", file=sys.stderr)
    print(f"meshlab done in {time.perf_counter() - t_all:.1f} s", file=sys.stderr)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "one":
        return one(sys.argv[2:])
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cmd", choices=["run"])
    ap.add_argument("--manifest", default="bench/results/simplify_inputs.json")
    ap.add_argument("--jsonl", default="bench/results/simplify_raw.jsonl")
    ap.add_argument("--harness", default="target/release/bench-simplify")
    ap.add_argument("--work", default=None)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--budget", type=float, default=12.0)
    ap.add_argument("--meshes", default=None)
    ap.add_argument("--max-output-vertices", type=float, default=1.5e6)
    ap.add_argument("--max-input-triangles", type=float, default=2e7)
    run(ap.parse_args())


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
