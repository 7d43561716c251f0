#!/usr/bin/env python3
"""Report of the B-Rep benchmark (bench/run_brep.sh).

    report.py [--jsonl bench/results/brep_raw.jsonl] [--manifest WORK/parts.json]
              [--out bench/results] [--wall-s SECONDS] [--load-start "a b c"] [--load-end "a b c"]
              [--command "bash bench/run_brep.sh"]

Reads the JSON lines of `bench-brep run` (tool "tessd": kinds doc, trim, classify, tessellate,
child, export) and `peer_ocp.py mesh` (tool "ocp") and writes `brep.md`: paper 000's table 1
(faces per surface type, trims per curve type, quadratic pieces at ε = 0.1 and 0.01 mm),
table 3 (trim structure bytes vs OCP's static tessellation at 36 bytes per vertex), table 4
(quadtree depths, depth-13 failures, separating lines, k_i), build times per face and the CPU
classification rate, tessd's tessellation vs OCP's BRepMesh_IncrementalMesh (time, triangles,
cracks, deviation), the goals and whether each is met, and everything odd the run met; plus
`brep_bytes.png` (trim bytes vs static tessellation bytes) and `brep_tessellation.png` (time vs
triangles). Run with /work/main/.venv-bench/bin/python (needs matplotlib).
"""

import argparse
import datetime
import json
import math
import os
import statistics
import sys
from collections import Counter, defaultdict
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from report_common import gmean, machine, yes  # noqa: E402

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

EPS = (0.1, 0.01)
TOLS = (0.1, 0.01)
SURFACES = ["plane", "cylinder", "cone", "sphere", "torus", "revolution", "extrusion", "bspline"]
CURVES = ["line", "circle", "ellipse", "bspline"]
GOAL_BYTES = 0.3  # trim bytes / static tessellation bytes at 0.01 mm
GOAL_FAIL_PCT = 0.22  # faces with a depth-13 failure, % of faces
GOAL_SPEED = 5.0  # OCP time / tessd time at equal tolerance
MAX_DEPTH = 13

# Paper 000, table 1 (models: satellite, aircraft section, piston): trim curves and quadratics.
PAPER_T1 = {
    "Satellite": {"faces": 96448, "curves": 471230, "q01": 690140, "q001": 941476},
    "Aircraft section": {"faces": 702064, "curves": 3702916, "q01": 5975794, "q001": 8661440},
    "Piston": {"faces": 790, "curves": 4186, "q01": 5695, "q001": 7854},
}
# Table 3 (MB): trim structure (“Découpe”) at ε = 0.1 / 0.01 mm, static tessellation at 0.1 / 0.01 mm.
PAPER_T3 = {
    "Aircraft section": (197, 294, 246, 1010),
    "Satellite": (31, 43.7, 42.5, 139.3),
    "Piston": (0.309, 0.440, 0.629, 2.683),
}
# Table 4: patches reaching depth 13 (count, % of patches) at 0.1 / 0.01 mm.
PAPER_T4 = {
    "Aircraft section": ((365, 0.12), (668, 0.22)),
    "Satellite": ((147, 0.23), (333, 0.5)),
    "Piston": ((0, 0), (0, 0)),
}


