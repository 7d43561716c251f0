#!/usr/bin/env python3
"""Report of the subdivision benchmark.

    report.py [--jsonl bench/results/subdiv_raw.jsonl] [--out bench/results] [--wall-s SECONDS]
              [--command "bash bench/run_subdiv.sh"]

Reads the JSON lines written by `bench-subdiv run` (tools tessd, tessd-gpu, osd) and
`blender_bench.py run` (tool blender) and writes `subdiv.md` (per-cage tables of every phase's
median time, a peak-memory table, the goals with their ratios, the comparison with the paper's
table 7.2 and consistency checks) and the plot `subdiv_time_per_vertex.png` (time per output
vertex vs output vertices, log-log, one line per tool and phase). Run with
/work/main/.venv-bench/bin/python (needs matplotlib).
"""

import argparse
import datetime
import json
import math
import os
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from report_common import gmean, machine, yes  # noqa: E402

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# Paper 002, figure 7.2: frames per second on the CPU, and polygons, per model and level
# (level 0 = the control mesh, drawn without subdividing).
PAPER = {
    "Cube": {"faces": [6, 24, 96, 384, 1536, 6144], "fps": [3271.3, 960.1, 276.2, 68.7, 16.7, 3.6]},
    "Torus Knot": {"faces": [96, 384, 1536, 6144, 24576, 98304], "fps": [1529.4, 90.4, 17.2, 3.7, 0.9, 0.2]},
    "Monsterfrog": {"faces": [1292, 5168, 20672, 82688, 330752, 1323008],
                    "fps": [1257.7, 5.8, 1.1, 0.3, 0.07, 0.02]},
}
# Our cage standing in for each of the paper's models.
PAPER_CAGE = {"Cube": "cube.obj", "Torus Knot": "torus_knot_96.obj", "Monsterfrog": "quadknot.obj"}
# The reference case of the goals, and the reference figures measured on these machines.
REF_CAGE, REF_LEVEL = "torus_8192.obj", 4
REFERENCE = {"osd_topology_ms": 351.0, "osd_primvar_ms": 76.0, "osd_stencil_eval_ms": 127.0, "dupuy_vanhoey_ms": 18.0}
GOAL_TOPOLOGY = 10.0
GOAL_APPLY = 1.5
GOAL_PAPER = 1000.0
# Configurations with at least this many output vertices count in the gmean of the goals
# (below, a phase takes tens of microseconds and timer and cache noise dominate).
LARGE = 100_000


