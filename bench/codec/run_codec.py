#!/usr/bin/env python3
"""Codec benchmark: `tessd compress` / `tessd decompress` (core/codec, the Gandoin–Devillers
kd-tree coder in an nSP-tree, paper 003) vs Draco (levels 10 and 7) and meshoptimizer's codecs
(raw, + zstd), on every mesh of $TESSD_SHARED_DATA/mesh at p = 12 and 16 bits per coordinate.

    run_codec.py run [--data DIR] [--meshes NAME,...] [--bits 12,16] [--work DIR]
                     [--jsonl bench/results/codec_raw.jsonl] [--out bench/results]
                     [--tessd-args "--cell-split 4 --min-cell 50000 --root-bits 7"]
                     [--rd-mesh stanford_bunny] [--rd-bits 12] [--budget 1.0] [--peers-only]
    run_codec.py rd --tsc FILE.tsc --mesh ORIGINAL [--bits P] [--min-bits 4]
                    [--draco-bits 4-16] [--csv OUT.csv] [--png OUT.png] [--jsonl ...]
    run_codec.py report [--jsonl bench/results/codec_raw.jsonl] [--out bench/results]

The tessd binary is $TESSD_BIN (default target/release/tessd); `run` requires it. `--peers-only`
is for developing the peer side before the codec exists: it writes a "tessd binary not built
yet" row instead of the tessd rows and marks the report as incomplete.

`run`, per mesh and p:
  * the peers (bench/codec/peers.py, one child process each: bytes, bits/vertex, encode /
    decode medians, decoded error, lossless check, peak RSS);
  * tessd: `tessd compress IN OUT.tsc --bits P <tessd-args> --json` and `tessd decompress
    OUT.tsc OUT.ply --json`, each in child processes (median of the CLI's own `elapsed_ms`
    and of the wall time over repeats within --budget; peak RSS from GNU time), the file size
    checked against `bytes`; then the lossless hook: OUT.ply is loaded and its quantised
    positions (grid: the compress JSON's `origin` / `step` when it prints them, else the
    convention of peers.py, the same as core/codec/src/quantize.rs) compared with the quantised
    input's, and its oriented triangles with the input's (for meshes with polygons the input's
    triangles are a fan triangulation, so that comparison is only indicative there);
  * for --rd-mesh at --rd-bits, the rate-distortion curves (the `rd` command).

`rd`: decodes FILE.tsc with `tessd decompress --max-bits B` for B = min-bits..p and measures, for
each output, `bytes_read` against the distance to the original (unquantised) mesh; Draco
(level 10, its own quantisation of the float positions) at each of --draco-bits gives its own
curve. Distances are sampled point-to-surface, both ways (peers.surface_distance: 100 000
area-weighted samples plus the vertices on each side, exact point-to-triangle distance to the
other mesh): Hausdorff = the larger max, RMS over both sample sets; relative to the largest
side of the original's bounding box. An output without triangles is measured as points.
Writes a CSV and, with matplotlib, a PNG (log-log: bits per input vertex vs distance).

`report`: bench/results/codec.md from the JSON lines (a table like the paper's Table 2, times,
memory, checks, the rate-distortion summary), and codec_rd.csv / codec_rd.png from its "rd" lines
(`run` ends with it).

Run with /work/main/.venv-bench/bin/python (numpy, scipy, DracoPy, meshopt,
zstandard, matplotlib: bench/requirements-bench.txt).
"""

import argparse
import csv
import datetime
import json
import math
import os
import shlex
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
import numpy as np  # noqa: E402

import peers  # noqa: E402
from report_common import machine  # noqa: E402

DEFAULT_TESSD_ARGS = "--cell-split 4 --min-cell 50000 --root-bits 7"
MESH_EXT = (".obj", ".ply", ".off", ".stl")
NOT_BUILT = "tessd binary not built yet"


def tessd_bin(arg=None):
    return Path(arg or os.environ.get("TESSD_BIN") or ROOT / "target" / "release" / "tessd")


