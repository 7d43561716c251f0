"""bench/results/freecad_roundtrip.md from the round trip's JSON (bench/freecad/roundtrip.py)."""

import json
import sys

src, dst, load_start, load_end = sys.argv[1:5]
r = json.load(open(src))
a, t, m, s, d = r["assembly"], r["tessellate"], r["meshFromShape"], r["simplify"], r["decimate"]
ms = lambda x: "%.0f" % (1e3 * x)  # noqa: E731
lines = [
    "# FreeCAD round trip (issue 14)",
    "",
    "FreeCAD %s, 2 cores; `bash bench/run_freecad.sh` (bench/freecad/roundtrip.py says how each "
    "figure is taken). Load average %s at the start, %s at the end." % (
        ".".join(r["freecad"]), load_start, load_end),
    "",
    "Input: a STEP assembly of %d parts, %d B-Rep faces (shared featuretype.step ×6, "
    "CrankArm.brep ×4, bottle.brep ×3), written by FreeCAD's Import and read back. "
    "Tolerance %g mm, angle %g rad. Medians of %d runs (ms)." % (
        a["objects"], a["faces"], a["tolerance_mm"], a["angle"], a["runs"]),
    "",
    "## Tessellate (0.1 mm): click to result",
    "",
    "| | total | FreeCAD side: prepare | B-Rep export | waiting for the daemon | build meshes | apply | daemon's own time | transfer | triangles |",
    "|---|---|---|---|---|---|---|---|---|---|",
] + [
    "| %s | **%s** | %s | %s | %s | %s | %s | %s | %s | %d |" % (
        name, ms(x["total"]), ms(x["prepare"]), ms(x["export"]), ms(x["wait"]), ms(x["build"]),
        ms(x["apply"]), ms(x["daemon"]) + (" (overlapped)" if overlapped else ""),
        "–" if overlapped else ms(x["wait"] - x["daemon"]), x["triangles"])
    for name, x, overlapped in [("tessd workbench (pipelined, BREP text, as shipped)", t, True),
                                ("tessd, one request at a time", r["sequential"], False),
                                ("tessd, Python B-Rep export (the fallback)",
                                 r["python_export"], True)]
] + [
    "| `MeshPart.meshFromShape` | **%s** | | | | | | | | %d |" % (ms(m["total"]), m["triangles"]),
    "",
    "Ratio tessd / meshFromShape: **%.2f×** (goal: below 1). The workbench's meshes are "
    "watertight (shared edges discretised once), meshFromShape's are not." % (
        t["total"] / m["total"]),
    "",
    "## Simplify (complexity, 20 %% of %d vertices, quadric)" % r["input_vertices"],
    "",
    "| | total | prepare | transfer | daemon | build | apply | vertices |",
    "|---|---|---|---|---|---|---|---|",
    "| tessd workbench | **%s** | %s | %s | %s | %s | %s | %d |" % (
        ms(s["total"]), ms(s["prepare"]), ms(s["transfer"]), ms(s["daemon"]), ms(s["build"]),
        ms(s["apply"]), s["vertices"]),
    "| FreeCAD `Mesh.decimate(0.1, 0.8)` | **%s** | | | | | | %d |" % (
        ms(d["total"]), d["vertices"]),
    "",
]
open(dst, "w").write("\n".join(lines))
