#!/usr/bin/env python3
"""Report of the simplification benchmark.

    report.py [--jsonl bench/results/simplify_raw.jsonl]
              [--manifest bench/results/simplify_inputs.json] [--out bench/results]
              [--wall-s SECONDS]

Reads the JSON lines written by `bench-simplify run`, `meshlab.py run` and `e2e_daemon.py run`
(`"record": "e2e"`), writes `simplify.md` (tables per mesh, the thread-scaling and end-to-end
table, and the goals table with their ratios), `simplify_summary.json`
(the goal ratios, machine-readable) and two plots: `simplify_error_vs_size.png` (RMS error vs
output vertex count) and `simplify_time_vs_input.png` (time vs input triangles at the scaling
fraction). Issue 33's goal rows carry a *before* column from `simplify_goals_before.json` (the
same rows on the last full run before issue 33), and the report shows this run's stage times
and headline (`simplify_stages.json`, `simplify_headline.json`) beside the committed before
(`simplify_stages_before.json`, `simplify_headline_before.json`; tables.py). Run with
/work/main/.venv-bench/bin/python (needs matplotlib).
"""

import argparse
import datetime
import json
import math
import re
import os
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from report_common import gmean  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tables import headline_table, stage_tables  # noqa: E402

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METHODS = [
    "tessd-grid-bary",
    "tessd-grid-quadric",
    "tessd-quality-bary",
    "tessd-quality-quadric",
    "tessd-complexity-bary",
    "tessd-complexity-quadric",
    "meshopt-sloppy",
    "meshopt-simplify",
    "meshlab-clustering",
]
STYLE = {
    "tessd-grid-bary": ("tab:blue", "o", "-"),
    "tessd-grid-quadric": ("tab:blue", "s", "--"),
    "tessd-quality-bary": ("tab:green", "o", "-"),
    "tessd-quality-quadric": ("tab:green", "s", "--"),
    "tessd-complexity-bary": ("tab:red", "o", "-"),
    "tessd-complexity-quadric": ("tab:red", "s", "--"),
    "meshopt-sloppy": ("tab:gray", "^", "-"),
    "meshopt-simplify": ("black", "v", "-"),
    "meshlab-clustering": ("tab:purple", "D", ":"),
}
# Inputs at least this large count in the throughput goals (below, runs take well under a
# millisecond and timer/process noise dominates).
THROUGHPUT_MIN_TRIANGLES = 50_000
# A pair of results compares "at equal output size" when both are within this of the target.
MATCH_DEVIATION = 0.05
# Error ratios need targets of at least this many vertices (below, ±1 vertex is > 2 %).
ERROR_MIN_TARGET = 50
# The thread-scaling goal (2 threads ≥ 1.8 × one) holds on inputs at least this large.
SCALING_MIN_TRIANGLES = 9_000_000
SCALING_GOAL = 1.8
# Issue 33's speed goals, one thread, at equal output size: (tessd method, peer, speed ratio ≥).
GOALS = [
    ("tessd-grid-bary", "meshopt-sloppy", 2.0),
    ("tessd-grid-quadric", "meshopt-sloppy", 1.3),
    ("tessd-quality-bary", "meshopt-sloppy", 0.8),
    ("tessd-quality-quadric", "meshopt-sloppy", 0.6),
    ("tessd-complexity-bary", "meshopt-sloppy", 0.5),
    ("tessd-complexity-quadric", "meshopt-simplify", 2.0),
]
PEER_NAME = {"meshopt-sloppy": "simplifySloppy", "meshopt-simplify": "meshoptimizer simplify"}
TESSD = [m for m in METHODS if m.startswith("tessd")]
# The committed "before" stage times and headline (the library at 65769d72, before issue 33).
BEFORE = Path(__file__).resolve().parent.parent / "results"


def matched(a, b):
    return abs(a["deviation"]) <= MATCH_DEVIATION and abs(b["deviation"]) <= MATCH_DEVIATION


