#!/usr/bin/env python3
"""Blender side of the subdivision benchmark: the Subdivision Surface modifier (Catmull-Clark,
CPU OpenSubdiv inside Blender) on the same cages and levels as bench-subdiv and osd_bench.

    blender_bench.py run --cages A.obj,B.obj [--levels 1,2,3,4,5] [--jsonl FILE]
                         [--budget 3] [--min-repeat 1] [--max-repeat 7]
    blender_bench.py one CAGE.obj LEVEL [--budget 3] [--min-repeat 1] [--max-repeat 7]

Run with the interpreter that has the `bpy` module (Blender as a Python module):
/work/main/.venv/bin/python. `run` starts one child process (`one`) per (cage, level), so each
configuration's peak memory is its own, and appends one JSON line per configuration to the
jsonl (`tool` = "blender"). `one` prints one JSON object.

What is measured, in one process per (cage, level):

- The cage is read (v and f records), turned into a Blender mesh once (`from_pydata`, edges
  derived), linked to an object in an empty factory-settings scene, with GPU subdivision off,
  and evaluated once without a modifier (so the cage's own evaluation is not counted).
- `cold_ms` (the full pipeline, as a first frame or a topology change): a Subdivision Surface
  modifier is added (Catmull-Clark, levels = render levels = LEVEL, use_limit_surface = False so
  the result is the level-N control points like OpenSubdiv's RefineUniform, boundary
  PRESERVE_CORNERS = OpenSubdiv's edge-and-corner, creases on, quality 10, no custom normals)
  and the timer covers `evaluated_depsgraph_get()` and reading the evaluated mesh's vertex and
  face counts, which forces the subdivided mesh to be built (Blender builds it lazily, at first
  access of the evaluated data). That includes Blender's OpenSubdiv topology refiner, its
  evaluator (stencil and patch tables), evaluating every output vertex and building the output
  Blender mesh (vertices, edges, faces, corners). The modifier is then removed and the scene
  evaluated again (untimed) before the next run, so nothing is cached between runs.
- `pose_ms` (the apply phase as Blender does it, an animation frame): with the modifier in
  place, the cage's positions are changed (scaled by 1 +/- 1e-4, untimed, `mesh.update()`) and
  the same evaluation is timed. Blender keeps the topology refiner and evaluator when only
  positions change, so this is: copying the cage into the evaluated scene, updating the
  evaluator's coarse positions, evaluating every output vertex and building the output mesh.
- Each is warmed up once, then run budget / warm-up time times (clamped to
  [min-repeat, max-repeat]); the median is reported with every run.
- `peak_over_baseline_kib`: the process's peak resident set (VmHWM) during the runs over its
  resident set before them (after the cage mesh is built; the peak is reset through
  /proc/self/clear_refs and glibc's heap trimmed first).
- Blender runs its own threads (TBB, every core); `cpu_count` says how many there are.
"""

import argparse
import ctypes
import json
import os
import statistics
import subprocess
import sys
import time


def status_kib(key):
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def reset_peak():
    """Trims glibc's heap and resets VmHWM to VmRSS; False when the kernel refused."""
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


def read_obj(path):
    """Positions and faces (0-based) of the v and f records; f a/b/c takes a; negative indices
    count back from the last vertex read."""
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append(tuple(float(x) for x in parts[1:4]))
            elif parts[0] == "f":
                face = []
                for tok in parts[1:]:
                    i = int(tok.split("/")[0])
                    face.append(i - 1 if i > 0 else len(verts) + i)
                faces.append(face)
    return verts, faces


def repeated(budget_s, lo, hi, run):
    """Warm-up run, then budget / warm-up time timed runs clamped to [lo, hi]; times in ms."""
    warm = run()
    n = max(lo, min(hi, int(budget_s * 1e3 / max(warm, 1e-6))))
    return warm, [run() for _ in range(n)]


