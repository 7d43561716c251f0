#!/usr/bin/env python3
"""Stores a tessd binary's bit budget and one-core speed as the "before" column of issue 34's
budget table (bench/results/codec_budget_before.json), so that run_codec.py's report can print it
beside the run's own figures after the format changes (a version-2 reader refuses v1 files, so
the v1 figures cannot be measured again later without the old binary).

    budget_before.py TESSD_BIN [--data DIR] [--torus PLY] [--repeats 3] [--out JSON]

Per shared mesh at 12 bits: `tessd compress --json` with the binary's defaults (and with one
nSP-cell, `--min-cell 1000000000`), bytes, bits/vertex, bits/vertex per code family (ideal code
lengths under the file's own tables), and the v1 header's table and index sizes (bytes 80..112
of a v1 header; absent for later versions). Then the one-core user time (RAYON_NUM_THREADS=1,
GNU time %U, median of --repeats) of compress at 12 and 16 bits and decompress of both files
on the ~1.1 M-triangle torus.
"""

import argparse
import json
import os
import statistics
import struct
import subprocess
import sys
from pathlib import Path

ONE_CELL = "1000000000"
MESH_EXT = (".obj", ".ply", ".off", ".stl")


def compress(binary, mesh, out, *args):
    r = subprocess.run([binary, "compress", str(mesh), str(out), "--bits", "12", *args, "--json"],
                       capture_output=True, text=True, check=True)
    js = json.loads(r.stdout)
    row = {k: js.get(k) for k in ("bytes", "bits_per_vertex", "bits_per_vertex_by_family", "nsp_cells",
                                  "input_vertices", "input_triangles", "vertices", "triangles")}
    head = Path(out).read_bytes()[:128]
    version = struct.unpack_from("<H", head, 4)[0]
    row["format_version"] = version
    if version == 1:
        _, tables_len, _, index_len = struct.unpack_from("<4Q", head, 80)
        row.update(header_bytes=128, tables_bytes=tables_len, index_bytes=index_len)
    return row


def user_time(argv):
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    r = subprocess.run(["/usr/bin/time", "-f", "%U", *map(str, argv)], capture_output=True, text=True, env=env,
                       check=True)
    return float(r.stderr.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("binary")
    ap.add_argument("--data", default=os.environ.get("TESSD_SHARED_DATA", "/work/shared/data"))
    ap.add_argument("--torus", required=True, help="the ~1.1 M-triangle torus (bench-simplify gen 1100000)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--work", default="/tmp/tessd-budget-before")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "results" / "codec_budget_before.json"))
    ap.add_argument("--label", default="")
    a = ap.parse_args()
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    meshes = {}
    for m in sorted(p for p in Path(a.data, "mesh").iterdir() if p.suffix.lower() in MESH_EXT):
        meshes[m.stem] = {"default": compress(a.binary, m, work / f"{m.stem}.tsc"),
                          "one_cell": compress(a.binary, m, work / f"{m.stem}_1.tsc", "--min-cell", ONE_CELL)}
        d = meshes[m.stem]["default"]
        print(f"{m.stem}: {d['bytes']} B, {d['bits_per_vertex']:.3f} b/v, {d['nsp_cells']} cells; one cell "
              f"{meshes[m.stem]['one_cell']['bits_per_vertex']:.3f} b/v", file=sys.stderr)
    speed = {}
    if a.torus and Path(a.torus).is_file():
        torus = compress(a.binary, a.torus, work / "torus12.tsc")
        tris = torus["input_triangles"]
        runs = {k: [] for k in ("compress_12", "compress_16", "decompress_12", "decompress_16")}
        for _ in range(a.repeats):  # interleaved, so a busy spell spreads over every figure
            for bits in (12, 16):
                runs[f"compress_{bits}"].append(user_time(
                    [a.binary, "compress", a.torus, work / f"torus{bits}.tsc", "--bits", bits]))
                runs[f"decompress_{bits}"].append(user_time(
                    [a.binary, "decompress", work / f"torus{bits}.tsc", work / f"torus{bits}.ply"]))
        for k, v in runs.items():
            u = statistics.median(v)
            speed[k] = {"user_s": v, "median_user_s": u, "mtri_per_s": tris / u / 1e6}
            print(f"torus {k}: user {v} s, median {u:.2f} s, {tris / u / 1e6:.3f} M tri/s", file=sys.stderr)
        speed["mesh"] = a.torus
        speed["triangles"] = tris
        speed["bytes_12"] = torus["bytes"]
    out = {"binary": a.binary, "label": a.label, "bits": 12, "one_cell_args": ["--min-cell", ONE_CELL],
           "family_bits": "ideal code lengths under the file's own per-context static tables (v1)",
           "meshes": meshes, "speed_one_core": speed}
    Path(a.out).write_text(json.dumps(out, indent=1) + "\n")
    print(a.out, file=sys.stderr)


if __name__ == "__main__":
    main()