def fmt(x, sig=3):
    """A time or ratio with `sig` significant digits, no exponent."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if isinstance(x, int):
        return f"{x:,}".replace(",", " ")
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    if mag >= sig - 1:
        return f"{x:,.0f}".replace(",", " ")
    return f"{x:.{sig - 1 - mag}f}"


def mb(kib):
    return None if kib is None else kib / 1024.0


def load(path):
    by = {}
    for line in open(path):
        if not line.strip():
            continue
        r = json.loads(line)
        key = (r.get("tool"), r.get("threads") if r.get("tool") == "tessd" else None, r.get("cage"), r.get("level"))
        by[key] = r  # the last line of a configuration wins (re-runs append)
    return by


def ok(r):
    return r is not None and "error" not in r and "skipped" not in r


class Data:
    def __init__(self, recs):
        self.recs = recs
        cages = {}
        for (tool, _, cage, _), r in recs.items():
            if cage and r.get("cage_faces") is not None:
                cages[cage] = r["cage_faces"]
            elif cage and cage not in cages:
                cages[cage] = None
        self.cages = sorted(cages, key=lambda c: (cages[c] is None, cages[c] or 0, c))
        self.cage_faces = cages
        self.levels = sorted({k[3] for k in recs if k[3] is not None})
        self.threads = sorted({k[1] for k in recs if k[0] == "tessd" and k[1] is not None})

    def get(self, tool, cage, level, threads=None):
        return self.recs.get((tool, threads, cage, level))

    def val(self, tool, cage, level, key, threads=None):
        r = self.get(tool, cage, level, threads)
        if not ok(r):
            return None
        v = r.get(key)
        return v if isinstance(v, (int, float)) else None

    def out_vertices(self, cage, level):
        for tool, th in [("tessd", t) for t in self.threads] + [("osd", None), ("blender", None), ("tessd-gpu", None)]:
            v = self.val(tool, cage, level, "out_vertices", th)
            if v:
                return v
        return None

    def out_faces(self, cage, level):
        for tool, th in [("tessd", t) for t in self.threads] + [("osd", None), ("blender", None)]:
            v = self.val(tool, cage, level, "out_faces", th)
            if v:
                return v
        return None


def runs_range(d, tool, *keys):
    """'a–b runs' over the records of `tool`: the length of each `*_runs_ms` list, or the number."""
    ns = []
    for (t, *_), r in d.recs.items():
        if t == tool and ok(r):
            for k in keys:
                v = r.get(k)
                if isinstance(v, list):
                    ns.append(len(v))
                elif isinstance(v, int):
                    ns.append(v)
    return f"{min(ns)}–{max(ns)} runs" if ns else "no runs"


def span(d, tool, key):
    """'a–b' over the records of `tool`."""
    vs = [r[key] for (t, *_), r in d.recs.items() if t == tool and ok(r) and isinstance(r.get(key), (int, float))]
    return f"{fmt(min(vs))}–{fmt(max(vs))}" if vs else "–"


def cell(d, tool, cage, level, key, threads=None):
    r = d.get(tool, cage, level, threads)
    if r is None:
        return "–"
    if "skipped" in r:
        return "skipped"
    if "error" in r:
        return "over device limit" if "limit" in str(r["error"]) else "failed"
    return fmt(r.get(key))


def ratio_rows(d, num, den, levels=None):
    """[(cage, level, out_vertices, ratio)] for num(cage, level) / den(cage, level)."""
    rows = []
    for cage in d.cages:
        for level in levels or d.levels:
            a, b = num(cage, level), den(cage, level)
            if a and b:
                rows.append((cage, level, d.out_vertices(cage, level) or 0, a / b))
    return rows


def goal_row(name, rows, goal, note=""):
    ref = [r for c, lv, _, r in rows if c == REF_CAGE and lv == REF_LEVEL]
    large = [r for _, _, n, r in rows if n >= LARGE]
    g = gmean(large)
    ref_v = ref[0] if ref else None
    lo = min((r for *_, r in rows), default=None)
    hi = max((r for *_, r in rows), default=None)
    met = ref_v is not None and ref_v >= goal and math.isfinite(g) and g >= goal
    rng = f"{fmt(lo)}–{fmt(hi)}" if lo is not None else "–"
    return (f"| {name} | ≥ {fmt(goal)} | {fmt(ref_v)} | {fmt(g)} ({len(large)}) | {rng} | {yes(met)} |{note}",
            {"reference_case": ref_v, "gmean_large": g, "min": lo, "max": hi, "met": met})


def paper_rows(d, threads):
    rows = []
    for model, p in PAPER.items():
        cage = PAPER_CAGE[model]
        for level in range(1, 6):
            frame_ms = 1000.0 / p["fps"][level]
            tessd = d.val("tessd", cage, level, "pipeline_ms", threads)
            faces = d.out_faces(cage, level)
            osd_topo = d.val("osd", cage, level, "topology_ms")
            osd_pv = d.val("osd", cage, level, "primvar_ms")
            osd = osd_topo + osd_pv if osd_topo is not None and osd_pv is not None else None
            ratio = frame_ms / tessd if tessd else None
            # Per output face: the paper's ms per polygon over ours (our model may differ in size).
            norm = (frame_ms / p["faces"][level]) / (tessd / faces) if tessd and faces else None
            rows.append(dict(model=model, cage=cage, level=level, paper_faces=p["faces"][level], fps=p["fps"][level],
                             frame_ms=frame_ms, faces=faces, tessd_ms=tessd, ratio=ratio, norm=norm, osd_ms=osd,
                             osd_ratio=frame_ms / osd if osd else None))
    return rows


def write_plot(d, path):
    series = [
        # (panel, label, tool, threads, key, colour, marker, style)
        (0, "tessd topology, 1 thread", "tessd", 1, "topology_ms", "tab:red", "o", "-"),
        (0, "tessd topology, 2 threads", "tessd", 2, "topology_ms", "tab:red", "s", "--"),
        (0, "tessd connectivity only, 1 thread", "tessd", 1, "connectivity_ms", "tab:orange", "o", "-"),
        (0, "OSD create + RefineUniform", "osd", None, "topology_ms", "black", "^", "-"),
        (0, "OSD stencil table build", "osd", None, "stencil_build_ms", "tab:gray", "v", ":"),
        (1, "tessd apply, 1 thread", "tessd", 1, "apply_ms", "tab:blue", "o", "-"),
        (1, "tessd apply, 2 threads", "tessd", 2, "apply_ms", "tab:blue", "s", "--"),
        (1, "tessd apply into reused buffers, 1 thread", "tessd", 1, "apply_reused_ms", "tab:cyan", "o", "-"),
        (1, "tessd apply into reused buffers, 2 threads", "tessd", 2, "apply_reused_ms", "tab:cyan", "s", "--"),
        (1, "tessd GPU apply on lavapipe (CPU), call", "tessd-gpu", None, "apply_ms", "tab:green", "P", "-"),
        (1, "tessd GPU apply on lavapipe (CPU), device", "tessd-gpu", None, "device_ms", "tab:green", "x", ":"),
        (1, "OSD PrimvarRefiner", "osd", None, "primvar_ms", "black", "^", "-"),
        (1, "OSD CpuEvaluator (stencils)", "osd", None, "stencil_eval_ms", "tab:gray", "v", ":"),
        (1, "Blender modifier, positions changed", "blender", None, "pose_ms", "tab:purple", "D", "-"),
        (2, "tessd topology + apply, 1 thread", "tessd", 1, "pipeline_ms", "tab:red", "o", "-"),
        (2, "tessd topology + apply, 2 threads", "tessd", 2, "pipeline_ms", "tab:red", "s", "--"),
        (2, "OSD RefineUniform + PrimvarRefiner", "osd", None, ("topology_ms", "primvar_ms"), "black", "^", "-"),
        (2, "Blender modifier, first evaluation", "blender", None, "cold_ms", "tab:purple", "D", "-"),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(20, 6.5), sharey=True)
    for panel, label, tool, threads, key, colour, marker, style in series:
        labelled = False
        for cage in d.cages:  # one line per cage through its levels, one legend entry per series
            pts = []
            for level in d.levels:
                keys = key if isinstance(key, tuple) else (key,)
                vals = [d.val(tool, cage, level, k, threads) for k in keys]
                n = d.out_vertices(cage, level)
                if n and all(v for v in vals):
                    pts.append((n, sum(vals) * 1e6 / n))
            if not pts:
                continue
            xs, ys = zip(*sorted(pts))
            axes[panel].plot(xs, ys, linestyle=style, marker=marker, color=colour, markersize=4, linewidth=1.1,
                             label=None if labelled else label)
            labelled = True
    # The paper's table 7.2: frame time per output polygon (closed quad meshes: vertices ≈ polygons).
    for i, (model, p) in enumerate(PAPER.items()):
        xs = p["faces"][1:]
        ys = [1e9 / fps / n for fps, n in zip(p["fps"][1:], xs)]
        axes[2].plot(xs, ys, linestyle="-", marker="*", color="tab:orange", markersize=6, linewidth=1.1,
                     label="paper 002, table 7.2 (frame time, per polygon)" if i == 0 else None)
    titles = ["Topology phase", "Apply phase (positions, every level)", "Whole pipeline (topology + apply)"]
    for ax, title in zip(axes, titles):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("output vertices (last level)")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("time per output vertex (ns)")
    fig.suptitle("Uniform Catmull-Clark, levels 1-5: median time per output vertex; one line per cage "
                 "(cube, torus knot 96, spot, quadknot, torus 8192) for each tool and phase")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--jsonl", default="bench/results/subdiv_raw.jsonl")
    ap.add_argument("--out", default="bench/results")
    ap.add_argument("--wall-s", type=float, default=None)
    ap.add_argument("--command", default="bash bench/run_subdiv.sh")
    a = ap.parse_args()
    d = Data(load(a.jsonl))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_plot(d, out / "subdiv_time_per_vertex.png")

    L = []
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    wall = f", whole run {a.wall_s / 60:.1f} min" if a.wall_s else ""
    adapters = sorted({r.get("adapter") for (t, *_), r in d.recs.items() if t == "tessd-gpu" and r.get("adapter")})
    blender = sorted({r.get("blender_version") for (t, *_), r in d.recs.items() if t == "blender" and r.get("blender_version")})
    osd_v = sorted({r.get("osd_version") for (t, *_), r in d.recs.items() if t == "osd" and r.get("osd_version")})
    L.append("# Subdivision benchmark: tessd vs OpenSubdiv vs Blender")
    L.append("")
    L.append(f"Machine: {machine()}; shared with other jobs during the run (noisy: medians, and ratios can move by "
             f"±30 %). Run {now}{wall}. Command: `{a.command}`. OpenSubdiv {', '.join(osd_v) or '?'} (Debian "
             f"`libosd-dev`, g++ -O2), Blender {', '.join(blender) or '?'} (`bpy`).")
    L.append("")
    L.append(f"**The \"GPU\" here is lavapipe, Mesa's software Vulkan driver running on the CPU** "
             f"(adapter: {'; '.join(adapters) or 'none'}): the tessd-gpu figures show that the GPU path works "
             f"end to end and what it costs on this machine, not what a GPU would do.")
    L.append("")
    L.append("## Method")
    L.append("")
    L.append("* **Cages** (closed; scheme Catmull–Clark; boundary edge-and-corner everywhere): "
             + ", ".join(f"`{c}` ({d.cage_faces.get(c)} faces)" for c in d.cages)
             + ". `cube.obj` (6 quads) and `torus_knot_96.obj` (96 quads, a tube around the (2,3) torus knot) are "
             "the paper's first two models' sizes, generated by `make_cages.py`; the paper's third model "
             "(Monsterfrog, 1292 faces) is stood in for by `quadknot.obj` (1440 quads, a real mesh from the shared "
             "data: trimesh's quad torus-knot tube); `spot_control_mesh.obj` (Keenan Crane's Spot cage: quads, "
             "triangles and pentagons) has extraordinary faces; `torus_8192.obj` (128 × 64 quads) is the "
             "reference case. Levels 1–5; each level is refined from the cage again.")
    L.append("* **tessd** (`bench-subdiv one`, one child process per cage × level × thread count, rayon pool of 1 or "
             "2 threads): *topology* = `Refiner::new` (faces of every level and one stencil table per level); "
             "*apply* = `Refiner::apply` of the cage's xyz (stride 3) through every level, allocation of each "
             f"level's output included. Each phase: one warm-up, then the median of budget ÷ warm-up time runs "
             f"({runs_range(d, 'tessd', 'topology_runs_ms', 'apply_runs_ms')} here). "
             "*pipeline* = topology + apply.")
    L.append(f"* **tessd GPU apply** (`bench-subdiv one --gpu`, tessd-gpu on wgpu/Vulkan): tables built on the CPU "
             "and uploaded once (not in the apply time); *call* = the whole `apply_timed` call (buffer setup, "
             "positions upload, one dispatch per level, copy, read-back); *device* = what `apply_timed` reports "
             "(submission to completion: positions upload, dispatches and copy, no buffer setup or read-back); "
             f"{runs_range(d, 'tessd-gpu', 'apply_runs_ms')} after a warm-up. Creating the device took "
             f"{span(d, 'tessd-gpu', 'init_ms')} ms and uploading the tables {span(d, 'tessd-gpu', 'upload_ms')} ms "
             f"(per process; not in the apply times).")
    L.append("* **OpenSubdiv** (`osd_bench --first-level L --levels L`, one process per cage × level, single "
             f"thread, a fresh `TopologyRefiner` per run, median of the runs that fit a time budget, "
             f"{runs_range(d, 'osd', 'repeat')} here; each run does all four steps, so the stencil build, "
             f"slow at high levels, sets the count): "
             "*RefineUniform* = `TopologyRefinerFactory::Create` + `RefineUniform` (the topology); "
             "*PrimvarRefiner* = `PrimvarRefiner::Interpolate` of xyz through every level into a preallocated "
             "buffer; *stencils* = `StencilTableFactory::Create` (last level from the cage directly) + "
             "`Osd::CpuEvaluator::EvalStencils`.")
    L.append("* **Blender** (`blender_bench.py`, Subdivision Surface modifier with use_limit_surface = False, "
             "i.e. uniform level-N control points; one process per cage × level, Blender's own threads on every "
             "core): *first evaluation* = adding the modifier and evaluating the depsgraph including building the "
             "subdivided mesh (Blender's OpenSubdiv topology refiner, evaluator tables, vertex evaluation and the "
             "output mesh with edges and corners) — the whole pipeline; *positions changed* = the same evaluation "
             "after moving the cage's vertices (Blender reuses its refiner and evaluator): its apply phase plus "
             f"building the output mesh. Warm-up, then the median of the runs that fit a time budget "
             f"({runs_range(d, 'blender', 'cold_runs_ms', 'pose_runs_ms')} here).")
    L.append("* **Peak memory**: each configuration in its own process; peak resident set (VmHWM) over the "
             "resident set before the measured work (cage loaded, heap trimmed, peak reset through "
             "`/proc/self/clear_refs`). tessd: topology phase peak, and the pipeline peak = max(topology peak, "
             "tables held + apply peak); tessd GPU: device creation, uploaded tables and apply buffers (on lavapipe "
             "\"device\" memory is host memory); OpenSubdiv: the whole `osd_bench` run (topology, primvar buffer, "
             "stencil table and its evaluation; the stencil table dominates); Blender: the modifier's runs.")
    L.append("")

    # ---- goals
    t1 = 1 if 1 in d.threads else (d.threads[0] if d.threads else None)
    L.append("## Goals")
    L.append("")
    L.append(f"Ratios per cage and level; *reference* = `{REF_CAGE}` at level {REF_LEVEL} "
             f"({fmt(d.out_vertices(REF_CAGE, REF_LEVEL))} output vertices); *gmean* = geometric mean over the "
             f"configurations with ≥ {fmt(LARGE)} output vertices (their count in brackets), *range* over every "
             f"configuration. A goal is met when both the reference case and the gmean reach it. OpenSubdiv runs "
             f"on one thread.")
    L.append("")
    L.append("| goal | target | reference | gmean (n) | range | met |")
    L.append("|---|---|---|---|---|---|")
    goals = {}
    for th in d.threads:
        rows = ratio_rows(d, lambda c, lv: d.val("osd", c, lv, "topology_ms"),
                          lambda c, lv, th=th: d.val("tessd", c, lv, "topology_ms", th))
        line, goals[f"topology_{th}t"] = goal_row(
            f"topology: OSD create + RefineUniform ÷ tessd topology ({th} thread{'s' if th > 1 else ''})",
            rows, GOAL_TOPOLOGY)
        L.append(line)
    for th in d.threads:
        rows = ratio_rows(d, lambda c, lv: d.val("osd", c, lv, "primvar_ms"),
                          lambda c, lv, th=th: d.val("tessd", c, lv, "apply_ms", th))
        line, goals[f"apply_{th}t"] = goal_row(
            f"apply: OSD PrimvarRefiner ÷ tessd apply ({th} thread{'s' if th > 1 else ''})", rows, GOAL_APPLY)
        L.append(line)
    # The same goals on like-for-like measures: OpenSubdiv's PrimvarRefiner writes into a
    # preallocated buffer (tessd's apply into reused buffers is the same situation);
    # RefineUniform builds connectivity only (tessd's corner arithmetic alone), while tessd's
    # topology phase also builds the stencil tables (OpenSubdiv's StencilTableFactory).
    for th in d.threads:
        ts = f"{th} thread{'s' if th > 1 else ''}"
        rows = ratio_rows(d, lambda c, lv: d.val("osd", c, lv, "topology_ms"),
                          lambda c, lv, th=th: d.val("tessd", c, lv, "connectivity_ms", th))
        line, goals[f"connectivity_{th}t"] = goal_row(
            f"like for like: OSD create + RefineUniform ÷ tessd connectivity only (corner arithmetic, {ts})",
            rows, GOAL_TOPOLOGY)
        L.append(line)
        rows = ratio_rows(d, lambda c, lv: (d.val("osd", c, lv, "topology_ms") or 0)
                          + (d.val("osd", c, lv, "stencil_build_ms") or 0) or None,
                          lambda c, lv, th=th: d.val("tessd", c, lv, "topology_ms", th))
        line, goals[f"topology_tables_{th}t"] = goal_row(
            f"like for like: OSD RefineUniform + StencilTableFactory ÷ tessd topology phase (tables too, {ts})",
            rows, GOAL_TOPOLOGY)
        L.append(line)
        rows = ratio_rows(d, lambda c, lv: d.val("osd", c, lv, "primvar_ms"),
                          lambda c, lv, th=th: d.val("tessd", c, lv, "apply_reused_ms", th))
        line, goals[f"apply_reused_{th}t"] = goal_row(
            f"like for like: OSD PrimvarRefiner (preallocated) ÷ tessd apply into reused buffers ({ts})",
            rows, GOAL_APPLY)
        L.append(line)
    prow = {th: paper_rows(d, th) for th in d.threads}
    for th in d.threads:
        l5 = [r for r in prow[th] if r["level"] == 5 and r["ratio"]]
        allr = [r["ratio"] for r in prow[th] if r["ratio"]]
        frog = [r for r in l5 if r["model"] == "Monsterfrog"]
        met = bool(l5) and all(r["ratio"] >= GOAL_PAPER for r in l5)
        frog_s = fmt(frog[0]["ratio"]) if frog else "–"
        L.append(f"| full pipeline: paper's frame time (table 7.2) ÷ tessd topology + apply ({th} "
                 f"thread{'s' if th > 1 else ''}), level 5 of the three models | ≥ {fmt(GOAL_PAPER)} | "
                 f"{frog_s} (1292-face model → quadknot) | {fmt(gmean([r['ratio'] for r in l5]))} ({len(l5)}) | "
                 f"{fmt(min(allr) if allr else None)}–{fmt(max(allr) if allr else None)} (levels 1–5) | "
                 f"{yes(met)} |")
        goals[f"paper_{th}t"] = {"level5": {r["model"]: r["ratio"] for r in l5}, "met": met}
    L.append("")
    L.append("The paper goal counts level 5 of its three models (the *reference* column there is its third "
             "model, the gmean is over the three): at low levels the paper's frame time is mostly drawing and "
             "its framework (the control meshes alone, not subdivided, drew at 1258–3271 frames/s), so "
             "the per-level table below shows every level, each against the goal.")
    L.append("")

    # ---- reference figures
    L.append(f"Reference figures (`{REF_CAGE}` to level {REF_LEVEL}, {fmt(d.out_faces(REF_CAGE, REF_LEVEL))} quads):")
    L.append("")
    L.append("| phase | reference (issue) | this run | M vertices/s this run |")
    L.append("|---|---|---|---|")
    n_out = d.out_vertices(REF_CAGE, REF_LEVEL) or 0
    n_all = None
    for th in d.threads:
        n_all = d.val("tessd", REF_CAGE, REF_LEVEL, "vertices_all_levels", th) or n_all

    def rate(ms, n):
        return fmt(n / ms / 1e3) if ms and n else "–"

    osd_t = d.val("osd", REF_CAGE, REF_LEVEL, "topology_ms")
    osd_p = d.val("osd", REF_CAGE, REF_LEVEL, "primvar_ms")
    osd_e = d.val("osd", REF_CAGE, REF_LEVEL, "stencil_eval_ms")
    L.append(f"| OSD create + RefineUniform | {fmt(REFERENCE['osd_topology_ms'])} ms | {fmt(osd_t)} ms | "
             f"{rate(osd_t, n_out)} (last level) |")
    L.append(f"| OSD PrimvarRefiner | {fmt(REFERENCE['osd_primvar_ms'])} ms (37 M vertices/s) | {fmt(osd_p)} ms | "
             f"{rate(osd_p, n_all)} (all levels' vertices) |")
    L.append(f"| OSD CpuEvaluator (stencils) | {fmt(REFERENCE['osd_stencil_eval_ms'])} ms (16.5 M vertices/s) | "
             f"{fmt(osd_e)} ms | {rate(osd_e, n_out)} (last level) |")
    L.append(f"| index-arithmetic refinement (Dupuy & Vanhoey 2021), topology | {fmt(REFERENCE['dupuy_vanhoey_ms'])} ms "
             f"| not run | – |")
    for th in d.threads:
        tt = d.val("tessd", REF_CAGE, REF_LEVEL, "topology_ms", th)
        ta = d.val("tessd", REF_CAGE, REF_LEVEL, "apply_ms", th)
        L.append(f"| tessd topology, {th} thread{'s' if th > 1 else ''} | – | {fmt(tt)} ms | {rate(tt, n_out)} (last level) |")
        L.append(f"| tessd apply, {th} thread{'s' if th > 1 else ''} | – | {fmt(ta)} ms | {rate(ta, n_all)} (all levels' vertices) |")
        tc = d.val("tessd", REF_CAGE, REF_LEVEL, "connectivity_ms", th)
        tr = d.val("tessd", REF_CAGE, REF_LEVEL, "apply_reused_ms", th)
        L.append(f"| tessd connectivity only, {th} thread{'s' if th > 1 else ''} | – | {fmt(tc)} ms | {rate(tc, n_out)} (last level) |")
        L.append(f"| tessd apply into reused buffers, {th} thread{'s' if th > 1 else ''} | – | {fmt(tr)} ms | {rate(tr, n_all)} (all levels' vertices) |")
    g = d.get("tessd-gpu", REF_CAGE, REF_LEVEL)
    if ok(g):
        L.append(f"| tessd GPU apply on lavapipe (call / device) | – | {fmt(g.get('apply_ms'))} / "
                 f"{fmt(g.get('device_ms'))} ms | {rate(g.get('apply_ms'), n_all)} |")
    L.append("")

    # ---- per-cage time tables
    L.append("## Times per cage and level (median ms)")
    L.append("")
    L.append("Columns: output vertices (last level); tessd topology and apply at 1 and 2 threads; tessd GPU apply "
             "on lavapipe (whole call / device part); OpenSubdiv create + RefineUniform, PrimvarRefiner, stencil "
             "table build + CpuEvaluator; Blender's modifier, first evaluation (whole pipeline) / after the "
             "positions changed. Run counts are in the raw JSON lines.")
    L.append("")
    for cage in d.cages:
        L.append(f"### {cage} ({d.cage_faces.get(cage)} faces)")
        L.append("")
        head = ["level", "out vertices"]
        head += [f"tessd topology {th}t" for th in d.threads]
        head += [f"tessd apply {th}t" for th in d.threads]
        head += ["GPU apply (lavapipe) call / device", "OSD RefineUniform", "OSD PrimvarRefiner",
                 "OSD stencils build + eval", "Blender first / positions changed"]
        L.append("| " + " | ".join(head) + " |")
        L.append("|" + "---|" * len(head))
        for level in d.levels:
            row = [str(level), fmt(d.out_vertices(cage, level))]
            row += [cell(d, "tessd", cage, level, "topology_ms", th) for th in d.threads]
            row += [cell(d, "tessd", cage, level, "apply_ms", th) for th in d.threads]
            row.append(f"{cell(d, 'tessd-gpu', cage, level, 'apply_ms')} / {cell(d, 'tessd-gpu', cage, level, 'device_ms')}")
            row.append(cell(d, "osd", cage, level, "topology_ms"))
            row.append(cell(d, "osd", cage, level, "primvar_ms"))
            row.append(f"{cell(d, 'osd', cage, level, 'stencil_build_ms')} + {cell(d, 'osd', cage, level, 'stencil_eval_ms')}")
            row.append(f"{cell(d, 'blender', cage, level, 'cold_ms')} / {cell(d, 'blender', cage, level, 'pose_ms')}")
            L.append("| " + " | ".join(row) + " |")
        L.append("")

    # ---- ratios per configuration
    L.append("## Ratios per cage and level")
    L.append("")
    L.append("topology = OSD create + RefineUniform ÷ tessd topology; apply = OSD PrimvarRefiner ÷ tessd apply "
             f"(goals ≥ {fmt(GOAL_TOPOLOGY)} and ≥ {fmt(GOAL_APPLY)}); Blender = Blender's first evaluation ÷ tessd "
             "pipeline (both whole pipelines; Blender also builds edges and corners of its output mesh).")
    L.append("")
    head = ["cage", "level", "out vertices"]
    head += [f"topology {th}t" for th in d.threads] + [f"apply {th}t" for th in d.threads]
    head += [f"Blender ÷ tessd {th}t" for th in d.threads]
    L.append("| " + " | ".join(head) + " |")
    L.append("|" + "---|" * len(head))
    for cage in d.cages:
        for level in d.levels:
            row = [cage, str(level), fmt(d.out_vertices(cage, level))]
            for key_o, key_t in (("topology_ms", "topology_ms"), ("primvar_ms", "apply_ms")):
                for th in d.threads:
                    a, b = d.val("osd", cage, level, key_o), d.val("tessd", cage, level, key_t, th)
                    row.append(fmt(a / b) if a and b else "–")
            for th in d.threads:
                a, b = d.val("blender", cage, level, "cold_ms"), d.val("tessd", cage, level, "pipeline_ms", th)
                row.append(fmt(a / b) if a and b else "–")
            L.append("| " + " | ".join(row) + " |")
    L.append("")

    # ---- paper
    L.append("## Against the paper's table 7.2 (CPU, frames per second)")
    L.append("")
    L.append("The paper re-subdivides every frame, so its frame time (1 / fps) is its whole pipeline plus drawing. "
             "Ours: tessd topology + apply on the stand-in cage (`cube.obj` = its 6-face cube, `torus_knot_96.obj` "
             "= its 96-face torus knot, `quadknot.obj` (1440 quads) for its 1292-face Monsterfrog, so ours refines "
             "11 % more faces there). *× paper* = paper frame time ÷ ours; *per face* = the same per output "
             "polygon (paper ms / its polygons ÷ our ms / our quads). OpenSubdiv create + RefineUniform + "
             "PrimvarRefiner is shown for scale.")
    L.append("")
    head = ["model (ours)", "level", "paper polygons", "paper fps", "paper ms/frame", "our quads"]
    head += [f"tessd {th}t ms" for th in d.threads] + [f"× paper {th}t" for th in d.threads]
    head += [f"per face {th}t" for th in d.threads] + [f"≥ {fmt(GOAL_PAPER)}× ({d.threads[0] if d.threads else ''}t)"]
    head += ["OSD ms", "OSD × paper"]
    L.append("| " + " | ".join(head) + " |")
    L.append("|" + "---|" * len(head))
    if d.threads:
        for i, r0 in enumerate(prow[d.threads[0]]):
            row = [f"{r0['model']} ({r0['cage']})", str(r0["level"]), fmt(r0["paper_faces"]), fmt(r0["fps"]),
                   fmt(r0["frame_ms"]), fmt(r0["faces"])]
            row += [fmt(prow[th][i]["tessd_ms"]) for th in d.threads]
            row += [fmt(prow[th][i]["ratio"]) for th in d.threads]
            row += [fmt(prow[th][i]["norm"]) for th in d.threads]
            row.append(yes(r0["ratio"] is not None and r0["ratio"] >= GOAL_PAPER) if r0["ratio"] else "–")
            row += [fmt(r0["osd_ms"]), fmt(r0["osd_ratio"])]
            L.append("| " + " | ".join(row) + " |")
    L.append("")

    # ---- memory
    L.append("## Peak memory (MB over the process's baseline)")
    L.append("")
    head = ["cage", "level", "out vertices"]
    head += [f"tessd topology {th}t" for th in d.threads] + [f"tessd pipeline {th}t" for th in d.threads]
    head += ["tessd tables", "tessd GPU (lavapipe)", "OSD (incl. stencil table)", "Blender"]
    L.append("| " + " | ".join(head) + " |")
    L.append("|" + "---|" * len(head))
    for cage in d.cages:
        for level in d.levels:
            row = [cage, str(level), fmt(d.out_vertices(cage, level))]
            row += [fmt(mb(d.val("tessd", cage, level, "topology_peak_kib", th))) for th in d.threads]
            row += [fmt(mb(d.val("tessd", cage, level, "peak_over_baseline_kib", th))) for th in d.threads]
            tb = None
            for th in d.threads:
                tb = d.val("tessd", cage, level, "table_bytes", th) or tb
            row.append(fmt(tb / 2**20) if tb else "–")
            row.append(fmt(mb(d.val("tessd-gpu", cage, level, "peak_over_baseline_kib"))))
            row.append(fmt(mb(d.val("osd", cage, level, "peak_over_baseline_kb"))))
            row.append(fmt(mb(d.val("blender", cage, level, "peak_over_baseline_kib"))))
            L.append("| " + " | ".join(row) + " |")
    L.append("")

    # ---- plot
    L.append("## Time per output vertex")
    L.append("")
    L.append("![time per output vertex vs output vertices](subdiv_time_per_vertex.png)")
    L.append("")
    L.append("`subdiv_time_per_vertex.png`: median time ÷ output vertices (last level) against output vertices, "
             "log-log; each tool and phase has one colour and marker, with a line per cage through its levels 1–5. "
             "Left: topology phases; middle: apply phases (tessd GPU on lavapipe, i.e. the CPU); right: whole "
             "pipelines (Blender's first evaluation) and the paper's table 7.2 as frame time per polygon "
             "(for closed quad meshes output vertices ≈ polygons).")
    L.append("")

    # ---- checks
    L.append("## Checks")
    L.append("")
    problems = []
    for cage in d.cages:
        for level in d.levels:
            counts = {}
            for (tool, th, c, lv), r in d.recs.items():
                if c == cage and lv == level and ok(r) and r.get("out_vertices") is not None:
                    counts[f"{tool}{'' if th is None else f' {th}t'}"] = (r["out_vertices"], r.get("out_faces"))
            if len(set(counts.values())) > 1:
                problems.append(f"output counts differ on {cage} L{level}: {counts}")
    for key, r in sorted(d.recs.items(), key=lambda kv: str(kv[0])):
        tool, th, cage, level = key
        name = f"{tool}{'' if th is None else f' {th}t'} {cage} L{level}"
        if r is None:
            continue
        if "error" in r:
            problems.append(f"{name} failed: {str(r['error'])[:300]}")
        elif "skipped" in r:
            problems.append(f"{name} skipped: {r['skipped']}")
        elif tool == "tessd-gpu" and isinstance(r.get("max_abs_vs_cpu"), (int, float)) and r["max_abs_vs_cpu"] > 1e-4:
            problems.append(f"{name}: GPU result differs from the CPU's by {r['max_abs_vs_cpu']:.3g}")
        elif tool == "osd" and (r.get("stencil_vs_primvar_max_abs") or 0) > 1e-4:
            problems.append(f"{name}: stencils differ from PrimvarRefiner by {r['stencil_vs_primvar_max_abs']:.3g}")
    gpu_err = [r.get("max_abs_vs_cpu") for (t, *_), r in d.recs.items()
               if t == "tessd-gpu" and ok(r) and isinstance(r.get("max_abs_vs_cpu"), (int, float))]
    L.append(f"* Output vertex and face counts agree between tessd, OpenSubdiv, Blender and the GPU path on every "
             f"cage and level" + (" except as listed below." if any("counts differ" in p for p in problems) else "."))
    if gpu_err:
        L.append(f"* GPU (lavapipe) vs CPU apply: largest coordinate difference {max(gpu_err):.3g} over "
                 f"{len(gpu_err)} configurations.")
    osd_err = [r.get("stencil_vs_primvar_max_abs") for (t, *_), r in d.recs.items() if t == "osd" and ok(r)]
    if osd_err:
        L.append(f"* OpenSubdiv stencils vs PrimvarRefiner: largest difference {max(osd_err):.3g}.")
    few = []
    for (tool, th, cage, level), r in d.recs.items():
        if not ok(r):
            continue
        for k in ("topology_runs_ms", "apply_runs_ms", "cold_runs_ms", "pose_runs_ms"):
            if k in r and len(r[k]) < 3:
                few.append(f"{tool}{'' if th is None else f' {th}t'} {cage} L{level} {k[:-8]} ({len(r[k])})")
        if tool == "osd" and r.get("repeat", 3) < 3:
            few.append(f"osd {cage} L{level} ({r['repeat']})")
    if few:
        L.append("* Timed fewer than 3 times (one run over the budget): " + "; ".join(sorted(few)) + ".")
    for p in problems:
        L.append(f"* {p}")
    L.append("")
    (out / "subdiv.md").write_text("\n".join(L))
    print(f"wrote {out / 'subdiv.md'} and {out / 'subdiv_time_per_vertex.png'}")
    for k, v in goals.items():
        print(k, json.dumps(v))


if __name__ == "__main__":
    main()