def fmt(x, sig=3):
    """A number with `sig` significant digits, thin-space thousands, no exponent."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return f"{x:,}".replace(",", " ")
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    if mag < -4:
        return f"{x:.{sig - 1}e}"
    if mag >= sig - 1:
        return f"{x:,.0f}".replace(",", " ")
    return f"{x:.{sig - 1 - mag}f}"


def kb(b):
    return None if b is None else b / 1024.0


def pct(x):
    return "–" if x is None else f"{100 * x:.2f} %"


def pctl(xs, q):
    xs = sorted(xs)
    if not xs:
        return None
    k = (len(xs) - 1) * q
    lo, hi = math.floor(k), math.ceil(k)
    return xs[lo] + (xs[hi] - xs[lo]) * (k - lo)


class Data:
    def __init__(self, jsonl, manifest):
        self.manifest = manifest
        self.doc, self.trim, self.classify, self.tess, self.ocp = {}, {}, {}, {}, {}
        self.errors = []  # (part, what, error)
        self.ocp_versions = None
        for line in open(jsonl):
            if not line.strip():
                continue
            r = json.loads(line)
            part, tool, kind = r.get("part"), r.get("tool"), r.get("kind")
            if tool == "ocp":
                if "error" in r and "deflection" not in r:
                    self.errors.append((part, "OCP read", r["error"]))
                    continue
                self.ocp[(part, r["deflection"], bool(r["parallel"]))] = r
            elif kind == "doc":
                self.doc[part] = r
            elif kind == "trim":
                self.trim[(part, r["eps_mm"])] = r
            elif kind == "classify":
                self.classify[(part, r["eps_mm"])] = r
            elif kind == "tessellate":
                self.tess[(part, r["tol_mm"], r["threads"])] = r
            elif kind == "child":
                if r.get("step") == "tessellate":
                    self.tess[(part, r["tol_mm"], r["threads"])] = r
                where = f"{r.get('step', '?')} child" + (f" tol {r['tol_mm']} mm, {r['threads']} threads"
                                                        if r.get("step") == "tessellate" else "")
                self.errors.append((part, where, f"{r['error']} (in: {r.get('last_step', '')})"))
            elif "error" in r:
                self.errors.append((part, kind or "?", r["error"]))
        order = [p["name"] for p in manifest] if manifest else []
        seen = {k[0] for k in self.tess} | set(self.doc) | {k[0] for k in self.ocp}
        self.parts = [p for p in order if p in seen] + sorted(seen - set(order))

    def kind(self, part):
        for p in self.manifest:
            if p["name"] == part:
                return p.get("kind")
        return None

    def faces(self, part):
        d = self.doc.get(part)
        return d["stats"]["faces"] if d and "stats" in d else None

    def mm(self, part):
        d = self.doc.get(part)
        return d.get("mm_per_unit", 1.0) if d else 1.0

    def trim_faces(self, part, eps):
        r = self.trim.get((part, eps))
        return r["faces"] if r else []

    def built(self, part, eps):
        return [f for f in self.trim_faces(part, eps) if "error" not in f]

    def trim_sum(self, part, eps, key):
        r = self.trim.get((part, eps))
        if not r:
            return None
        return sum(f.get(key, 0) or 0 for f in r["faces"] if "error" not in f)

    def tess_ok(self, part, tol, threads):
        r = self.tess.get((part, tol, threads))
        return r if r and "error" not in r and "skipped" not in r and "time_ms" in r else None

    def ocp_ok(self, part, tol, parallel):
        r = self.ocp.get((part, tol, parallel))
        return r if r and "error" not in r and "skipped" not in r and "time_ms" in r else None

    def ocp_any(self, part, tol):
        return self.ocp_ok(part, tol, False) or self.ocp_ok(part, tol, True)

    def tess_any(self, part, tol):
        return self.tess_ok(part, tol, 2) or self.tess_ok(part, tol, 1)

    def best(self, part, tol, tool):
        if tool == "tessd":
            rs = [self.tess_ok(part, tol, t) for t in (1, 2)]
        else:
            rs = [self.ocp_ok(part, tol, p) for p in (False, True)]
        rs = [r for r in rs if r]
        return min(rs, key=lambda r: r["time_ms"]) if rs else None


def tess_cell(d, part, tol, threads):
    r = d.tess.get((part, tol, threads))
    if r is None:
        return "–"
    if "skipped" in r:
        return "not run"
    if "error" in r:
        return f"> {r['error'].split('after the ')[1].split(' s')[0]} s" if "killed after" in r["error"] else "**failed**"
    return fmt(r["time_ms"]) + ("¹" if r.get("only_warmup") else "")


def ocp_cell(d, part, tol, parallel):
    r = d.ocp.get((part, tol, parallel))
    if r is None:
        return "–"
    if "skipped" in r:
        return "not run"
    if "error" in r:
        return "**failed**"
    return fmt(r["time_ms"]) + ("¹" if r.get("only_warmup") else "")


def table1(d, L):
    L.append("## Table 1: faces, trim curves and quadratic pieces\n")
    L.append("Faces per basis surface type (the format's types; OCP's offset and other surfaces arrive as "
             "`bspline` through NurbsConvert), as `Document::stats` counts them:\n")
    L.append("| part | " + " | ".join(SURFACES) + " | faces | loops | holes | most trims in a face |")
    L.append("|---|" + "---|" * (len(SURFACES) + 4))
    tot = Counter()
    for p in d.parts:
        doc = d.doc.get(p)
        if not doc or "stats" not in doc:
            L.append(f"| {p} | " + " | ".join(["–"] * (len(SURFACES) + 4)) + " |")
            continue
        st = doc["stats"]
        fs = st["faces_by_surface"]
        for s in SURFACES:
            tot[s] += fs.get(s, 0)
        tot["faces"] += st["faces"]
        tot["loops"] += st["loops"]
        tot["holes"] += st["holes"]
        L.append(f"| {p} | " + " | ".join(fmt(fs.get(s, 0)) for s in SURFACES)
                 + f" | {fmt(st['faces'])} | {fmt(st['loops'])} | {fmt(st['holes'])} | {fmt(doc.get('max_trims'))} |")
    L.append("| **all** | " + " | ".join(f"**{fmt(tot[s])}**" for s in SURFACES)
             + f" | **{fmt(tot['faces'])}** | **{fmt(tot['loops'])}** | **{fmt(tot['holes'])}** | |")
    L.append("")
    L.append("Trim curves per type (B-spline trims split by degree as the paper does) and the connected "
             "quadratic pieces after approximation (section 3.1: fit, knot removal to the face's (u, v) "
             "tolerance derived from ε, flat pieces made lines; circles and ellipses cut directly into "
             "equal-angle pieces within the same share of the tolerance) at ε = 0.1 and 0.01 mm in world units; "
             "*pieces* = curved + lines (the paper's “Quadratiques”), *lines* = how many of them are line "
             "segments; *per trim* = pieces at 0.01 mm ÷ trims:\n")
    L.append("| part | line | circle | ellipse | B-spline | deg 1 | deg 2–4 | deg 5 | deg ≥ 6 | rational | trims "
             "| pieces 0.1 mm (lines) | pieces 0.01 mm (lines) | per trim |")
    L.append("|---|" + "---|" * 13)
    tot = Counter()
    any_failed = False
    for p in d.parts:
        doc = d.doc.get(p)
        if not doc or "stats" not in doc:
            continue
        st = doc["stats"]
        tc = st["trims_by_curve"]
        deg = {int(k): v for k, v in st["bspline_trims_by_degree"].items()}
        groups = [deg.get(1, 0), sum(v for k, v in deg.items() if 2 <= k <= 4), deg.get(5, 0),
                  sum(v for k, v in deg.items() if k >= 6)]
        q = {}
        for e in EPS:
            n, ln = d.trim_sum(p, e, "quadratics"), d.trim_sum(p, e, "lines")
            failed = d.trim.get((p, e), {}).get("failed_faces", 0)
            q[e] = "–" if n is None else f"{fmt(n)} ({fmt(ln)})" + ("²" if failed else "")
            any_failed = any_failed or bool(failed)
            tot[f"q{e}"] += n or 0
            tot[f"l{e}"] += ln or 0
        for c in CURVES:
            tot[c] += tc.get(c, 0)
        for i, g in enumerate(groups):
            tot[f"g{i}"] += g
        tot["rational"] += st["rational_trims"]
        tot["trims"] += st["trims"]
        per = (d.trim_sum(p, 0.01, "quadratics") or 0) / st["trims"] if st["trims"] else None
        L.append(f"| {p} | " + " | ".join(fmt(tc.get(c, 0)) for c in CURVES) + " | "
                 + " | ".join(fmt(g) for g in groups)
                 + f" | {fmt(st['rational_trims'])} | {fmt(st['trims'])} | {q[0.1]} | {q[0.01]} | {fmt(per)} |")
    L.append("| **all** | " + " | ".join(f"**{fmt(tot[c])}**" for c in CURVES) + " | "
             + " | ".join(f"**{fmt(tot[f'g{i}'])}**" for i in range(4))
             + f" | **{fmt(tot['rational'])}** | **{fmt(tot['trims'])}** | **{fmt(tot['q0.1'])} ({fmt(tot['l0.1'])})** "
             f"| **{fmt(tot['q0.01'])} ({fmt(tot['l0.01'])})** | **{fmt(tot['q0.01'] / tot['trims'] if tot['trims'] else None)}** |")
    L.append("")
    if any_failed:
        L.append("² some faces of the part have no structure (see *Problems found*); their pieces are not counted.\n")
    rows = [f"{m}: {fmt(v['curves'])} curves → {fmt(v['q01'])} / {fmt(v['q001'])} pieces "
            f"({fmt(v['q01'] / v['curves'])} / {fmt(v['q001'] / v['curves'])} per curve)" for m, v in PAPER_T1.items()]
    ratio01 = tot["q0.1"] / tot["trims"] if tot["trims"] else None
    ratio001 = tot["q0.01"] / tot["trims"] if tot["trims"] else None
    L.append(f"Paper's table 1 for comparison (0.1 / 0.01 mm): {'; '.join(rows)}. This set: "
             f"{fmt(tot['trims'])} trims → {fmt(tot['q0.1'])} / {fmt(tot['q0.01'])} pieces "
             f"({fmt(ratio01)} / {fmt(ratio001)} per trim).\n")


def table3(d, L):
    L.append("## Table 3: trim structure memory vs static tessellation\n")
    L.append("*Trim* = the packed GPU layout of every face's structure (`TrimStats::bytes`: header, nodes, "
             "curves, separating lines), summed over the faces, at ε = 0.1 / 0.01 mm. *Static* = OCP's "
             "`BRepMesh_IncrementalMesh` at linear deflection 0.1 / 0.01 mm (absolute, angular 0.5 rad): "
             "the nodes of every face's `Poly_Triangulation` (a face's own vertex array, so edge vertices "
             "count once per face using them) × 36 bytes, the paper's rule (section 8, table 3: coordinates, "
             "normal and colour per vertex; section 7 gives no other counting). *Ratio* = trim ÷ static at "
             "the same tolerance. *tessd mesh* = the same 36-byte rule applied to tessd-tessellate's mesh "
             "at 0.01 mm (per-face vertices), for context. Sizes in KiB.\n")
    L.append("| part | trim 0.1 mm | trim 0.01 mm | static 0.1 mm (vertices) | static 0.01 mm (vertices) "
             "| ratio 0.1 mm | ratio 0.01 mm | tessd mesh 0.01 mm |")
    L.append("|---|---|---|---|---|---|---|---|")
    tot = defaultdict(float)
    tot_nh = defaultdict(float)
    per_part = []
    for p in d.parts:
        tb = {e: d.trim_sum(p, e, "bytes") for e in EPS}
        ob = {t: (d.ocp_any(p, t) or {}).get("bytes_36") for t in TOLS}
        ov = {t: (d.ocp_any(p, t) or {}).get("vertices") for t in TOLS}
        ours = d.tess_any(p, 0.01)
        r = {t: (tb[t] / ob[t] if tb[t] is not None and ob[t] else None) for t in TOLS}
        if r[0.01] is not None:
            per_part.append((p, r[0.01]))
        incomplete = any(d.trim.get((p, e), {}).get("failed_faces", 0) for e in EPS)
        for e in EPS:
            if tb[e] is not None and ob[e]:
                for acc in ([tot] if "hammer" in p else [tot, tot_nh]):
                    acc[f"t{e}"] += tb[e]
                    acc[f"o{e}"] += ob[e]
        L.append(f"| {p}{'²' if incomplete else ''} | {fmt(kb(tb[0.1]))} | {fmt(kb(tb[0.01]))} | "
                 f"{fmt(kb(ob[0.1]))} ({fmt(ov[0.1])}) | {fmt(kb(ob[0.01]))} ({fmt(ov[0.01])}) | "
                 f"{fmt(r[0.1])} | {fmt(r[0.01])} | {fmt(kb(36 * ours['vertices']) if ours else None)} |")

    def total_row(name, acc):
        rt = {t: acc[f"t{t}"] / acc[f"o{t}"] if acc[f"o{t}"] else None for t in TOLS}
        L.append(f"| **{name}** | **{fmt(kb(acc['t0.1']))}** | **{fmt(kb(acc['t0.01']))}** | "
                 f"**{fmt(kb(acc['o0.1']))}** | **{fmt(kb(acc['o0.01']))}** | **{fmt(rt[0.1])}** | "
                 f"**{fmt(rt[0.01])}** | |")
        return rt

    rt = total_row("all parts", tot)
    rt_nh = total_row("all but hammer.iges", tot_nh)
    L.append("")
    paper = "; ".join(f"{m}: {fmt(a / c)} at 0.1 mm, {fmt(b / e)} at 0.01 mm" for m, (a, b, c, e) in PAPER_T3.items())
    L.append(f"Paper's ratios (trim ÷ static, table 3): {paper}.\n")
    return rt, rt_nh, per_part


def table4(d, L):
    L.append("## Table 4: quadtree depth, depth-13 failures, separating lines, k_i\n")
    L.append("Per part and ε: quadtree nodes (all faces; mean per face), the deepest leaf, the faces "
             "(“patches”) with at least one failed leaf — a depth-13 leaf still crossed by more than two "
             "curves or by two without a separating line (section 8, figure 14) — as a count and % of the "
             "part's faces, the failed leaves and their mean per failing face (the paper's “nodes per "
             "patch”), separating lines (two-curve leaves), and the level k_i of section 6 (40 % of the "
             "domain classifiable by triangles at 2^k × 2^k), as `k:faces` (`none`: no level reaches 40 %).\n")
    totals = {}
    for e in EPS:
        L.append(f"### ε = {e} mm\n")
        L.append("| part | faces | nodes (per face) | deepest | failing faces (%) | failed leaves (per failing face) "
                 "| separating lines | k_i |")
        L.append("|---|---|---|---|---|---|---|---|")
        t = Counter()
        kdist = Counter()
        for p in d.parts:
            fs = d.built(p, e)
            nf = len(d.trim_faces(p, e))
            if not nf:
                continue
            nodes = sum(f["nodes"] for f in fs)
            deep = max((f["max_depth"] for f in fs), default=None)
            failing = [f for f in fs if f["failures"] > 0]
            leaves = sum(f["failures"] for f in failing)
            seps = sum(f["separating_lines"] for f in fs)
            ks = Counter("none" if f["k_i"] is None else f["k_i"] for f in fs)
            kdist.update(ks)
            t.update(faces=nf, nodes=nodes, failing=len(failing), leaves=leaves, seps=seps)
            t["deep"] = max(t["deep"], deep or 0)
            kstr = " ".join(f"{k}:{n}" for k, n in sorted(ks.items(), key=lambda kv: (kv[0] == "none", kv[0]
                                                                                      if kv[0] != "none" else 0)))
            L.append(f"| {p} | {fmt(nf)} | {fmt(nodes)} ({fmt(nodes / len(fs) if fs else None)}) | {fmt(deep)} | "
                     f"{fmt(len(failing))} ({pct(len(failing) / nf)}) | {fmt(leaves)} "
                     f"({fmt(leaves / len(failing) if failing else 0)}) | {fmt(seps)} | {kstr} |")
        kstr = " ".join(f"{k}:{n}" for k, n in sorted(kdist.items(), key=lambda kv: (kv[0] == "none", kv[0]
                                                                                      if kv[0] != "none" else 0)))
        L.append(f"| **all** | **{fmt(t['faces'])}** | **{fmt(t['nodes'])}** ({fmt(t['nodes'] / t['faces'] if t['faces'] else None)}) "
                 f"| **{fmt(t['deep'])}** | **{fmt(t['failing'])} ({pct(t['failing'] / t['faces'] if t['faces'] else None)})** "
                 f"| **{fmt(t['leaves'])}** ({fmt(t['leaves'] / t['failing'] if t['failing'] else 0)}) | **{fmt(t['seps'])}** | {kstr} |")
        L.append("")
        none = [f for p in d.parts for f in d.built(p, e) if f["k_i"] is None]
        found = Counter(f.get("k_i_to_6") for f in none)
        if none and any("k_i_to_6" in f for f in none):
            L.append(f"k_i is `none` on {len(none)} of {t['faces']} faces. The crate searches k only up to the face's "
                     f"deepest leaf (at least 1); searching every level up to 6 (tessellation factor 64, section 7) "
                     f"with the crate's own `Quadtree::classifiable_at` finds k for {len(none) - found.get(None, 0)} of "
                     f"them: " + " ".join(f"{k}:{n}" for k, n in sorted(found.items(), key=lambda kv: (kv[0] is None, kv[0] or 0)))
                     + " (see *Problems found*).\n")
        totals[e] = t
    # depth histogram over the whole set
    L.append("Leaves per depth over the whole set (the quadtree's depth histogram, all faces):\n")
    hists = {}
    for e in EPS:
        h = []
        for p in d.parts:
            r = d.trim.get((p, e))
            if r:
                for i, n in enumerate(r.get("depth_histogram", [])):
                    if len(h) <= i:
                        h += [0] * (i + 1 - len(h))
                    h[i] += n
        hists[e] = h
    depth = max((len(h) for h in hists.values()), default=0)
    L.append("| ε | " + " | ".join(str(i) for i in range(depth)) + " |")
    L.append("|---|" + "---|" * depth)
    for e in EPS:
        h = hists[e] + [0] * (depth - len(hists[e]))
        L.append(f"| {e} mm | " + " | ".join(fmt(n) for n in h) + " |")
    L.append("")
    paper = "; ".join(f"{m}: {a[0]} ({a[1]} %) at 0.1 mm, {b[0]} ({b[1]} %) at 0.01 mm" for m, (a, b) in PAPER_T4.items())
    L.append(f"Paper's table 4 (patches reaching depth 13): {paper}.\n")
    return totals, hists


def build_and_classify(d, L):
    L.append("## Build time per face and CPU classification rate\n")
    L.append("Build = `TrimStructure::build` of one face (approximation, quadtree, separating lines, coverage, "
             "k_i, packing; its own `build_time`), faces one after the other on one thread. Classification = "
             "`TrimStructure::classify(u, v)` (exact, no footprint), single thread, on ≥ 1 M random (u, v) "
             "spread evenly over the part's faces and uniform in each face's bounds; median of 5 passes after "
             "a warm-up; *on* = the share of points on the face.\n")
    L.append("| part | faces | build ε=0.1 median / p95 / max / total ms | build ε=0.01 median / p95 / max / total ms "
             "| classify ε=0.1 M points/s | classify ε=0.01 M points/s (ns/point) | on |")
    L.append("|---|---|---|---|---|---|---|")
    all_ms = {e: [] for e in EPS}
    rates = {e: [] for e in EPS}
    slow = []
    for p in d.parts:
        cells = []
        for e in EPS:
            ms = [f["build_ms"] for f in d.built(p, e)]
            all_ms[e] += ms
            for f in d.built(p, e):
                slow.append((f["build_ms"], p, f["id"], e, f))
            cells.append(" / ".join(fmt(x) for x in (statistics.median(ms) if ms else None, pctl(ms, 0.95),
                                                     max(ms) if ms else None, sum(ms) if ms else None)))
        c = {e: d.classify.get((p, e)) for e in EPS}
        for e in EPS:
            if c[e] and "points_per_s" in c[e]:
                rates[e].append(c[e]["points_per_s"])
        nf = len(d.trim_faces(p, 0.01)) or d.faces(p)
        r01 = fmt(c[0.1]["points_per_s"] / 1e6) if c[0.1] and "points_per_s" in c[0.1] else "–"
        r001 = (f"{fmt(c[0.01]['points_per_s'] / 1e6)} ({fmt(c[0.01]['ns_per_point'])})"
                if c[0.01] and "points_per_s" in c[0.01] else "–")
        on = pct(c[0.01]["on_fraction"]) if c[0.01] and "on_fraction" in c[0.01] else "–"
        L.append(f"| {p} | {fmt(nf)} | {cells[0]} | {cells[1]} | {r01} | {r001} | {on} |")
    cells = []
    for e in EPS:
        ms = all_ms[e]
        cells.append(" / ".join(fmt(x) for x in (statistics.median(ms) if ms else None, pctl(ms, 0.95),
                                                 max(ms) if ms else None, sum(ms) if ms else None)))
    L.append(f"| **all faces** | **{fmt(len(all_ms[0.01]))}** | **{cells[0]}** | **{cells[1]}** | "
             f"**{fmt(statistics.median(rates[0.1]) / 1e6) if rates[0.1] else '–'}** (median of parts) | "
             f"**{fmt(statistics.median(rates[0.01]) / 1e6) if rates[0.01] else '–'}** (median of parts) | |")
    L.append("")
    slow.sort(key=lambda s: -s[0])
    if slow:
        L.append("Slowest face builds: " + "; ".join(
            f"{p} face {fid} at ε={e} ({f['surface']}, {f['trims']} trims, {fmt(f['quadratics'])} pieces, "
            f"{fmt(f['nodes'])} nodes): {fmt(ms)} ms" for ms, p, fid, e, f in slow[:6]) + ".\n")
    return all_ms, rates


def tessellation(d, L):
    L.append("## Tessellation: tessd-tessellate vs OCP BRepMesh_IncrementalMesh\n")
    L.append("Equal tolerance: tessd `tessellate(doc, &Options::new(tol))` (chordal tolerance in document units = "
             "mm here, default angle 0.5 rad), in a rayon pool of 1 or 2 threads, the whole call timed "
             "(validation included); OCP `BRepMesh_IncrementalMesh(shape, tol, False, 0.5, parallel)` on the "
             "shape read once, its triangulation removed (`BRepTools.Clean_s`, untimed) before every run; "
             "file reading is excluded on both sides. Medians of 3–9 runs after a warm-up (¹ = a single run: "
             "the warm-up took over 3 s); “> N s” = killed at the limit; “not run” = skipped after a slower "
             "configuration. *Speed-up* = OCP ÷ tessd (goal ≥ 5): *best* = the faster configuration of each, "
             "*1 thread* = OCP sequential ÷ tessd with 1 thread. Triangle rates use the best time.\n")
    summary = {}
    for tol in TOLS:
        L.append(f"### {tol} mm\n")
        L.append("| part | tessd 1t ms | tessd 2t ms | OCP seq ms | OCP par ms | speed-up best | speed-up 1 thread "
                 "| triangles tessd | triangles OCP | M tri/s tessd | M tri/s OCP | open edges (closed?) "
                 "| deviation max tessd / OCP (× tol) |")
        L.append("|---|" + "---|" * 12)
        sp_best, sp_one, sums = [], [], Counter()
        for p in d.parts:
            ours, theirs = d.best(p, tol, "tessd"), d.best(p, tol, "ocp")
            one, seq = d.tess_ok(p, tol, 1), d.ocp_ok(p, tol, False)
            sb = theirs["time_ms"] / ours["time_ms"] if ours and theirs else None
            s1 = seq["time_ms"] / one["time_ms"] if one and seq else None
            if sb:
                sp_best.append((p, sb))
                sums.update(ours=ours["time_ms"], ocp=theirs["time_ms"], tri_ours=ours["triangles"],
                            tri_ocp=theirs["triangles"])
            if s1:
                sp_one.append((p, s1))
            anyt = d.tess_any(p, tol)
            doc = d.doc.get(p, {})
            closed = doc.get("closed")
            crack = "–" if not anyt else f"{fmt(anyt['open_edges'])} ({'closed' if closed else 'open'})"
            if anyt and anyt.get("nonmanifold_edges"):
                crack += f", {fmt(anyt['nonmanifold_edges'])} non-manifold"
            mm = d.mm(p)
            oc = d.ocp_any(p, tol)
            dv_o = oc.get("deviation_max") if oc else None
            dv_t = anyt["deviation_max"] * mm if anyt else None
            dev = f"{fmt(dv_t / tol if dv_t is not None else None)} / {fmt(dv_o / tol if dv_o is not None else None)}"
            L.append(f"| {p} | {tess_cell(d, p, tol, 1)} | {tess_cell(d, p, tol, 2)} | {ocp_cell(d, p, tol, False)} | "
                     f"{ocp_cell(d, p, tol, True)} | {fmt(sb)} | {fmt(s1)} | "
                     f"{fmt(anyt['triangles']) if anyt else '–'} | {fmt(oc['triangles']) if oc else '–'} | "
                     f"{fmt(ours['triangles'] / ours['time_ms'] / 1e3) if ours else '–'} | "
                     f"{fmt(theirs['triangles'] / theirs['time_ms'] / 1e3) if theirs else '–'} | {crack} | {dev} |")
        tot_sp = sums["ocp"] / sums["ours"] if sums["ours"] else None
        # parts where tessd ran past its limit but OCP finished: an upper bound of the speed-up
        killed = []
        for p in d.parts:
            if d.best(p, tol, "tessd"):
                continue
            rs = [d.tess.get((p, tol, t)) for t in (1, 2)]
            lim = [float(r["error"].split("after the ")[1].split(" s")[0]) for r in rs
                   if r and "killed after" in r.get("error", "")]
            theirs = d.best(p, tol, "ocp")
            if lim and theirs:
                killed.append((p, theirs["time_ms"] / (1e3 * max(lim))))
        L.append(f"| **sum over parts both ran** | | {fmt(sums['ours'])} (best) | | {fmt(sums['ocp'])} (best) | "
                 f"**{fmt(tot_sp)}** | | {fmt(sums['tri_ours'])} | {fmt(sums['tri_ocp'])} | "
                 f"{fmt(sums['tri_ours'] / sums['ours'] / 1e3) if sums['ours'] else '–'} | "
                 f"{fmt(sums['tri_ocp'] / sums['ocp'] / 1e3) if sums['ocp'] else '–'} | | |")
        L.append("")
        g = gmean([s for _, s in sp_best])
        g1 = gmean([s for _, s in sp_one])
        met = sum(1 for _, s in sp_best if s >= GOAL_SPEED)
        L.append(f"Speed-up at {tol} mm: geometric mean over {len(sp_best)} parts **{fmt(g)}** (best of each), "
                 f"{fmt(g1)} (1 thread vs sequential); whole-set time ratio {fmt(tot_sp)}; parts at ≥ {GOAL_SPEED:g}×: "
                 f"{met} of {len(sp_best)}"
                 + (f" ({', '.join(p for p, s in sp_best if s >= GOAL_SPEED)})" if met else "") + ". "
                 f"Triangles tessd ÷ OCP over the set: {fmt(sums['tri_ours'] / sums['tri_ocp'] if sums['tri_ocp'] else None)}."
                 + "".join(f" Not counted: {p}, where tessd ran past its limit (speed-up < {fmt(b)})." for p, b in killed)
                 + "\n")
        summary[tol] = {"killed": killed, "gmean": g, "gmean1": g1, "total": tot_sp, "met": met, "n": len(sp_best),
                        "tri_ratio": sums["tri_ours"] / sums["tri_ocp"] if sums["tri_ocp"] else None}
    L.append("*Deviation* = the distance from each triangle's centroid to its face's (untrimmed) surface, "
             "projected by six Gauss–Newton steps started at the mean of the corners' (u, v), the largest over "
             "the mesh, divided by the tolerance (tessd: every triangle, from its f32 positions; OCP: up to "
             "20 000 triangles evenly strided, from `Poly_Triangulation` nodes and UV nodes): the same estimate of "
             "the chordal error for both, a lower bound of the true largest deviation where the projection "
             "converges. *Open edges* = edges used by one triangle after welding equal positions (bit for bit): "
             "cracks on a closed solid (*closed* = every edge with a 3D curve is used by two trims); on open "
             "shells and loose faces they are the free boundary.\n")
    loose = [(p["name"], p["loose_faces"]) for p in d.manifest if p.get("loose_faces") and p["name"] in d.parts]
    if loose:
        L.append("Data with loose edges (OCP's `BRep_Tool.Tolerance` of a face's edges, i.e. how far the source's "
                 "edges may lie off the surface; no mesh whose boundary follows them is closer than that): "
                 + "; ".join(f"{p}: face " + ", ".join(f"{fid} ({fmt(t)} mm)" for fid, t in fs) for p, fs in loose)
                 + ".\n")
    # CPU use of the 2-thread runs
    use = [r["cpu_ms"] / r["time_ms"] for (p, t, th), r in d.tess.items()
           if th == 2 and "cpu_ms" in r and r.get("time_ms", 0) > 20]
    if use:
        L.append(f"Parallelism: tessd's 2-thread runs (over 20 ms) used {fmt(statistics.median(use))} CPU-seconds per "
                 f"second (median; 2.0 = both cores busy throughout).\n")
    return summary


def problems(d, L):
    L.append("## Problems found\n")
    items = []
    for part, what, err in d.errors:
        items.append(f"{part}: {what}: {err}")
    for (p, e), r in sorted(d.trim.items()):
        for f in r["faces"]:
            if "error" in f:
                items.append(f"{p} face {f['id']} ({f['surface']}, {f['trims']} trims), ε = {e} mm: trim structure "
                             f"not built: {f['error']}")
            elif f.get("fit_over_tol", 0) > 1.0 + 1e-9:
                items.append(f"{p} face {f['id']} ({f['surface']}), ε = {e} mm: the approximation's (u, v) error "
                             f"{f['fit_error_uv']:.3g} is {f['fit_over_tol']:.3g}× the face's (u, v) tolerance "
                             f"{f['eps_uv']:.3g}")
        failing = [f for f in r["faces"] if f.get("failures")]
        if failing:
            items.append(f"{p}, ε = {e} mm: depth-13 failures on face(s) " + ", ".join(
                f"{f['id']} ({f['surface']}, {f['failures']} leaves)" for f in failing[:12])
                + (" …" if len(failing) > 12 else ""))
    for e in EPS:
        none = [(p, f) for p in d.parts for f in d.built(p, e) if f["k_i"] is None]
        fixable = [(p, f) for p, f in none if f.get("k_i_to_6") is not None]
        if fixable:
            ex = ", ".join(f"{p} face {f['id']} ({f['surface']}, deepest leaf {f['max_depth']}, k = {f['k_i_to_6']} "
                           f"classifies {100 * f['classifiable_at_6']:.0f} % at level 6)" for p, f in fixable[:3])
            items.append(f"core/trim, ε = {e} mm: `k_i` is `None` on {len(none)} faces, {len(fixable)} of which reach "
                         f"40 % at some level ≤ 6 by the crate's own `classifiable_at` — the search in "
                         f"`Quadtree::level_for_triangles` stops at max(deepest leaf, 1), so shallow trees (a rectangular "
                         f"loop: four depth-1 leaves) never get a level; e.g. {ex}")
    for (p, tol, th), r in sorted(d.tess.items()):
        if "time_ms" not in r:
            continue
        if r.get("empty_faces"):
            items.append(f"{p}, tessellation {tol} mm: faces without triangles: {r['empty_faces']}")
        if r.get("mesh_valid"):
            items.append(f"{p}, tessellation {tol} mm: mesh does not validate: {r['mesh_valid']}")
        if th != max(t for (q, u, t) in d.tess if q == p and u == tol):
            continue  # one line per (part, tol): the counts do not depend on the pool size
        if d.doc.get(p, {}).get("closed") and r.get("open_edges"):
            items.append(f"{p} (closed), tessellation {tol} mm: {r['open_edges']} open edges (cracks), e.g. "
                         f"{r.get('open_edge_examples', [])[:2]}")
        if r.get("nonmanifold_edges"):
            ex = "; ".join(f"{[[round(c, 3) for c in q] for q in e['edge']]} by faces {e['faces']}"
                           for e in r.get("nonmanifold_examples", [])[:3])
            items.append(f"{p}, tessellation {tol} mm: {r['nonmanifold_edges']} edges used by more than two triangles"
                         + (f" (after welding; a face id listed more than once = that face's own triangles overlap "
                            f"on the edge), e.g. {ex}" if ex else ""))
        if r.get("deviation_over_tol"):
            items.append(f"{p}, tessellation {tol} mm: {r['deviation_over_tol']} of {r['triangles']} triangles' "
                         f"centroids farther than the tolerance from the surface (max {r['deviation_max'] * d.mm(p):.3g} mm "
                         f"= {r['deviation_max'] * d.mm(p) / tol:.2g}× tol, face {r.get('deviation_worst_face')}"
                         + (f", triangle (u, v) {[[round(x, 4) for x in q] for q in r['deviation_worst_uvs']]}"
                            if r.get("deviation_worst_uvs") else "") + ")")
    for (p, tol, par), r in sorted(d.ocp.items()):
        if "error" in r:
            items.append(f"{p}: OCP mesh at {tol} mm (parallel {par}): {r['error']}")
        elif r.get("faces_without_triangulation"):
            items.append(f"{p}: OCP left {r['faces_without_triangulation']} faces without triangulation at {tol} mm")
    for p in d.parts:
        doc = d.doc.get(p, {})
        if doc.get("validation_errors"):
            items.append(f"{p}: the exported document has {doc['validation_errors']} validation errors, first: "
                         f"{doc.get('first_validation_error')}")
    if not items:
        L.append("None.\n")
    for it in items:
        L.append(f"- {it}")
    L.append("")


def plots(d, out):
    paths = []
    fig, ax = plt.subplots(figsize=(8.5, 7))
    xs = []
    for tol, marker, color in ((0.1, "o", "tab:blue"), (0.01, "s", "tab:red")):
        pts = []
        for p in d.parts:
            tb = d.trim_sum(p, tol, "bytes")
            oc = d.ocp_any(p, tol)
            if tb and oc and oc.get("bytes_36"):
                pts.append((oc["bytes_36"] / 1024, tb / 1024, p))
        if pts:
            ax.scatter([a for a, _, _ in pts], [b for _, b, _ in pts], marker=marker, color=color,
                       label=f"ε = deflection = {tol} mm")
            for a, b, p in pts:
                ax.annotate(p.replace("cq_", "").split(".")[0], (a, b), fontsize=6, alpha=0.7,
                            xytext=(3, 2), textcoords="offset points")
            xs += [a for a, _, _ in pts]
    if xs:
        lo, hi = min(xs) / 2, max(xs) * 2
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8, label="trim = static")
        ax.plot([lo, hi], [GOAL_BYTES * lo, GOAL_BYTES * hi], "k--", lw=0.8, label=f"trim = {GOAL_BYTES} × static (goal at 0.01 mm)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("OCP static tessellation, KiB (36 B × vertices)")
    ax.set_ylabel("trim structures, KiB (packed, all faces)")
    ax.set_title("Trim structure vs static tessellation memory, per part")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out / "brep_bytes.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    paths.append(path)

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(16, 7), gridspec_kw={"width_ratios": [1, 1.2]})
    for tool, color in (("tessd", "tab:green"), ("ocp", "tab:purple")):
        for tol, marker in ((0.1, "o"), (0.01, "s")):
            pts = [(r["triangles"], r["time_ms"]) for p in d.parts if (r := d.best(p, tol, tool))]
            if pts:
                ax.scatter([a for a, _ in pts], [b for _, b in pts], marker=marker, color=color, alpha=0.8,
                           label=f"{'tessd-tessellate' if tool == 'tessd' else 'OCP BRepMesh'}, {tol} mm")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("triangles")
    ax.set_ylabel("time, ms (best configuration, median)")
    ax.set_title("Tessellation time vs triangles, per part and tolerance")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    names = [p for p in d.parts if any(d.best(p, t, "tessd") and d.best(p, t, "ocp") for t in TOLS)]
    width = 0.4
    for k, (tol, color) in enumerate(((0.1, "tab:blue"), (0.01, "tab:red"))):
        vals = []
        for p in names:
            a, b = d.best(p, tol, "tessd"), d.best(p, tol, "ocp")
            vals.append(b["time_ms"] / a["time_ms"] if a and b else 0)
        bx.bar([i + (k - 0.5) * width for i in range(len(names))], vals, width, color=color, label=f"{tol} mm")
    bx.axhline(GOAL_SPEED, color="k", ls="--", lw=0.8, label=f"goal {GOAL_SPEED:g}×")
    bx.axhline(1, color="k", lw=0.6)
    bx.set_yscale("log")
    bx.set_xticks(range(len(names)))
    bx.set_xticklabels([p.replace("cq_", "").split(".")[0] for p in names], rotation=60, ha="right", fontsize=7)
    bx.set_ylabel("speed-up = OCP time ÷ tessd time (best configuration of each)")
    bx.set_title("Tessellation speed-up over OCP BRepMesh, per part")
    bx.grid(True, axis="y", which="both", alpha=0.3)
    bx.legend(fontsize=8)
    fig.tight_layout()
    path = out / "brep_tessellation.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    paths.append(path)
    return paths


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jsonl", default="bench/results/brep_raw.jsonl")
    ap.add_argument("--manifest", default="/tmp/tessd-bench-brep/parts.json")
    ap.add_argument("--out", default="bench/results")
    ap.add_argument("--wall-s", type=float, default=None)
    ap.add_argument("--load-start", default=None)
    ap.add_argument("--load-end", default=None)
    ap.add_argument("--command", default="bash bench/run_brep.sh")
    ap.add_argument("--source-note", default=None, help="the code state measured (git), one line")
    a = ap.parse_args()
    manifest = json.loads(Path(a.manifest).read_text()) if Path(a.manifest).is_file() else []
    d = Data(a.jsonl, manifest)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    body = []
    table1(d, body)
    rt, rt_nh, per_part = table3(d, body)
    t4, _ = table4(d, body)
    all_ms, rates = build_and_classify(d, body)
    sp = tessellation(d, body)
    problems(d, body)
    plot_paths = plots(d, out)

    L = ["# B-Rep benchmark: paper 000's trim structure and trimmed tessellation vs OCP\n"]
    # the time the raw results were last written (so a report regenerated later keeps it)
    when = datetime.datetime.fromtimestamp(os.path.getmtime(a.jsonl), datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    load = ""
    if a.load_start or a.load_end:
        load = f" Load average (1, 5, 15 min) at the start {a.load_start}, at the end {a.load_end}."
    L.append(f"Machine: {machine()}; shared with other jobs during the run (noisy: every time is a median, and "
             f"ratios can move by ±30 % between runs).{load} Run {when}"
             + (f", whole run {a.wall_s / 60:.1f} min" if a.wall_s else "") + f". Command: `{a.command}`. "
             "Parts: every file of the shared data's `brep/` folder and the cadquery parts of "
             "`tests/brep/test_brep_export.py` (prefix `cq_`) plus `cq_plate_540_holes` (a 300 × 200 × 5 mm plate "
             "with 540 Ø4 holes: two faces of 541 loops, the paper's figure-1 case), all exported by `tessd.brep` "
             "in millimetres. `hammer.iges` is 41 m long in its file's units (IGES surfaces, unsewn), so its "
             "0.01 mm meshes are enormous; the totals are also given without it.\n")
    if a.source_note:
        L.append(f"Code measured: {a.source_note}\n")
    nparts = len(d.parts)
    nfaces = sum(d.faces(p) or 0 for p in d.parts)
    L.append(f"{nparts} parts, {fmt(nfaces)} faces.\n")

    # goals
    static = {p: (d.ocp_any(p, 0.01) or {}).get("bytes_36") or 0 for p in d.parts}
    hammer_share = (sum(v for p, v in static.items() if "hammer" in p) / sum(static.values())
                    if sum(static.values()) else None)
    hammer_share = None if hammer_share is None else f"{100 * hammer_share:.0f} %"
    L.append("## Goals\n")
    L.append("| goal | target | this run | met |")
    L.append("|---|---|---|---|")
    mets = sum(1 for _, r in per_part if r <= GOAL_BYTES)
    L.append(f"| trim structure ÷ static tessellation (OCP, 36 B/vertex) at 0.01 mm, whole set | ≤ {GOAL_BYTES} "
             f"| {fmt(rt.get(0.01))} (hammer.iges alone holds {hammer_share} of the static bytes) "
             f"| {yes(rt.get(0.01) is not None and rt[0.01] <= GOAL_BYTES)} |")
    L.append(f"| the same without hammer.iges | ≤ {GOAL_BYTES} | {fmt(rt_nh.get(0.01))} ({mets} of {len(per_part)} parts "
             f"≤ {GOAL_BYTES} on their own; median part {fmt(statistics.median([r for _, r in per_part]) if per_part else None)}) "
             f"| {yes(rt_nh.get(0.01) is not None and rt_nh[0.01] <= GOAL_BYTES)} |")
    for e in EPS:
        t = t4.get(e, Counter())
        share = 100 * t["failing"] / t["faces"] if t["faces"] else float("nan")
        L.append(f"| faces with a depth-13 failure, ε = {e} mm | ≤ {GOAL_FAIL_PCT} % | {share:.2f} % "
                 f"({t['failing']} of {t['faces']}) | {yes(share <= GOAL_FAIL_PCT)} |")
    for tol in TOLS:
        s = sp.get(tol, {})
        L.append(f"| tessellation speed-up over OCP BRepMesh at {tol} mm (geometric mean over parts, best "
                 f"configuration of each) | ≥ {GOAL_SPEED:g}× | {fmt(s.get('gmean'))} (1 thread vs sequential "
                 f"{fmt(s.get('gmean1'))}; whole-set time {fmt(s.get('total'))}; {s.get('met', 0)} of "
                 f"{s.get('n', 0)} parts ≥ {GOAL_SPEED:g}×"
                 + "".join(f"; {p}: tessd over its limit, < {fmt(b)}" for p, b in s.get("killed", []))
                 + f") | {yes(s.get('gmean', 0) >= GOAL_SPEED)} |")
    closed_cracks = [(p, tol, r["open_edges"]) for (p, tol, th), r in d.tess.items()
                     if "open_edges" in r and d.doc.get(p, {}).get("closed") and r["open_edges"]]
    n_closed = sum(1 for p in d.parts if d.doc.get(p, {}).get("closed"))
    L.append(f"| tessd meshes of closed solids without cracks (open edges after welding) | 0 | "
             f"{len({(p, t) for p, t, _ in closed_cracks})} (part, tolerance) pairs with open edges over {n_closed} closed parts "
             f"| {yes(not closed_cracks)} |")
    L.append("")
    rate = statistics.median(rates[0.01]) if rates[0.01] else None
    ms = all_ms[0.01]
    L.append(f"Also measured (no goal set): trim build per face at ε = 0.01 mm median {fmt(statistics.median(ms) if ms else None)} ms, "
             f"p95 {fmt(pctl(ms, 0.95))} ms, total {fmt(sum(ms) / 1e3 if ms else None)} s for {fmt(len(ms))} faces; "
             f"CPU classification {fmt(rate / 1e6 if rate else None)} M points/s on one thread (median of the parts).\n")
    L.append("Plots: [brep_bytes.png](brep_bytes.png) (trim structure vs static tessellation bytes per part, with "
             "the goal line) and [brep_tessellation.png](brep_tessellation.png) (tessellation time vs triangles, "
             "tessd and OCP, and the speed-up per part against the goal).\n")
    L += body
    L.append("## Reproduce\n")
    L.append("```sh\nbash bench/run_brep.sh          # 6 min on 2 cores (13 min under heavy load); raw lines in bench/results/brep_raw.jsonl\n```\n")
    L.append("Needs the CAD venv `.venv-cad` (cadquery 2.8, cadquery-ocp 7.9: export, OCP meshing; "
             "`scripts/setup.sh`) and matplotlib in `.venv-bench` (`bench/requirements-bench.txt`). Steps: "
             "`cargo build --release -p tessd-bench-brep`; `peer_ocp.py export` writes the JSON documents, the "
             "cadquery shapes (.brep) and `parts.json` to `$BENCH_WORK` (default /tmp/tessd-bench-brep); then per "
             "part `bench-brep run --only PART` (a child process for the trim step and one per tessellation "
             "configuration, killed after `TESS_TIMEOUT` s, default 90) and `peer_ocp.py mesh --only PART`; "
             "finally `report.py`. Environment: `TESSD_SHARED_DATA` (default ../shared/data), `BENCH_WORK`, "
             "`TESS_TIMEOUT`, `BENCH_PYTHON`, `CAD_PYTHON`. Extra arguments go to `bench-brep run` (e.g. "
             "`--eps 0.1 --tols 0.1` for a quick run). See bench/brep/README.md.\n")
    (out / "brep.md").write_text("\n".join(L) + "\n")
    print(f"wrote {out / 'brep.md'} and {', '.join(str(p) for p in plot_paths)}")


if __name__ == "__main__":
    main()