def one(cage_path, level, budget_s, lo, hi):
    t0 = time.perf_counter()
    import bpy
    import numpy as np

    import_s = time.perf_counter() - t0
    verts, faces = read_obj(cage_path)

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.system.use_gpu_subdivision = False
    mesh = bpy.data.meshes.new("cage")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new("cage", mesh)
    bpy.context.scene.collection.objects.link(obj)
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    assert len(ev.data.vertices) == len(verts)
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)

    def add_modifier():
        mod = obj.modifiers.new("subsurf", "SUBSURF")
        mod.subdivision_type = "CATMULL_CLARK"
        mod.levels = level
        mod.render_levels = level
        mod.use_limit_surface = False
        mod.use_creases = True
        mod.boundary_smooth = "PRESERVE_CORNERS"
        mod.quality = mod.bl_rna.properties["quality"].hard_max
        mod.use_custom_normals = False
        return mod

    counts = {}

    def evaluate():
        t = time.perf_counter()
        dg = bpy.context.evaluated_depsgraph_get()
        data = obj.evaluated_get(dg).data
        counts["v"], counts["f"] = len(data.vertices), len(data.polygons)
        return (time.perf_counter() - t) * 1e3

    def cold():
        for m in list(obj.modifiers):
            obj.modifiers.remove(m)
        bpy.context.evaluated_depsgraph_get()  # back to the bare cage, untimed
        add_modifier()
        return evaluate()

    sign = [1.0]

    def pose():
        sign[0] = -sign[0]
        mesh.vertices.foreach_set("co", co * np.float32(1.0 + sign[0] * 1e-4))
        mesh.update()
        return evaluate()

    base_reset = reset_peak()
    base_rss = status_kib("VmRSS")
    cold_warm, cold_runs = repeated(budget_s, lo, hi, cold)
    pose_warm, pose_runs = repeated(budget_s, lo, hi, pose)
    peak = max(0, status_kib("VmHWM") - base_rss)
    return {
        "tool": "blender",
        "cage": os.path.basename(cage_path),
        "level": level,
        "cage_vertices": len(verts),
        "cage_faces": len(faces),
        "out_vertices": counts["v"],
        "out_faces": counts["f"],
        "cold_ms": statistics.median(cold_runs),
        "cold_runs_ms": cold_runs,
        "cold_warmup_ms": cold_warm,
        "pose_ms": statistics.median(pose_runs),
        "pose_runs_ms": pose_runs,
        "pose_warmup_ms": pose_warm,
        "baseline_rss_kib": base_rss,
        "peak_over_baseline_kib": peak,
        "peak_reset_ok": base_reset,
        "import_s": import_s,
        "blender_version": bpy.app.version_string,
        "cpu_count": os.cpu_count(),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    for name in ("run", "one"):
        p = sub.add_parser(name)
        p.add_argument("--budget", type=float, default=3.0, help="seconds of timed runs per phase")
        p.add_argument("--min-repeat", type=int, default=1)
        p.add_argument("--max-repeat", type=int, default=7)
        if name == "run":
            p.add_argument("--cages", required=True, help="comma-separated OBJ paths")
            p.add_argument("--levels", default="1,2,3,4,5")
            p.add_argument("--jsonl", default="bench/results/subdiv_raw.jsonl")
        else:
            p.add_argument("cage")
            p.add_argument("level", type=int)
    a = ap.parse_args()
    if a.cmd == "one":
        print(json.dumps(one(a.cage, a.level, a.budget, a.min_repeat, a.max_repeat)))
        return
    cages = [c for c in a.cages.split(",") if c]
    levels = [int(x) for x in a.levels.split(",") if x]
    jobs = [(c, lv) for c in cages for lv in levels]
    with open(a.jsonl, "a") as out:
        for i, (cage, level) in enumerate(jobs):
            t = time.perf_counter()
            cmd = [sys.executable, os.path.abspath(__file__), "one", cage, str(level),
                   "--budget", str(a.budget), "--min-repeat", str(a.min_repeat),
                   "--max-repeat", str(a.max_repeat)]
            p = subprocess.run(cmd, capture_output=True, text=True)
            wall = time.perf_counter() - t
            rec = None
            if p.returncode == 0:
                for line in reversed(p.stdout.splitlines()):
                    if line.startswith("{"):
                        rec = json.loads(line)
                        break
            if rec is None:
                err = (p.stderr or p.stdout).strip().splitlines()[-5:]
                rec = {"error": "exit %d: %s" % (p.returncode, " | ".join(err))}
            rec.update({"tool": "blender", "cage": os.path.basename(cage), "cage_path": cage,
                        "level": level, "child_wall_s": wall})
            out.write(json.dumps(rec) + "\n")
            out.flush()
            if "error" in rec:
                msg = "ERROR " + rec["error"]
            else:
                msg = "cold %.3f pose %.3f ms  out %d" % (rec["cold_ms"], rec["pose_ms"], rec["out_vertices"])
            print("[%3d/%d] blender %-28s %s  [%.1f s]" % (i + 1, len(jobs), "%s L%d" % (os.path.basename(cage), level),
                                                          msg, wall), file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