def fmt(x, digits=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if x == 0:
        return "0"
    if abs(x) >= 1000 or abs(x) < 0.01:
        return f"{x:.{digits - 1}e}"
    return f"{x:.{digits}g}"


def pct(f):
    return f"{f * 100:g} %"


def ok(flag):
    return "yes" if flag else "**no**"


def load(jsonl):
    """The harness/MeshLab records and the daemon's (`"record": "e2e"`), each by (mesh, method,
    fraction); the last line of one wins (re-runs append)."""
    recs = [json.loads(line) for line in open(jsonl) if line.strip()]
    by, e2e = {}, {}
    for r in recs:
        (e2e if r.get("record") == "e2e" else by)[(r["mesh"], r["method"], r["fraction"])] = r
    return by, e2e


def scaling_of(r, threads="2"):
    """The thread-scaling entry of a record for `threads`, when it ran."""
    for s in (r or {}).get("scaling") or []:
        if s.get("threads") == threads and "time_s" in s:
            return s
    return None


def good(r):
    return r is not None and "skipped" not in r and "error" not in r and "time_s" in r


def mesh_table(lines, mesh, recs, fractions):
    lines.append(
        "| method | target | output vertices (dev.) | time ms (runs) | M tri/s | extra peak / input | "
        "process peak MB | Hausdorff (% diag) | RMS (% diag) | out→in max | parameter |"
    )
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for f in fractions:
        for m in METHODS:
            r = recs.get((mesh, m, f))
            if r is None:
                continue
            tgt = f"{pct(f)} = {r['target_vertices']}"
            if "skipped" in r:
                lines.append(f"| {m} | {tgt} | skipped: {r['skipped']} |||||||||")
                continue
            if "error" in r:
                lines.append(f"| {m} | {tgt} | failed: {r['error'][:200]} |||||||||")
                continue
            dev = f"{r['deviation'] * 100:+.1f} %"
            ov = f"{r['out_vertices']} ({dev}{'' if r['hit'] else ', **miss**'})"
            t = f"{r['time_s'] * 1e3:.3g} ({r['repeats']})"
            diag = r.get("bbox_diagonal") or 0
            if "hausdorff" in r:
                h = f"{fmt(r['hausdorff'])} ({r['hausdorff_rel'] * 100:.3g})"
                rms = f"{fmt(r['rms'])} ({r['rms_rel'] * 100:.3g})"
                o2i = fmt(r["out_to_in_max"])
            else:
                h = rms = o2i = f"– ({r.get('compare_error', 'not measured')[:60]})"
            param = f"{r['param_name']} = {fmt(r['param'], 4)}"
            if "cells_per_axis" in r:
                param += f" (≈ {r['cells_per_axis']:.0f} cells/axis)"
            _ = diag
            lines.append(
                f"| {m} | {tgt} | {ov} | {t} | {r['mtris_per_s']:.3g} | {r['mem_ratio']:.2f} | "
                f"{r['process_hwm_kib'] / 1024:.0f} | {h} | {rms} | {o2i} | {param} |"
            )
    lines.append("")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--jsonl", default="bench/results/simplify_raw.jsonl")
    ap.add_argument("--manifest", default="bench/results/simplify_inputs.json")
    ap.add_argument("--out", default="bench/results")
    ap.add_argument("--wall-s", type=float, default=None)
    ap.add_argument("--stages", default=None, help="this run's stage times (default OUT/simplify_stages.json)")
    ap.add_argument("--headline", default=None, help="this run's headline (default OUT/simplify_headline.json)")
    ap.add_argument("--before-stages", default=str(BEFORE / "simplify_stages_before.json"))
    ap.add_argument("--before-headline", default=str(BEFORE / "simplify_headline_before.json"))
    ap.add_argument("--before-goals", default=str(BEFORE / "simplify_goals_before.json"),
                    help="the goals of a run before issue 33 (the before column; '' for none)")
    args = ap.parse_args()
    out = Path(args.out)
    recs, e2e = load(args.jsonl)
    manifest = json.loads(Path(args.manifest).read_text())
    meta = manifest["meta"]
    meshes = [e for e in manifest["meshes"] if any(k[0] == e["mesh"] for k in recs)]
    big_names = {f"torus_{x:g}M" for x in meta.get("big_sizes") or []}
    big_sizes = [e for e in meshes if e["mesh"] in big_names]
    info = {e["mesh"]: e for e in meshes}
    fractions_all = sorted({k[2] for k in recs}, reverse=True)
    big = [e["mesh"] for e in meshes if e["input_triangles"] >= THROUGHPUT_MIN_TRIANGLES]
    generated = sorted((e for e in meshes if e["generated"]), key=lambda e: e["input_triangles"])
    scaling_fraction = 0.1 if 0.1 in fractions_all else fractions_all[0]

    def get(mesh, m, f):
        r = recs.get((mesh, m, f))
        return r if good(r) else None

    summary = {"machine": {"nproc": meta.get("nproc"), "cpu_model": meta.get("cpu_model")},
               "date_utc": datetime.datetime.fromtimestamp(meta.get("unix_time", 0), datetime.UTC).strftime(
                   "%Y-%m-%d %H:%M"),
               "wall_s": args.wall_s, "goals": {}}

    L = []
    L.append("# Simplification benchmark: tessd vs meshoptimizer vs MeshLab")
    L.append("")
    L.append(
        f"Machine: {meta.get('nproc')} cores, {meta.get('cpu_model')}; shared with other jobs during the run "
        f"(noisy: timings are medians and the ratios below can move by ±30 %). Run {summary['date_utc']} UTC"
        + (f", whole run {args.wall_s / 60:.1f} min" if args.wall_s else "")
        + ". Command: `bash bench/run_simplify.sh`."
    )
    L.append("")
    L.append("## Method")
    L.append("")
    L.append(
        "* **Inputs**: every mesh of the shared data folder (`$TESSD_SHARED_DATA/mesh`) and generated bumpy tori "
        "(closed, genus 1, 3 bump frequencies plus a 10 %-of-an-edge radial jitter, row-ordered vertices) of "
        + ", ".join(f"{e['input_triangles'] / 1e6:.3g} M" for e in generated)
        + " triangles; "
        + ", ".join(e["mesh"] for e in generated if len(e["targets"]) == 1 and e["mesh"] not in big_names)
        + f" serve the size scaling only and run at {pct(scaling_fraction)} only"
        + ("; " + ", ".join(e["mesh"] for e in big_sizes) + " (optional: `SIMPLIFY_BENCH_50M=1`, the default of "
           "`run_simplify.sh`) runs at " + ", ".join(pct(t["fraction"]) for t in big_sizes[0]["targets"])
           + " only, to keep the run short (a call takes seconds there, and each search several calls)"
           + (", without MeshLab (≈ 200 s a call at 50 M: its time grows as size^1.56)"
              if any("skipped" in r for k, r in recs.items() if k[1] == "meshlab-clustering"
                     and k[0] in big_names) else "") if big_sizes else "")
        + "."
    )
    L.append(
        "* **Targets**: 50 %, 10 %, 1 % of the input's referenced vertices. tessd complexity takes the count "
        "directly; tessd grid (cubic cells, `GridSize::CellSize`), tessd quality (absolute tolerance), meshoptimizer "
        "(`target_index_count`, `target_error = FLT_MAX`, no options) and MeshLab (`meshing_decimation_clustering`, "
        "absolute `threshold`) get the parameter found by an untimed log-log secant/bisection search, then the "
        "timed run uses it. Output vertices = distinct vertices referenced by the output faces. "
        "A target counts as met within 1 % (exact below 50 vertices); misses are flagged."
    )
    L.append(
        f"* **Time**: each method in its own child process, the call only (mesh loaded, meshoptimizer's fan-"
        f"triangulated index buffer built beforehand; MeshLab: the filter call only), single-threaded "
        f"(`RAYON_NUM_THREADS={meta.get('timing_threads')}`), median of {meta.get('repeat')} runs (fewer when one "
        f"run exceeds the {meta.get('budget_s')} s budget: see the run counts). M tri/s = input triangles / "
        f"median time. MeshLab: one fresh process per run. As issue 33 sets it, *simplifySloppy's time includes "
        f"its size search; tessd's grid takes a cell size*: meshoptimizer gets the `target_index_count` found by "
        f"the untimed outer search, so the timed call includes simplifySloppy's own search for a grid size "
        f"(its 5–7 counting passes), while tessd's grid gets the cell size found by the outer search "
        f"(`GridSize::CellSize`) and runs once. The adaptive goals get their tolerance or vertex count."
    )
    L.append(
        "* **Stage times**: `bench-simplify stages` (one thread) runs every tessd mode on the 1 M and 4 M tori "
        "at 10 % (the harness's parameter search) in interleaved rounds and records the time between the "
        "library's `progress(fraction, stage)` callbacks: the span after a callback is charged to the stage it "
        "names (the span before the first callback to *start*; repeated names, such as the quality goal's "
        "`cover` rounds, are summed). *Before* is the same harness built against commit 65769d72 (the library "
        "before issue 33), run on this machine and committed as `simplify_stages_before.json`; its stages are "
        "that library's coarse ones. Medians per stage; they need not add up to the median call."
    )
    L.append(
        "* **Headline** (issue 33's table): `headline.py`, the 4 M-triangle torus (2 M vertices), one thread: "
        "tessd through the daemon (`elapsed_ms`, arrays in) against meshoptimizer in process "
        "(`bench-simplify peer`), the peer matched to tessd's output vertex count by an untimed search. *Before* "
        "= the daemon built at 65769d72 (`simplify_headline_before.json`)."
    )
    L.append(
        f"* **Threads**: every tessd run is timed again in a second child with "
        f"`RAYON_NUM_THREADS={','.join(meta.get('scaling_threads') or ['2'])}` and the parameter found for one thread "
        "(same repeats and budget); *2t/1t* = one-thread median ÷ two-thread median. The library is deterministic "
        "across thread counts, so both outputs must be the same bytes: the harness compares the written files "
        "(and the output vertex counts) and flags any difference."
    )
    L.append(
        "* **End to end**: on the generated tori, the same method, goal value and representative through the daemon "
        "(`tessd serve` started with `RAYON_NUM_THREADS=1`, one daemon for the whole pass): the mesh sent as arrays "
        "(`positions` f32 [V, 3], `face_indices` u32 [T, 3]) with the Python client, the result returned as arrays; "
        "the time is the daemon's own `elapsed_ms` (intake and validation, simplification, encoding; not the "
        "socket transfer), median of the same repeats within the same budget "
        "(`bench/simplify/e2e_daemon.py`). *÷ library* = daemon time ÷ the library call's one-thread median; the "
        "daemon's `output_vertices` must equal the library call's."
    )
    L.append(
        "* **Memory**: in the child, after loading, freed heap is trimmed and the peak RSS reset "
        "(`/proc/self/clear_refs` = 5); *extra peak / input* = (VmHWM after the runs − VmRSS before them) / "
        "(12 B × positions + 12 B × triangles, the indexed-triangle input), i.e. the simplification's working "
        "memory plus its output, relative to the input mesh. *Process peak* is the child's whole VmHWM (loading "
        "included). The child, like `tessd serve`, fixes glibc's mmap threshold at 4 MiB "
        "(`tessd_mesh::allocation`): buffers that large are returned to the system when freed, for every "
        "method alike (meshoptimizer's allocations go through the same malloc); with glibc's default rising "
        "threshold, freed buffers stay in the heap and the peak over several runs grows (grid-bary on "
        "torus_1M at 50 %: 1.29 on one run, 2.00 over three). Between two timed runs the child returns freed "
        "memory to the system (`malloc_trim`), as the daemon does when its last job ends, and its allocator, "
        "like the daemon's, asks for transparent huge pages on buffers of 4 MiB or more "
        "(`tessd_mesh::allocation::LargePages`; meshoptimizer's buffers come from malloc without that advice)."
    )
    L.append(
        "* **Error**: tessd-compare (Metro-style) of every output against its input with the same options for all "
        "methods of one input: 10 face samples per input triangle clamped to 0.1–2 M per direction, plus every "
        "vertex for inputs ≤ 2 M triangles (face samples only above, to keep the run short). Hausdorff = symmetric "
        "max, RMS = pooled RMS of both directions, out→in max = one-sided max from the output to the input; "
        "% of the bounding-box diagonal. MeshLab's outputs are measured by the same binary "
        "(`bench-simplify compare`)."
    )
    L.append("")

    # ---------------- goals
    G = summary["goals"]
    bg = json.loads(Path(args.before_goals).read_text()) if args.before_goals and Path(args.before_goals).exists() \
        else None
    before_src = f"{bg['meta']['source']}" if bg else "no earlier run (none found)"

    def norm(name):
        return re.sub(r" \(torus[^)]*\)$", "", name)

    def before_goal(name):
        if not bg:
            return None
        goals = bg["goals"]
        return goals.get(name) or next((v for k, v in goals.items() if norm(k) == norm(name)), None)

    L.append("## Goals")
    L.append("")
    L.append(
        f"Throughput ratios are over inputs ≥ {THROUGHPUT_MIN_TRIANGLES // 1000} k triangles "
        f"({', '.join(big)}), per (mesh, target) at equal output vertex count; *gmean* = geometric mean "
        f"over those pairs. Error ratios are over every (mesh, target) of ≥ {ERROR_MIN_TARGET} target vertices where "
        "both methods have a result. Pairs count only when both outputs are within "
        f"{MATCH_DEVIATION * 100:g} % of the target count."
    )
    L.append("")
    L.append(f"*before* = the same goal on {before_src} (`simplify_goals_before.json`; *(no)*: missed there).")
    L.append("")
    L.append("| goal | measured (gmean) | before | on the 10 M torus (50 / 10 / 1 %) | range | met |")
    L.append("|---|---|---|---|---|---|")
    ten = [e["mesh"] for e in generated if e["input_triangles"] >= 9e6]
    ten = ten[0] if ten else None
    fr3 = [f for f in fractions_all if f in (0.5, 0.1, 0.01)]

    def thr_ratio(m, ref="meshopt-sloppy", meshes_=None):
        pairs = {}
        for mesh in meshes_ or big:
            for f in fractions_all:
                a, b = get(mesh, m, f), get(mesh, ref, f)
                if a and b and matched(a, b):
                    pairs[(mesh, f)] = a["mtris_per_s"] / b["mtris_per_s"]
        return pairs

    def bcell(name):
        """The before column: the same goal on the committed last full run before issue 33."""
        b = before_goal(name)
        if b is None:
            return "–"
        v = b.get("gmean")
        return (f"{v:.2f}" if isinstance(v, (int, float)) and b.get("pairs") else "–") + ("" if b.get("met") else " (no)")

    def row(name, pairs, goal_fn, ten_key_fmt=lambda v: f"{v:.2f}", before=True):
        vals = list(pairs.values())
        g = gmean(vals)
        tens = " / ".join(ten_key_fmt(pairs[(ten, f)]) if (ten, f) in pairs else "–" for f in fr3) if ten else "–"
        rng = f"{min(vals):.2f}–{max(vals):.2f}" if vals else "–"
        met = goal_fn(g) if vals else False
        bc = f" {bcell(name)} |" if before else ""
        L.append(f"| {name} | {f'{g:.2f}' if vals else '– (no pairs in this run)'} |{bc} {tens} | {rng} | {ok(met)} |")
        G[name] = {"gmean": g, "pairs": {f"{k[0]}@{k[1]}": v for k, v in pairs.items()}, "met": met}

    def err_ratio(m, ref, key):
        pairs = {}
        for e in meshes:
            for f in fractions_all:
                a, b = get(e["mesh"], m, f), get(e["mesh"], ref, f)
                if (a and b and a.get(key) and b.get(key) and matched(a, b)
                        and a["target_vertices"] >= ERROR_MIN_TARGET):
                    pairs[(e["mesh"], f)] = a[key] / b[key]
        return pairs

    # Issue 33's goals: speed ÷ the peer's at equal output size, one thread.
    for m, ref, goal in GOALS:
        row(f"{m[6:]} speed ÷ {PEER_NAME[ref]}'s ≥ {goal:g}", thr_ratio(m, ref), lambda g, goal=goal: g >= goal)
    row("complexity-quadric Hausdorff ÷ meshoptimizer simplify's ≤ 1.5 (with the speed goal above)",
        err_ratio("tessd-complexity-quadric", "meshopt-simplify", "hausdorff"), lambda g: g <= 1.5)
    fan = {k: v for k, v in err_ratio("tessd-complexity-quadric", "meshopt-simplify", "hausdorff").items()
           if k[0] == "fandisk"}
    name = "complexity-quadric Hausdorff ÷ meshoptimizer simplify's ≤ 2 on fandisk (gmean of its targets)"
    if fan:
        g = gmean(list(fan.values()))
        L.append(f"| {name} | {g:.2f} | {bcell(name)} | – | " + ", ".join(f"{pct(k[1])}: {v:.2f}" for k, v in sorted(fan.items()))
                 + f" | {ok(g <= 2)} |")
        G[name] = {"gmean": g, "pairs": {f"{k[0]}@{k[1]}": v for k, v in fan.items()}, "met": g <= 2}
    else:
        L.append(f"| {name} | – (fandisk not in this run) | {bcell(name)} | – | – | **no** |")
        G[name] = {"met": False, "pairs": {}}

    # Thread scaling: 2 threads ÷ 1 thread on inputs ≥ 10 M triangles.
    for m in TESSD:
        pairs = {}
        for e in meshes:
            if e["input_triangles"] < SCALING_MIN_TRIANGLES:
                continue
            for f in fractions_all:
                sc = scaling_of(get(e["mesh"], m, f))
                if sc:
                    pairs[(e["mesh"], f)] = sc["speedup"]
        if pairs:
            row(f"{m[6:]}: 2 threads ≥ {SCALING_GOAL} × one thread on ≥ 10 M triangles "
                f"({', '.join(sorted({k[0] for k in pairs}))})", pairs, lambda g: g >= SCALING_GOAL)
        else:
            name = f"{m[6:]}: 2 threads ≥ {SCALING_GOAL} × one thread on ≥ 10 M triangles"
            L.append(f"| {name} | – (no input ≥ 10 M triangles timed with 2 threads) | {bcell(name)} | – | – | **no** |")
            G[f"{m[6:]}: 2 threads ≥ {SCALING_GOAL} × one thread on ≥ 10 M triangles"] = {"met": False, "pairs": {}}

    # The same speed goals end to end: the daemon's elapsed_ms (arrays in and out, one thread) on the
    # tori against the peer's in-process call.
    def e2e_ratio(m, ref):
        pairs = {}
        for e in generated:
            for f in fractions_all:
                d, a, b = e2e.get((e["mesh"], m, f)), get(e["mesh"], m, f), get(e["mesh"], ref, f)
                if d and "e2e_ms" in d and a and b and matched(a, b):
                    pairs[(e["mesh"], f)] = (e["input_triangles"] / d["e2e_ms"] / 1e3) / b["mtris_per_s"]
        return pairs

    for m, ref, goal in GOALS:
        pairs = e2e_ratio(m, ref)
        name = f"{m[6:]} end to end (daemon, arrays in; tori) ÷ {PEER_NAME[ref]}'s in-process ≥ {goal:g}"
        if pairs:
            row(name, pairs, lambda g, goal=goal: g >= goal)
        else:
            L.append(f"| {name} | – (no daemon pass in this run) | {bcell(name)} | – | – | **no** |")
            G[name] = {"met": False, "pairs": {}}
    L.append("")

    # Invariants of issue 33 and the goals of earlier issues.
    L.append("### Invariants and earlier goals")
    L.append("")
    L.append("| check | measured (gmean) | on the 10 M torus (50 / 10 / 1 %) | range | met |")
    L.append("|---|---|---|---|---|")
    same, differ = 0, []
    for k, r in sorted(recs.items()):
        for sc in (r.get("scaling") or []) if good(r) else []:
            if sc.get("identical"):
                same += 1
            else:
                differ.append(f"{k[1]} on {k[0]} @ {pct(k[2])} ({sc.get('threads')} threads: "
                              + ("failed" if "error" in sc else "same count, other bytes" if sc.get("same_count")
                                 else f"{sc.get('out_vertices')} vs {r['out_vertices']} vertices") + ")")
    L.append(f"| outputs identical at 1 and 2 threads (same bytes; every tessd run) | {same} of {same + len(differ)} | – | "
             + ("; ".join(differ[:8]) + (f"; {len(differ) - 8} more" if len(differ) > 8 else "") if differ else "–")
             + f" | {ok(same > 0 and not differ)} |")
    G["outputs identical across thread counts"] = {"identical": same, "differ": differ,
                                                   "met": same > 0 and not differ}
    row("complexity-quadric RMS ÷ MeshLab clustering's < 1", err_ratio("tessd-complexity-quadric", "meshlab-clustering", "rms"),
        lambda g: g < 1, before=False)
    row("complexity-quadric Hausdorff ÷ MeshLab clustering's < 1",
        err_ratio("tessd-complexity-quadric", "meshlab-clustering", "hausdorff"), lambda g: g < 1, before=False)
    row("complexity-quadric RMS ÷ meshopt simplify's ≤ 1.5", err_ratio("tessd-complexity-quadric", "meshopt-simplify", "rms"),
        lambda g: g <= 1.5, before=False)

    # Linearity: slope of log time vs log triangles at the scaling fraction over the tori.
    slopes = {}
    for m in METHODS:
        pts = [(e["input_triangles"], get(e["mesh"], m, scaling_fraction)) for e in generated]
        pts = [(t, r["time_s"]) for t, r in pts if r]
        if len(pts) >= 3:
            xs = [math.log(t) for t, _ in pts]
            ys = [math.log(s) for _, s in pts]
            mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
            k = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
            slopes[m] = {"slope": k, "ns_per_triangle": {f"{t / 1e6:.3g}M": s / t * 1e9 for t, s in pts}}
    for m in [m for m in METHODS if m.startswith("tessd")]:
        if m in slopes:
            k = slopes[m]["slope"]
            met = k <= 1.15
            L.append(f"| {m[6:]}: cost linear in input size (slope of log time vs log triangles at "
                     f"{pct(scaling_fraction)}, tori) | {k:.2f} | – | ns/tri " +
                     ", ".join(f"{v:.0f}" for v in slopes[m]["ns_per_triangle"].values()) + f" | {ok(met)} |")
            G[f"{m} linear"] = {"slope": k, **slopes[m], "met": met}
    # Memory: extra peak / input ≤ 2 (all tessd runs on inputs ≥ 1 M triangles).
    for m in [m for m in METHODS if m.startswith("tessd")]:
        vals = {}
        for e in meshes:
            if e["input_triangles"] < 1e6:
                continue
            for f in fractions_all:
                r = get(e["mesh"], m, f)
                if r:
                    vals[(e["mesh"], f)] = r["mem_ratio"]
        if vals:
            worst = max(vals, key=vals.get)
            tens = " / ".join(f"{vals[(ten, f)]:.2f}" if (ten, f) in vals else "–" for f in fr3) if ten else "–"
            met = vals[worst] <= 2
            L.append(f"| {m[6:]}: extra peak memory ≤ 2 × input (max over inputs ≥ 1 M triangles) | "
                     f"{vals[worst]:.2f} (max, {worst[0]} @ {pct(worst[1])}) | {tens} | "
                     f"{min(vals.values()):.2f}–{max(vals.values()):.2f} | {ok(met)} |")
            G[f"{m} memory"] = {"max": vals[worst], "pairs": {f"{k[0]}@{k[1]}": v for k, v in vals.items()},
                                "met": met}
    L.append("")
    few = [(k, r) for k, r in sorted(recs.items()) if good(r) and r["repeats"] < (meta.get("repeat") or 3)]
    if few:
        L.append(f"Timed fewer than {meta.get('repeat')} times (one run took longer than the "
                 f"{meta.get('budget_s')} s budget allows): "
                 + "; ".join(f"{k[1]} on {k[0]} @ {pct(k[2])} ({r['repeats']} run{'s' if r['repeats'] > 1 else ''}, "
                             f"{r['time_s']:.1f} s)" for k, r in few) + ".")
        L.append("")
    misses = [(k, r) for k, r in sorted(recs.items()) if good(r) and not r["hit"]]
    if misses:
        L.append(f"Target counts missed by more than 1 % ({len(misses)} of "
                 f"{sum(1 for r in recs.values() if good(r))} results; clustering and simplifySloppy counts move "
                 "in steps with the cell size, so on small meshes some counts are unreachable — the closest "
                 "count found is used and flagged in the tables): "
                 + ", ".join(f"{n} {k[1]}" for n, k in sorted(
                     ((sum(1 for kk, _ in misses if kk[1] == m), (None, m)) for m in {kk[1] for kk, _ in misses}),
                     reverse=True)) + ".")
        L.append("")
    # Reference throughputs.
    L.append("Reference throughputs on this machine (median M triangles/s, single thread):")
    L.append("")
    L.append("| input | target | " + " | ".join(m.replace("tessd-", "") for m in METHODS) + " |")
    L.append("|---|---|" + "---|" * len(METHODS))
    for mesh in big:
        for f in fractions_all:
            rs = [get(mesh, m, f) for m in METHODS]
            if not any(rs):
                continue
            L.append(f"| {mesh} | {pct(f)} | " + " | ".join(f"{r['mtris_per_s']:.3g}" if r else "–" for r in rs) + " |")
    L.append("")
    # Linearity details.
    if slopes:
        L.append(f"Time per input triangle at {pct(scaling_fraction)} across the tori (ns/triangle) and the slope of "
                 "log time vs log size (1 = linear):")
        L.append("")
        L.append("| method | " + " | ".join(f"{e['input_triangles'] / 1e6:.3g} M" for e in generated) + " | slope |")
        L.append("|---|" + "---|" * (len(generated) + 1))
        for m in METHODS:
            if m in slopes:
                cells = []
                for e in generated:
                    r = get(e["mesh"], m, scaling_fraction)
                    cells.append(f"{r['time_s'] / e['input_triangles'] * 1e9:.0f}" if r else "–")
                L.append(f"| {m} | " + " | ".join(cells) + f" | {slopes[m]['slope']:.2f} |")
        L.append("")
    # Error ratio details.
    L.append("Error of complexity + quadric relative to MeshLab clustering and meshopt simplify per input "
             "(RMS ratio / Hausdorff ratio; < 1 = tessd better):")
    L.append("")
    L.append("| input | " + " | ".join(f"vs MeshLab {pct(f)}" for f in fractions_all) + " | " +
             " | ".join(f"vs meshopt simplify {pct(f)}" for f in fractions_all) + " |")
    L.append("|---|" + "---|" * (2 * len(fractions_all)))
    for e in meshes:
        cells = []
        for ref in ["meshlab-clustering", "meshopt-simplify"]:
            for f in fractions_all:
                a, b = get(e["mesh"], "tessd-complexity-quadric", f), get(e["mesh"], ref, f)
                if a and b and a.get("rms") and b.get("rms") and a.get("hausdorff") and b.get("hausdorff"):
                    cells.append(f"{a['rms'] / b['rms']:.2f} / {a['hausdorff'] / b['hausdorff']:.2f}")
                else:
                    cells.append("–")
        if any(c != "–" for c in cells):
            L.append(f"| {e['mesh']} | " + " | ".join(cells) + " |")
    L.append("")

    # ---------------- issue 33: headline and stage times, before and after
    def load_opt(p):
        return json.loads(Path(p).read_text()) if p and Path(p).exists() else None

    head_after = load_opt(args.headline or out / "simplify_headline.json")
    head_before = load_opt(args.before_headline)
    L.append("## Headline: tessd through the daemon vs meshoptimizer (issue 33)")
    L.append("")
    if head_before and not head_after:
        L += ["This run made no headline (`SIMPLIFY_HEADLINE_TRIANGLES` empty): the committed *before* only.", ""]
    L += headline_table(head_after, head_before) or ["– (no headline results found)", ""]
    summary["headline"] = {"after": head_after, "before": head_before}
    stages_after = load_opt(args.stages or out / "simplify_stages.json")
    stages_before = load_opt(args.before_stages)
    L.append("## Stage times of each mode, before and after (issue 33)")
    L.append("")
    if stages_before and not stages_after:
        L += ["This run timed no stages (`SIMPLIFY_STAGES_SIZES` empty): the committed *before* only.", ""]
    L += stage_tables(stages_after, stages_before) or ["– (no stage times found)", ""]
    summary["stages"] = {"after": stages_after, "before": stages_before}

    # ---------------- thread scaling and end to end
    L.append("## Threads and end to end")
    L.append("")
    L.append("tessd's library call at 1 and 2 threads (same parameter; *identical* = the same output bytes) and, on the "
             "tori, the daemon's `elapsed_ms` with the mesh sent as arrays (1 thread) beside the library call "
             "(1 thread). Times in ms, medians (runs).")
    L.append("")
    L.append("| input | target | method | 1 thread | 2 threads | 2t/1t | identical | end to end (daemon) | "
             "÷ library |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for e in meshes:
        if not (e["generated"] or e["input_triangles"] >= 1e6):
            continue
        for f in fractions_all:
            for m in TESSD:
                r = get(e["mesh"], m, f)
                if not r:
                    continue
                sc = scaling_of(r)
                d = e2e.get((e["mesh"], m, f))
                two = f"{sc['time_s'] * 1e3:.4g} ({sc['repeats']})" if sc else "–"
                sp = f"{sc['speedup']:.2f}" if sc else "–"
                ident = "–"
                if r.get("scaling"):
                    s0 = r["scaling"][0]
                    ident = ("yes" if s0.get("identical") else "**no** (failed)" if "error" in s0
                             else "**no** (count same)" if s0.get("same_count")
                             else f"**no** ({s0.get('out_vertices')} vertices)")
                if d and "e2e_ms" in d:
                    e2 = f"{d['e2e_ms']:.4g} ({d['repeats']})" + ("" if d.get("same_count") else
                                                                  f" **count {d.get('out_vertices')}**")
                    ratio = f"{d['ratio']:.2f}"
                elif d:
                    e2, ratio = f"failed: {d.get('error', '')[:80]}", "–"
                else:
                    e2, ratio = "–", "–"
                L.append(f"| {e['mesh']} | {pct(f)} | {m[6:]} | {r['time_s'] * 1e3:.4g} ({r['repeats']}) | {two} | "
                         f"{sp} | {ident} | {e2} | {ratio} |")
    L.append("")
    summary["e2e"] = {f"{k[0]}@{k[1]}@{k[2]}": {"e2e_ms": d.get("e2e_ms"), "ratio": d.get("ratio"),
                                                "same_count": d.get("same_count")} for k, d in e2e.items()}

    # ---------------- per-mesh tables
    L.append("## Results per input")
    L.append("")
    for e in meshes:
        L.append(f"### {e['mesh']}")
        L.append("")
        L.append(
            f"{e['input_vertices']} referenced vertices, {e['input_faces']} faces ({e['input_triangles']} triangles), "
            f"bbox diagonal {fmt(e['bbox_diagonal'], 4)}, input {e['input_bytes'] / 2**20:.1f} MiB; "
            f"{e['face_samples']} face samples per direction{' + vertices' if e.get('vertex_samples', True) else ''}."
        )
        L.append("")
        mesh_table(L, e["mesh"], recs, fractions_all)

    (out / "simplify.md").write_text("\n".join(L) + "\n")
    summary["slopes"] = slopes
    (out / "simplify_summary.json").write_text(json.dumps(summary, indent=1, default=str) + "\n")

    # ---------------- plots
    plot_meshes = [m for m in ["bun_zipper", "torus_1M"] if m in info]
    if plot_meshes:
        fig, axes = plt.subplots(1, len(plot_meshes), figsize=(6.5 * len(plot_meshes), 5.2), squeeze=False)
        for ax, mesh in zip(axes[0], plot_meshes):
            for m in METHODS:
                pts = sorted((r["out_vertices"], r["rms_rel"] * 100) for f in fractions_all
                             if (r := get(mesh, m, f)) and r.get("rms_rel"))
                if pts:
                    c, mk, ls = STYLE[m]
                    ax.plot(*zip(*pts), color=c, marker=mk, linestyle=ls, label=m, alpha=0.85)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("output vertices")
            ax.set_ylabel("RMS error (% of bbox diagonal)")
            e = info[mesh]
            ax.set_title(f"{mesh} ({e['input_triangles'] / 1e3:.0f} k triangles)")
            ax.grid(True, which="both", alpha=0.3)
        axes[0][0].legend(fontsize=8)
        fig.suptitle("Error vs output size (targets 1 %, 10 %, 50 % of the input vertices)")
        fig.tight_layout()
        fig.savefig(out / "simplify_error_vs_size.png", dpi=110)
        plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for m in METHODS:
        pts = [(e["input_triangles"], r["time_s"]) for e in generated if (r := get(e["mesh"], m, scaling_fraction))]
        if pts:
            c, mk, ls = STYLE[m]
            ax.plot(*zip(*pts), color=c, marker=mk, linestyle=ls, label=m, alpha=0.85)
    if generated:
        xs = [generated[0]["input_triangles"], generated[-1]["input_triangles"]]
        ax.plot(xs, [x / 200e6 for x in xs], color="k", linestyle=(0, (1, 3)), linewidth=1,
                label="200 M tri/s (one pass over the triangles)")
        ax.plot(xs, [x / 13.5e6 for x in xs], color="tab:gray", linestyle=(0, (1, 3)), linewidth=1,
                label="13.5 M tri/s (quoted simplifySloppy rate)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("input triangles (bumpy torus)")
    ax.set_ylabel("time (s), median, 1 thread")
    ax.set_title(f"Time vs input size at {pct(scaling_fraction)} of the vertices")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "simplify_time_vs_input.png", dpi=110)
    plt.close(fig)
    print(f"wrote {out / 'simplify.md'}, {out / 'simplify_summary.json'}, simplify_error_vs_size.png, "
          "simplify_time_vs_input.png")


if __name__ == "__main__":
    main()
