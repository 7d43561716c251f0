"""Speed of `tessd-compare` beside MeshLab's Hausdorff filter on large meshes.

    .venv-bench/bin/python bench/compare/bench_speed.py [--levels 2] [--meshlab-samples N]

Makes (once, into bench/out/compare/) the Stanford bunny refined by `--levels` Loop subdivision
steps (2 → 1.11 M triangles, 3 → 4.4 M) and a MeshLab quadric decimation of it to 10 %, then
times, on the same two PLY files:

* ours (`compare_json`, release build, all cores) with the default sample count (10 per
  triangle of the larger mesh, capped at 20 M) and with exactly `--meshlab-samples` face samples;
* MeshLab (`get_hausdorff_distance`, single-threaded) with `--meshlab-samples` face samples.

Every run also samples every vertex. Ours is reported as the best of `--repeat` runs, split
into index build and sampling + queries. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pymeshlab

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests"))
from locate import shared_data  # noqa: E402

OUT = REPO / "bench" / "out" / "compare"
SAVE = dict(binary=True, save_vertex_normal=False, save_vertex_color=False,
            save_vertex_quality=False, save_face_color=False, save_face_quality=False)


def make_meshes(levels: int) -> tuple[Path, Path]:
    OUT.mkdir(parents=True, exist_ok=True)
    a = OUT / f"bunny_loop{levels}.ply"
    b = OUT / f"bunny_loop{levels}_q10.ply"
    if not (a.exists() and b.exists()):
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(shared_data() / "mesh" / "bun_zipper.ply"))
        ms.meshing_remove_unreferenced_vertices()
        ms.meshing_surface_subdivision_loop(iterations=levels,
                                            threshold=pymeshlab.PercentageValue(0))
        ms.save_current_mesh(str(a), **SAVE)
        ms.meshing_decimation_quadric_edge_collapse(targetperc=0.1)
        ms.meshing_remove_unreferenced_vertices()
        ms.save_current_mesh(str(b), **SAVE)
    return a, b


def ours(binary: Path, a: Path, b: Path, samples: int | None, repeat: int) -> dict:
    best = None
    for _ in range(repeat):
        cmd = [str(binary), str(a), str(b)] + (["--samples", str(samples)] if samples else [])
        r = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        total = r["time_s"]["a_to_b"] + r["time_s"]["b_to_a"]
        if best is None or total < best[0]:
            best = (total, r)
    return best[1]


def meshlab(a: Path, b: Path, samples: int) -> dict:
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(a))
    ms.load_new_mesh(str(b))
    diag = ms.mesh(0).bounding_box().diagonal()
    out = {}
    for key, (s, t) in {"a_to_b": (0, 1), "b_to_a": (1, 0)}.items():
        t0 = time.perf_counter()
        r = ms.get_hausdorff_distance(sampledmesh=s, targetmesh=t, samplevert=True,
                                      sampleface=True, samplenum=samples,
                                      maxdist=pymeshlab.PureValue(4 * diag))
        r["time_s"] = time.perf_counter() - t0
        out[key] = r
    out["faces"] = (ms.mesh(0).face_number(), ms.mesh(1).face_number())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", type=int, default=2)
    ap.add_argument("--meshlab-samples", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-meshlab", action="store_true")
    args = ap.parse_args()

    subprocess.run(["cargo", "build", "--release", "-q", "-p", "tessd-compare", "--example",
                    "compare_json"], cwd=REPO, check=True)
    binary = REPO / "target" / "release" / "examples" / "compare_json"
    a, b = make_meshes(args.levels)
    runs = [("ours, default samples", ours(binary, a, b, None, args.repeat)),
            (f"ours, {args.meshlab_samples} samples",
             ours(binary, a, b, args.meshlab_samples, args.repeat))]
    ml = None if args.no_meshlab else meshlab(a, b, args.meshlab_samples)

    r0 = runs[0][1]
    print(f"\nA = {a.name} ({r0['triangles_a']} triangles), "
          f"B = {b.name} ({r0['triangles_b']} triangles); "
          f"ours on {r0['threads']} threads, MeshLab on 1; {os.cpu_count()} CPUs\n")
    print("| tool | direction | samples | index (s) | sampling+queries (s) | total (s) "
          "| samples/s | max | RMS |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for name, r in runs:
        for key in ("a_to_b", "b_to_a"):
            t = r["time_s"]
            total = t[key]
            d = r[key]
            print(f"| {name} | {key} | {d['samples']:,} | {t[key + '_index']:.2f} | "
                  f"{t[key + '_sampling']:.2f} | {total:.2f} | "
                  f"{d['samples'] / total / 1e6:.2f} M | {d['max']:.4g} | {d['rms']:.4g} |")
    if ml:
        for key in ("a_to_b", "b_to_a"):
            m = ml[key]
            print(f"| MeshLab, {args.meshlab_samples} samples | {key} | {m['n_samples']:,} | – "
                  f"| – | {m['time_s']:.2f} | {m['n_samples'] / m['time_s'] / 1e6:.2f} M "
                  f"| {m['max']:.4g} | {m['RMS']:.4g} |")


if __name__ == "__main__":
    main()
