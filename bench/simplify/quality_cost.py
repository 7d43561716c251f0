"""What the quality goal's surface guarantee costs: the same `bench-simplify one` timing of
`tessd-quality-bary` / `tessd-quality-quadric` with two builds, before and after, interleaved
run by run on the same inputs and the same absolute tolerance (single thread, medians).

    python bench/simplify/quality_cost.py --before OLD/bench-simplify --after NEW/bench-simplify \
        --inputs a.ply b.ply ... [--fractions 0.01,0.005,0.001] [--runs 5] [--out bench/results/simplify_quality_cost.md]

Writes a Markdown table: per input, tolerance and representative, the median time of each
build, the ratio after / before, output vertices of each and the coverage rounds (after).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from report_common import gmean, machine  # noqa: E402


def largest_side(binary: str, path: str) -> float:
    tessd = Path(binary).parent / "tessd"
    s = json.loads(subprocess.run([str(tessd), "stats", "--json", path], check=True,
                                  capture_output=True, text=True).stdout)
    b = s["bounds"]
    return max(hi - lo for lo, hi in zip(b["min"], b["max"]))


def one(binary: str, method: str, path: str, tol: float, out: Path) -> dict:
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    run = subprocess.run([binary, "one", method, path, repr(tol), "--out", str(out), "--repeat", "1"],
                         check=True, capture_output=True, text=True, env=env)
    return json.loads(run.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--inputs", nargs="+", required=True)
    ap.add_argument("--fractions", default="0.01,0.005,0.001")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--out", default="bench/results/simplify_quality_cost.md")
    a = ap.parse_args()
    fractions = [float(f) for f in a.fractions.split(",")]
    rows, ratios = [], []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "o.ply"
        for path in a.inputs:
            size = largest_side(a.after, path)
            for method in ("tessd-quality-bary", "tessd-quality-quadric"):
                for f in fractions:
                    tol = f * size
                    t = {"before": [], "after": []}
                    rec = {}
                    for _ in range(a.runs):
                        for which, binary in (("before", a.before), ("after", a.after)):
                            r = one(binary, method, path, tol, out)
                            t[which].append(r["times_s"][0])
                            rec[which] = r
                    tb, ta = statistics.median(t["before"]), statistics.median(t["after"])
                    ratios.append(ta / tb)
                    rows.append((Path(path).name, method.removeprefix("tessd-"), f, rec["before"]["input_triangles"],
                                 tb * 1e3, ta * 1e3, ta / tb, rec["before"]["out_vertices"],
                                 rec["after"]["out_vertices"]))
                    print(rows[-1], flush=True)
    lines = [
        "# Quality goal: cost of the surface guarantee (before / after)",
        "",
        f"Machine: {machine()}. Command: `python bench/simplify/quality_cost.py --before BEFORE "
        f"--after AFTER --inputs {' '.join(Path(p).name for p in a.inputs)} --runs {a.runs}`. "
        "Each cell: median of the runs of `bench-simplify one METHOD INPUT TOL --repeat 1`, single "
        "thread, before and after interleaved run by run (the same absolute tolerance, a fraction "
        "of the input's largest side); the time is the simplification call only (mesh loaded).",
        "",
        "| input | method | tolerance | triangles | before ms | after ms | after / before | "
        "vertices before | vertices after |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, method, f, tris, tb, ta, ratio, vb, va in rows:
        lines.append(f"| {name} | {method} | {f * 100:g} % | {tris} | {tb:.1f} | {ta:.1f} | "
                     f"{ratio:.3f} | {vb} | {va} |")
    lines += ["", f"Geometric mean of after / before over {len(ratios)} cells: **{gmean(ratios):.3f}** "
              f"(median {statistics.median(ratios):.3f}, max {max(ratios):.3f})."]
    Path(a.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {a.out}: gmean {gmean(ratios):.3f}")


if __name__ == "__main__":
    main()