def parse_json_stdout(out):
    """The JSON object a `--json` CLI printed (the last line that parses as an object)."""
    for line in reversed(out.strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except json.JSONDecodeError:
                pass
    try:
        obj = json.loads(out)
        if isinstance(obj, dict):
            return obj
    except json.JSONDecodeError:
        pass
    raise ValueError(f"no JSON object on stdout: {out.strip()[-500:]!r}")


def run_cli(argv, budget, min_repeat=1, max_repeat=9, timeout=900):
    """Runs a `--json` CLI command repeatedly (each a child process) until `budget` seconds,
    at least `min_repeat` times; returns (last JSON, list of per-run dicts: elapsed_ms, wall_ms,
    peak_rss_kib)."""
    runs = []
    t0 = time.perf_counter()
    js = None
    while len(runs) < max_repeat:
        rc, out, err, rss, wall = peers.run_child_rss([str(a) for a in argv], timeout)
        if rc != 0:
            raise RuntimeError(f"`{shlex.join(map(str, argv))}` exited {rc}: {(err or out).strip()[-1500:]}")
        js = parse_json_stdout(out)
        runs.append({"elapsed_ms": js.get("elapsed_ms"), "wall_ms": 1e3 * wall, "peak_rss_kib": rss})
        if len(runs) >= min_repeat and time.perf_counter() - t0 >= budget:
            break
    return js, runs


def med(runs, key):
    vals = [r[key] for r in runs if r.get(key) is not None]
    return statistics.median(vals) if vals else None


def grid_from_json(js, verts, bits):
    """The grid the codec used, when its JSON says (origin + step / cell_size), else ours."""
    origin = js.get("origin")
    step = js.get("step", js.get("cell_size", js.get("scale")))
    if origin is not None and step is not None:
        return peers.Grid(verts, bits, origin=origin, step=step), "tessd JSON"
    return peers.Grid(verts, bits), "peers.py convention"


def tessd_rows(path, bits, binary, work, tessd_args, budget):
    """The tessd row of one mesh at p bits (or an error row)."""
    verts, tris, nfaces = peers.load_mesh(path)
    grid = peers.Grid(verts, bits)
    info, sets = peers.mesh_info(path, verts, tris, nfaces, grid)
    row = dict(info, tool="tessd", variant="tessd", tessd_args=tessd_args, binary=str(binary),
               polygons=nfaces != len(tris))
    stem = f"{Path(path).stem}_p{bits}"
    tsc = Path(work) / f"{stem}.tsc"
    ply = Path(work) / f"{stem}.ply"
    try:
        cjs, cruns = run_cli([binary, "compress", path, tsc, "--bits", bits, *shlex.split(tessd_args), "--json"],
                             budget, min_repeat=3)
        size = tsc.stat().st_size
        djs, druns = run_cli([binary, "decompress", tsc, ply, "--json"], budget, min_repeat=3)
    except Exception as e:  # noqa: BLE001 — recorded in the row and in the report
        row["error"] = str(e)
        return [row]
    row.update({
        "bytes": size, "bits_per_vertex": 8.0 * size / max(1, len(verts)),
        "bits_per_referenced_vertex": 8.0 * size / max(1, info["referenced_vertices"]),
        "compress_json": cjs, "decompress_json": djs,
        "bytes_matches_json": cjs.get("bytes") == size,
        "encode_ms": med(cruns, "elapsed_ms"), "decode_ms": med(druns, "elapsed_ms"),
        "encode_wall_ms": med(cruns, "wall_ms"), "decode_wall_ms": med(druns, "wall_ms"),
        "encode_repeats": len(cruns), "decode_repeats": len(druns),
        "peak_rss_kib": max(r["peak_rss_kib"] for r in cruns),
        "decode_peak_rss_kib": max(r["peak_rss_kib"] for r in druns),
        "nsp_cells": cjs.get("nsp_cells"), "bytes_read": djs.get("bytes_read"),
        "decoded_vertices": djs.get("vertices"), "decoded_triangles": djs.get("triangles"),
        # tessd's own counts vs ours (unique quantised points / oriented triangles)
        "counts_match": {
            "input_vertices": cjs.get("input_vertices") == len(verts),
            "input_triangles": cjs.get("input_triangles") == len(tris),
            "vertices": cjs.get("vertices") in (info["unique_quantised_vertices"], info["unique_quantised_referenced"]),
            "triangles": cjs.get("triangles") == info["unique_quantised_triangles"],
        },
    })
    try:
        dv, dt, _ = peers.load_mesh(str(ply))
        cgrid, source = grid_from_json(cjs, verts, bits)
        if source != "peers.py convention":
            _, sets = peers.quantised_summary(verts, tris, cgrid)
        row["check_grid"] = source
        row.update(peers.lossless_check(sets, dv, dt, cgrid))
        if nfaces != len(tris):
            # polygons: our fan triangulation need not be tessd's; check up to triangulation
            _, polys = peers.load_polygons(path)
            row.update(peers.polygon_triangle_check(verts, polys, cgrid, dv, dt))
            row["lossless"] = bool((row["positions_equal_referenced"] or row["positions_equal_all"])
                                   and row["triangles_equal_up_to_triangulation"]
                                   and row["max_offgrid_steps"] < peers.OFFGRID_TOL)
        row.update(peers.vertex_error(verts, tris, dv, cgrid))
        row["ply_vertices"] = int(len(dv))
        row["ply_triangles"] = int(len(dt))
    except Exception as e:  # noqa: BLE001
        row["error"] = f"lossless check of {ply}: {type(e).__name__}: {e}"
    return [row]


# ---------------------------------------------------------------------------------------------
# Rate-distortion


def parse_bits(spec):
    out = []
    for part in str(spec).split(","):
        if "-" in part:
            a, b = part.split("-")
            out.extend(range(int(a), int(b) + 1))
        elif part:
            out.append(int(part))
    return out


def rd_rows(tsc, mesh, bits, binary, min_bits=4, draco_bits=None, samples=100000, work=None, tool="tessd",
            draco=True):
    """Rate-distortion rows: tessd at --max-bits B = min_bits..bits (labelled `tool`), Draco-10 at
    draco_bits (unless `draco` is false)."""
    import DracoPy

    verts, tris, _ = peers.load_mesh(mesh)
    grid = peers.Grid(verts, bits)
    side = grid.side if grid.side > 0 else 1.0
    nv = len(verts)
    name = Path(mesh).stem
    work = Path(work or Path(tsc).parent)
    rows = []
    if tsc is not None:
        for b in range(min_bits, bits + 1):
            out = work / f"{Path(tsc).stem}_rd{b}.ply"
            rc, so, se, rss, wall = peers.run_child_rss(
                [str(binary), "decompress", str(tsc), str(out), "--max-bits", str(b), "--json"], 900)
            row = {"record": "rd", "mesh": name, "p": bits, "tool": tool, "max_bits": b, "input_vertices": nv}
            if rc != 0:
                row["error"] = (se or so).strip()[-1500:]
                rows.append(row)
                continue
            js = parse_json_stdout(so)
            dv, dt, _ = peers.load_mesh(str(out))
            d = peers.surface_distance(verts, tris, dv, dt, samples)
            row.update({"bytes": js.get("bytes_read"), "decoded_vertices": len(dv), "decoded_triangles": len(dt),
                        "decode_ms": js.get("elapsed_ms"), "decode_wall_ms": 1e3 * wall, **d})
            rows.append(row)
    pts = np.ascontiguousarray(verts, dtype=np.float32)
    faces = np.ascontiguousarray(tris, dtype=np.uint32)
    for q in (draco_bits or range(min_bits, bits + 1)) if draco else ():
        buf = DracoPy.encode(pts, faces, quantization_bits=q, compression_level=10,
                             quantization_range=float(grid.side) if grid.side > 0 else -1,
                             quantization_origin=[float(x) for x in grid.origin])
        dec = DracoPy.decode(buf)
        dv = np.asarray(dec.points, dtype=np.float64).reshape(-1, 3)
        dt = np.asarray(dec.faces, dtype=np.int64).reshape(-1, 3)
        d = peers.surface_distance(verts, tris, dv, dt, samples)
        rows.append({"record": "rd", "mesh": name, "p": bits, "tool": "draco-10", "quantization_bits": q,
                     "input_vertices": nv, "bytes": len(buf), "decoded_vertices": len(dv),
                     "decoded_triangles": len(dt), **d})
    for r in rows:
        if r.get("bytes") is not None:
            r["bits_per_vertex"] = 8.0 * r["bytes"] / max(1, nv)
        for k in ("hausdorff", "rms"):
            if k in r:
                r[k + "_rel"] = r[k] / side
        r["largest_side"] = grid.side
        r["distance"] = "sampled point-to-surface, both ways"
    return rows


RD_FIELDS = ["mesh", "p", "tool", "max_bits", "quantization_bits", "bytes", "bits_per_vertex", "hausdorff",
             "rms", "hausdorff_rel", "rms_rel", "max_fwd", "rms_fwd", "max_bwd", "rms_bwd",
             "decoded_vertices", "decoded_triangles", "decoded_has_surface", "error"]


def write_rd(rows, csv_path=None, png_path=None):
    if csv_path:
        with open(csv_path, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=RD_FIELDS, extrasaction="ignore")
            w.writeheader()
            for r in rows:
                w.writerow(r)
    if not png_path:
        return
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker  # noqa: F401
    except ImportError:
        print("matplotlib missing: no rate-distortion plot (the CSV has the data)", file=sys.stderr)
        return
    good = [r for r in rows if "error" not in r and r.get("bytes")]
    meshes = sorted({r["mesh"] for r in good})
    fig, axes = plt.subplots(len(meshes) or 1, 2, figsize=(11, 4.2 * max(1, len(meshes))), squeeze=False)
    for mi, m in enumerate(meshes):
        for ai, (key, label) in enumerate((("hausdorff_rel", "Hausdorff"), ("rms_rel", "RMS"))):
            ax = axes[mi][ai]
            for tool, style, lab in (("tessd", "o-", "tessd decompress --max-bits B"),
                                     ("tessd-ahead2", "^-", "tessd --ahead 2 (§6.4), --max-bits B"),
                                     ("draco-10", "s--", "Draco level 10, quantisation q bits")):
                pts = sorted(((r["bits_per_vertex"], r[key], r.get("max_bits", r.get("quantization_bits")))
                              for r in good if r["mesh"] == m and r["tool"] == tool and r[key] > 0))
                if not pts:
                    continue
                ax.plot([p[0] for p in pts], [p[1] for p in pts], style, label=lab, ms=4)
                for x, y, b in pts:
                    ax.annotate(str(b), (x, y), textcoords="offset points", xytext=(3, 3), fontsize=7)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
            ax.xaxis.set_minor_locator(matplotlib.ticker.LogLocator(subs=(2.0, 5.0)))
            ax.xaxis.set_minor_formatter(matplotlib.ticker.ScalarFormatter())
            ax.set_xlabel("bits per input vertex (tessd: bytes_read)")
            ax.set_ylabel(f"{label} distance / largest bbox side")
            ax.set_title(f"{m}: {label} vs rate")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png_path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------
# Report

PAPER_T2 = {  # paper 003, Table 2 (bits per vertex), the models we have
    "bunny": {"vertices": 35947, "p": 12, "GD02": 17.8, "paper": 27.0},
}
TABLE_VARIANTS = ["tessd", "draco-10", "draco-7", "meshopt", "meshopt+zstd"]


def f2(x, nd=2):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return f"{x:.{nd}f}"


def fms(x):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return f"{x:.3g}" if x < 100 else f"{x:.0f}"


def tri_cell(r):
    if r.get("triangles_equal"):
        return "yes"
    if r.get("polygons"):
        ok = r.get("triangles_equal_up_to_triangulation")
        return (f"{'yes' if ok else '**no**'} up to triangulation ({r.get('triangles_in_input_polygons')} of "
                f"{r.get('decoded_unique_triangles')} in input polygons, {r.get('input_polygon_triangles')} expected)")
    return "**no**"


def report(jsonl, out, wall_s=None, command=None):
    rows = [json.loads(l) for l in open(jsonl) if l.strip()]
    meta = [r for r in rows if r.get("record") == "meta"]
    codec = [r for r in rows if r.get("record", "codec") == "codec" and "mesh" in r]
    rd = [r for r in rows if r.get("record") == "rd"]
    by = {}
    for r in codec:
        by[(r["mesh"], r["p"], r["variant"])] = r
    keys = sorted({(r["mesh"], r["p"]) for r in codec},
                  key=lambda k: (-max((r.get("input_vertices") or 0) for r in codec if r["mesh"] == k[0]), k[0], k[1]))
    tessd_missing = any(r.get("skipped") == NOT_BUILT for r in codec if r["tool"] == "tessd")
    errors = [r for r in codec if "error" in r]
    L = []
    L.append("# Codec benchmark: tessd (GD02 kd-tree coder in an nSP-tree) vs Draco vs meshoptimizer\n")
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    libs = sorted({r["library"] for r in codec if r.get("library")})
    L.append(f"Machine: {machine()}. Run {now}" + (f", whole run {wall_s / 60:.1f} min" if wall_s else "")
             + f". Command: `{command or 'bash bench/run_codec.sh'}`. Peers: {'; '.join(libs)}.\n")
    if meta:
        m = meta[-1]
        who = "not run" if m.get("peers_only") else f"`{m.get('binary')}` with `{m.get('tessd_args')}`"
        L.append(f"tessd: {who}; meshes from `{m.get('data')}`.\n")
    if tessd_missing:
        L.append(f"**Incomplete: {NOT_BUILT}** (the run used `--peers-only`): the tessd columns are empty.\n")
    if errors:
        L.append(f"**{len(errors)} row(s) failed**: see *Errors* at the end.\n")
    L.append("## Bits per vertex (cf. paper 003, Table 2)\n")
    L.append("bits/vertex = 8 × file bytes ÷ input vertices (every vertex record of the file, as the paper's "
             "Table 2 counts them). Same quantised mesh for everyone: p bits per coordinate over the cubic "
             "bounding box (origin = bbox min, step = largest side ÷ (2^p − 1)). *meshopt* = "
             "optimizeVertexCache + optimizeVertexFetch, positions 4 × uint16, vertex codec v1 level 3 + "
             "index codec; *+zstd* = both streams through zstd −19. *lossless* = decoded quantised "
             "positions and oriented triangles equal the quantised input's.\n")
    L.append("| mesh | vertices | p | tessd | Draco-10 | Draco-7 | meshopt | meshopt+zstd | tessd ÷ Draco-10 | tessd lossless |")
    L.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for mesh, p in keys:
        cells = []
        for v in TABLE_VARIANTS:
            r = by.get((mesh, p, v))
            cells.append(f2(r.get("bits_per_vertex")) if r and "bits_per_vertex" in r else
                         ("err" if r and "error" in r else "–"))
        t, d = by.get((mesh, p, "tessd")), by.get((mesh, p, "draco-10"))
        ratio = (t["bits_per_vertex"] / d["bits_per_vertex"]) if t and d and "bits_per_vertex" in t \
            and d.get("bits_per_vertex") else None
        if t and "lossless" in t:
            ll = "yes" if t["lossless"] else "**no**"
        elif t and "error" in t:
            ll = "error"
        else:
            ll = "not run" if tessd_missing else "–"
        nv = next((r.get("input_vertices") for r in codec if r["mesh"] == mesh and r.get("input_vertices")), None)
        L.append(f"| {mesh} | {nv} | {p} | " + " | ".join(cells) + f" | {f2(ratio)} | {ll} |")
    L.append("")
    L.append("Paper 003's Table 2 for comparison (their figures, not measured here): Bunny (35 947 vertices, "
             "p = 12): GD02 17.8, the paper's nSP-tree method 27.0 bits/vertex.\n")

    L.append("## Times and memory\n")
    L.append("Medians over repeats in one process (peers: `time.perf_counter` around the library call; "
             "tessd: the CLI's own `elapsed_ms`, its process wall time in brackets). Peak memory: tessd, the "
             "whole CLI process's peak RSS (GNU time's %M: mesh parsing included); peers, the growth of "
             "the peak resident set over one encode / decode call, input arrays already built (meshopt's "
             "encode includes the reorder and zstd, its decode zstd). Every child's whole peak RSS is in "
             "the raw rows (`peak_rss_kib`, `baseline_rss_kib`).\n")
    L.append("| mesh | p | variant | encode ms | decode ms | peak memory MiB (encode / decode) | decoded vertices | decoded triangles | max error ÷ side | lossless |")
    L.append("|---|---:|---|---:|---:|---:|---:|---:|---:|---|")
    for mesh, p in keys:
        for v in TABLE_VARIANTS:
            r = by.get((mesh, p, v))
            if not r or "bytes" not in r:
                continue
            if v == "tessd":
                enc = f"{fms(r.get('encode_ms'))} ({fms(r.get('encode_wall_ms'))})"
                dec = f"{fms(r.get('decode_ms'))} ({fms(r.get('decode_wall_ms'))})"
                rss = f"{f2((r.get('peak_rss_kib') or 0) / 1024, 1)} / {f2((r.get('decode_peak_rss_kib') or 0) / 1024, 1)}"
            else:
                enc, dec = fms(r.get("encode_ms")), fms(r.get("decode_ms"))
                mib = lambda k: f2(r[k] / 1024, 1) if r.get(k) is not None else "–"  # noqa: E731
                rss = f"{mib('encode_peak_kib')} / {mib('decode_peak_kib')}"
            L.append(f"| {mesh} | {p} | {v} | {enc} | {dec} | {rss} | {r.get('decoded_vertices')} | "
                     f"{r.get('decoded_triangles')} | {r.get('max_err_rel', float('nan')):.2e} | "
                     f"{'yes' if r.get('lossless') else '**no**'} |")
    L.append("")

    tl = [r for r in codec if r["tool"] == "tessd" and "bytes" in r]
    if tl:
        L.append("## tessd checks\n")
        L.append("Counts printed by `tessd compress --json` against the benchmark's own (unique quantised "
                 "points, unique oriented non-degenerate triangles over them); the lossless hook's grid.\n")
        L.append("| mesh | p | nSP cells | input v / t | vertices (ours) | triangles (ours) | bytes = file | bytes_read (full decode) | grid | positions equal | triangles equal |")
        L.append("|---|---:|---:|---|---|---|---|---:|---|---|---|")
        for r in sorted(tl, key=lambda r: (r["mesh"], r["p"])):
            c = r.get("compress_json", {})
            L.append(f"| {r['mesh']} | {r['p']} | {r.get('nsp_cells')} | {c.get('input_vertices')} / "
                     f"{c.get('input_triangles')} | {c.get('vertices')} ({r['unique_quantised_vertices']}) | "
                     f"{c.get('triangles')} ({r['unique_quantised_triangles']}) | {r.get('bytes_matches_json')} | "
                     f"{r.get('bytes_read')} | {r.get('check_grid')} | "
                     f"{'all' if r.get('positions_equal_all') else ('referenced' if r.get('positions_equal_referenced') else '**no**')} | "
                     f"{tri_cell(r)} |")
        L.append("")

    if rd:
        L.append("## Rate–distortion\n")
        L.append("Distance to the original (unquantised) mesh: sampled point-to-surface both ways "
                 "(100 000 area-weighted samples plus the vertices per side, exact point-to-triangle "
                 "distance), Hausdorff = larger max, RMS over both sides, ÷ the largest bbox side. tessd: "
                 "`tessd decompress --max-bits B`, rate = `bytes_read` (tessd-ahead2: the file compressed with "
                 "`--ahead 2`, geometry two bits ahead of the connectivity, §6.4); Draco level 10 at q bits. Plot: "
                 "`codec_rd.png`, data: `codec_rd.csv`.\n")
        L.append("| mesh | tool | B or q | bits/vertex | Hausdorff ÷ side | RMS ÷ side |")
        L.append("|---|---|---:|---:|---:|---:|")
        for r in rd:
            b = r.get("max_bits", r.get("quantization_bits"))
            if "error" in r:
                L.append(f"| {r['mesh']} | {r['tool']} | {b} | error | | |")
                continue
            L.append(f"| {r['mesh']} | {r['tool']} | {b} | {f2(r.get('bits_per_vertex'))} | "
                     f"{r['hausdorff_rel']:.2e} | {r['rms_rel']:.2e} |")
        L.append("")

    L.append("## Notes\n")
    L.append("* Draco is given the grid integers (range 2^p − 1 from origin 0) so that its quantiser is "
             "the identity on them and it codes exactly the quantised mesh tessd codes; from the float "
             "positions it writes within a few bytes of the same size (`bytes_from_float_input` in the raw "
             "rows) but puts a few near-tie vertices in the neighbouring cell (float32 arithmetic).")
    L.append("* Draco and meshopt drop unreferenced vertices (the bunny has 1 113); the denominator is still "
             "every input vertex. Per referenced vertex: `bits_per_referenced_vertex` in the raw rows.")
    L.append("* Raw rows (`codec_raw.jsonl`) also have meshopt's vertex codec v1 level 2 (`-v1l2`) and v0 "
             "(`-v0`, glTF EXT_meshopt_compression), and deflate (zlib −9) instead of zstd.")
    L.append("* Polygons are fan-triangulated for the peers; tessd's triangles are checked up to "
             "triangulation there (each spans three corners of one input polygon, in its orientation, and "
             "there are as many as the polygons give).")
    if errors:
        L.append("\n## Errors\n")
        for r in errors:
            L.append(f"* {r.get('mesh')} p={r.get('p')} {r.get('variant')}: `{str(r['error'])[-600:]}`")
    Path(out).mkdir(parents=True, exist_ok=True)
    (Path(out) / "codec.md").write_text("\n".join(L) + "\n")
    if rd:
        write_rd(rd, Path(out) / "codec_rd.csv", Path(out) / "codec_rd.png")


# ---------------------------------------------------------------------------------------------


def mesh_paths(data, names):
    files = sorted(p for p in Path(data, "mesh").iterdir() if p.suffix.lower() in MESH_EXT)
    if names:
        want = set(names.split(","))
        files = [p for p in files if p.stem in want or p.name in want]
    return files


def append(jsonl, rows):
    with open(jsonl, "a") as fh:
        for r in rows:
            fh.write(json.dumps(r) + "\n")


def cmd_run(a):
    start = time.time()
    binary = tessd_bin(a.tessd)
    if not a.peers_only and not binary.is_file():
        raise SystemExit(f"{NOT_BUILT}: {binary} does not exist (cargo build --release -p tessd, or set "
                         "TESSD_BIN); --peers-only runs the peers alone")
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    Path(a.out).mkdir(parents=True, exist_ok=True)
    Path(a.jsonl).parent.mkdir(parents=True, exist_ok=True)
    append(a.jsonl, [{"record": "meta", "binary": str(binary), "tessd_args": a.tessd_args, "data": str(a.data),
                      "peers_only": a.peers_only}])
    files = mesh_paths(a.data, a.meshes)
    if not files:
        raise SystemExit(f"no meshes under {a.data}/mesh")
    bits_list = parse_bits(a.bits)
    for path in files:
        for bits in bits_list:
            rows = peers.peer_rows(path, bits, ("load", "draco-10", "draco-7", "meshopt"), a.budget)
            if a.peers_only:
                rows.append({"mesh": path.stem, "path": str(path), "p": bits, "tool": "tessd", "variant": "tessd",
                             "skipped": NOT_BUILT})
            else:
                rows.extend(tessd_rows(str(path), bits, binary, work, a.tessd_args, a.budget))
            for r in rows:
                r.setdefault("record", "codec")
            append(a.jsonl, rows)
            for r in rows:
                if "error" in r:
                    print(f"{path.stem} p={bits} {r['variant']}: ERROR {r['error'][-400:]}", file=sys.stderr)
                elif r["variant"] in TABLE_VARIANTS and "bits_per_vertex" in r:
                    print(f"{path.stem} p={bits} {r['variant']}: {r['bytes']} B, {r['bits_per_vertex']:.2f} b/v, "
                          f"lossless {r.get('lossless')}")
    if a.rd_mesh:
        rd_path = next((p for p in files if p.stem == a.rd_mesh or p.name == a.rd_mesh), None)
        if rd_path is None:
            print(f"rate-distortion mesh {a.rd_mesh} not among the meshes run", file=sys.stderr)
        else:
            tsc = None if a.peers_only else work / f"{rd_path.stem}_p{a.rd_bits}.tsc"
            if tsc is not None and not tsc.exists():
                tsc = None
                print(f"no {rd_path.stem}_p{a.rd_bits}.tsc: tessd curve skipped", file=sys.stderr)
            rows = rd_rows(tsc, str(rd_path), a.rd_bits, binary, a.rd_min_bits, parse_bits(a.draco_bits),
                           a.samples, work)
            append(a.jsonl, rows)
            if tsc is not None:
                # the same file with two bits of geometry ahead of the connectivity (§6.4)
                ahead = work / f"{rd_path.stem}_p{a.rd_bits}_ahead2.tsc"
                rc, so, se, _, _ = peers.run_child_rss(
                    [str(binary), "compress", str(rd_path), str(ahead), "--bits", str(a.rd_bits),
                     *a.tessd_args.split(), "--ahead", "2", "--json"], 900)
                if rc == 0:
                    append(a.jsonl, rd_rows(ahead, str(rd_path), a.rd_bits, binary, a.rd_min_bits, None,
                                            a.samples, work, tool="tessd-ahead2", draco=False))
                else:
                    append(a.jsonl, [{"record": "rd", "mesh": rd_path.stem, "p": a.rd_bits, "tool": "tessd-ahead2",
                                      "error": (se or so).strip()[-1500:]}])
    report(a.jsonl, a.out, time.time() - start, a.command)
    rows = [json.loads(l) for l in open(a.jsonl) if l.strip()]
    bad = [r for r in rows if "error" in r]
    nonlossless = [r for r in rows if r.get("tool") == "tessd" and r.get("lossless") is False]
    print(f"codec benchmark: {Path(a.out) / 'codec.md'}, {a.jsonl}; {len(bad)} error row(s), "
          f"{len(nonlossless)} tessd row(s) not lossless")
    if bad:
        sys.exit(1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--data", default=os.environ.get("TESSD_SHARED_DATA", str(ROOT.parent / "shared" / "data")))
    r.add_argument("--meshes", default="", help="comma-separated names (stem or file name); default all")
    r.add_argument("--bits", default="12,16")
    r.add_argument("--tessd", default=None, help="binary (default $TESSD_BIN or target/release/tessd)")
    r.add_argument("--tessd-args", default=DEFAULT_TESSD_ARGS)
    r.add_argument("--work", default=os.environ.get("BENCH_WORK", "/tmp/tessd-bench-codec"))
    r.add_argument("--jsonl", default=str(ROOT / "bench" / "results" / "codec_raw.jsonl"))
    r.add_argument("--out", default=str(ROOT / "bench" / "results"))
    r.add_argument("--budget", type=float, default=1.0, help="seconds of repeats per timed call")
    r.add_argument("--rd-mesh", default="stanford_bunny", help="'' for none")
    r.add_argument("--rd-bits", type=int, default=12)
    r.add_argument("--rd-min-bits", type=int, default=4)
    r.add_argument("--draco-bits", default="4-16")
    r.add_argument("--samples", type=int, default=100000)
    r.add_argument("--peers-only", action="store_true", help=f"development only: no tessd ('{NOT_BUILT}' rows)")
    r.add_argument("--command", default=None, help="the command line to quote in the report")
    d = sub.add_parser("rd")
    d.add_argument("--tsc", default=None, help="omit for Draco's curve alone")
    d.add_argument("--mesh", required=True)
    d.add_argument("--bits", type=int, default=12)
    d.add_argument("--min-bits", type=int, default=4)
    d.add_argument("--draco-bits", default="4-16")
    d.add_argument("--samples", type=int, default=100000)
    d.add_argument("--tessd", default=None)
    d.add_argument("--work", default=None)
    d.add_argument("--csv", default=None)
    d.add_argument("--png", default=None)
    d.add_argument("--jsonl", default=None)
    p = sub.add_parser("report")
    p.add_argument("--jsonl", default=str(ROOT / "bench" / "results" / "codec_raw.jsonl"))
    p.add_argument("--out", default=str(ROOT / "bench" / "results"))
    p.add_argument("--wall-s", type=float, default=None)
    p.add_argument("--command", default=None)
    a = ap.parse_args()
    if a.cmd == "run":
        cmd_run(a)
    elif a.cmd == "rd":
        binary = tessd_bin(a.tessd)
        if a.tsc and not binary.is_file():
            raise SystemExit(f"{NOT_BUILT}: {binary} does not exist")
        work = a.work or (str(Path(a.tsc).parent) if a.tsc else "/tmp/tessd-bench-codec")
        Path(work).mkdir(parents=True, exist_ok=True)
        rows = rd_rows(a.tsc, a.mesh, a.bits, binary, a.min_bits, parse_bits(a.draco_bits), a.samples, work)
        if a.jsonl:
            append(a.jsonl, rows)
        write_rd(rows, a.csv, a.png)
        for r in rows:
            b = r.get("max_bits", r.get("quantization_bits"))
            if "error" in r:
                print(f"{r['tool']} {b}: ERROR {r['error'][-300:]}")
            else:
                print(f"{r['tool']} {b}: {r['bytes']} B, {r['bits_per_vertex']:.2f} b/v, "
                      f"Hausdorff {r['hausdorff_rel']:.3e}, RMS {r['rms_rel']:.3e} (÷ side)")
    else:
        report(a.jsonl, a.out, a.wall_s, a.command)


if __name__ == "__main__":
    main()
