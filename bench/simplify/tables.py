#!/usr/bin/env python3
"""Markdown tables of issue 33's stage times and headline, before beside after.

    tables.py [--stages FILE.json] [--headline FILE.json] --out FILE.md [--title TEXT]

Used by `report.py` (before = the committed `simplify_stages_before.json` and
`simplify_headline_before.json`, after = this run's) and on its own to write the Markdown of
one set of results (both given files are then shown as "before").
"""

import argparse
import json
from pathlib import Path

SHORT = {"tessd-grid-bary": "grid, barycentre", "tessd-grid-quadric": "grid, quadric",
         "tessd-quality-bary": "quality, barycentre", "tessd-quality-quadric": "quality, quadric",
         "tessd-complexity-bary": "complexity, barycentre", "tessd-complexity-quadric": "complexity, quadric"}


def _ms(x):
    if x is None:
        return "–"
    ms = x * 1e3
    return f"{ms:.0f}" if ms >= 100 else f"{ms:.3g}" if ms >= 0.01 else "0"


def _load(path):
    return json.loads(Path(path).read_text()) if path and Path(path).exists() else None


def stage_tables(after, before, level="###"):
    """One table per tessd mode: rows = stages (before's, then those only after has), columns =
    each torus before and after; the medians of one-thread calls (ms)."""
    sets = [("before", before), ("after", after)]
    sets = [(n, d) for n, d in sets if d]
    if not sets:
        return []
    L = []
    for n, d in sets:
        m = d["meta"]
        lab = (m.get("label") or n).removeprefix(f"{n}: ")
        L.append(f"*{n}*: {lab}, {m.get('repeat')} interleaved rounds, median per stage, "
                 f"one thread, target {m.get('fraction', 0.1) * 100:g} % of the input vertices, "
                 f"{m.get('cpu_model')} ({m.get('nproc')} cores).")
        L.append("")
    methods = []
    for _, d in sets:
        for r in d["runs"]:
            if r["method"] not in methods:
                methods.append(r["method"])
    for meth in methods:
        cols, stages = [], []
        for n, d in sets:
            for r in d["runs"]:
                if r["method"] == meth:
                    cols.append((n, r))
                    at = 0  # a new stage goes after the last stage already listed
                    for s in r["stages"]:
                        if s["stage"] in stages:
                            at = stages.index(s["stage"]) + 1
                        else:
                            stages.insert(at, s["stage"])
                            at += 1
        L.append(f"{level} {SHORT.get(meth, meth)} (`{meth}`)")
        L.append("")
        L.append("| stage | " + " | ".join(f"{n}: {r['mesh']} ms (share)" for n, r in cols) + " |")
        L.append("|---|" + "---|" * len(cols))
        for st in stages:
            cells = []
            for _, r in cols:
                s = next((s for s in r["stages"] if s["stage"] == st), None)
                if s is None:
                    cells.append("–")
                    continue
                share = s["median_s"] / r["time_s"] * 100 if r["time_s"] else 0
                spans = f", {s['spans']}×" if s.get("spans", 1) > 1 else ""
                cells.append(f"{_ms(s['median_s'])} ({share:.0f} %{spans})")
            name = "start (until the first callback)" if st == "start" else st
            L.append(f"| {name} | " + " | ".join(cells) + " |")
        L.append("| **whole call** | " + " | ".join(f"**{_ms(r['time_s'])}**" for _, r in cols) + " |")
        L.append("| output vertices | " + " | ".join(str(r["out_vertices"]) for _, r in cols) + " |")
        speed = []
        for n, r in cols:
            if n != "after" or not before:
                continue
            b = next((x for x in before["runs"] if x["method"] == meth and x["mesh"] == r["mesh"]), None)
            if b and r["time_s"]:
                speed.append(f"{r['mesh']} {b['time_s'] / r['time_s']:.2f}×")
        L.append("")
        if speed:
            L.append("After vs before (whole call, before ÷ after): " + ", ".join(speed) + ".")
            L.append("")
    return L


def headline_table(after, before):
    """The issue's headline table: tessd (daemon, arrays in, one thread) vs its peer in
    process at the same output size; before and after side by side when both exist."""
    sets = [(n, d) for n, d in [("before", before), ("after", after)] if d]
    if not sets:
        return []
    m0 = sets[0][1]["meta"]
    other = [f"{n}: {d['meta']['mesh']}" for n, d in sets if d["meta"]["mesh"] != m0["mesh"]]
    L = [f"{m0['mesh']} ({m0['input_triangles']} triangles, {m0['input_vertices']} vertices)"
         + (f" (**other inputs**: {', '.join(other)}; not comparable)" if other else "") + ", one thread; "
         "tessd = the daemon's `elapsed_ms` with the mesh sent as arrays, peer = meshoptimizer in process "
         "matched to tessd's output vertex count; *ratio* = peer time ÷ tessd time (> 1: tessd faster). "
         "Medians (runs).", ""]
    head = "| mode | peer |"
    rule = "|---|---|"
    for n, _ in sets:
        head += f" {n}: tessd ms | {n}: peer ms | {n}: vertices | {n}: ratio |"
        rule += "---|---|---|---|"
    L += [head, rule]
    labels = []
    for _, d in sets:
        for r in d["rows"]:
            if r["row"] not in labels:
                labels.append(r["row"])
    for lab in labels:
        peer = ""
        cells = []
        for _, d in sets:
            r = next((r for r in d["rows"] if r["row"] == lab), None)
            if r is None:
                cells.append("– | – | – | –")
                continue
            peer = {"meshopt-sloppy": "simplifySloppy", "meshopt-simplify": "meshoptimizer `simplify`"}.get(
                r["peer"], r["peer"])
            if "error" in r:
                cells.append(f"failed: {r['error'][:80]} | – | – | –")
                continue
            pv = "" if r.get("peer_hit", True) else f" (peer {r['peer_out_vertices']}, miss)"
            cells.append(f"{r['tessd_ms']:.5g} ({len(r['tessd_runs_ms'])}) | {r['peer_ms']:.5g} "
                         f"({len(r['peer_runs_ms'])}) | {r['out_vertices']}{pv} | **{r['ratio']:.2f}×**")
        L.append(f"| {lab} | {peer} | " + " | ".join(cells) + " |")
    L.append("")
    return L


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--stages")
    ap.add_argument("--headline")
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="Simplification stage times and headline")
    a = ap.parse_args()
    L = [f"# {a.title}", ""]
    h = _load(a.headline)
    if h:
        L += ["## Headline", ""] + headline_table(None, h)
    s = _load(a.stages)
    if s:
        L += ["## Stage times", ""] + stage_tables(None, s)
    Path(a.out).write_text("\n".join(L) + "\n")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
