"""Round trip of the add-on's Simplify on a ~1.3 M-triangle object, from the operator call to
the new object, split into Blender export (read), transfer, daemon work and Blender import
(build); with `--before REV`, the add-on of git revision REV against the working tree's.

    .venv/bin/python bench/blender_roundtrip.py [--subdivisions 9] [--target 10] [--repeats 6]
                                                [--before REV [--before-daemon PATH]] [--rounds 3]
                                                [--out bench/results/blender_roundtrip.md]

Real Blender (the PyPI `bpy` module in .venv), the extension built and installed as the tests
do (tests/blender_addon/addon_env.py), a real daemon (target/release/tessd or $TESSD_BIN; the
before runs use `--before-daemon` when given, else the same one). Each add-on runs in a fresh
Python of its own (two versions of one extension cannot be installed in one Blender), for
`--rounds` rounds that alternate before / after, so both see the same load; each process makes
one uncounted call first (module imports, first allocations), then `repeats / rounds` counted
ones. Every number comes from the one real `bpy.ops.tessd.simplify(...)` call, instrumented
from the outside (nothing in the add-on is changed):

- export: the conversion of the object, `common.arrays_of` (object -> protocol arrays; of which
  `convert.mesh_to_arrays` alone, the rest being the depsgraph and `to_mesh` where the add-on
  evaluates the object), run from the job's tick;
- request round trip: the add-on job's submit -> reply (`jobs.Job.timings`), which includes
  sending the input arrays and receiving the reply's arrays;
- daemon work: the daemon's own time of that request (`elapsed_ms` of its `ok` frame, the
  client's `tessd.Job.elapsed_ms`);
- transfer (both directions) = request round trip - daemon work;
- import: the operator's `apply_task` (arrays -> mesh with `foreach_set`, attributes, object
  creation; of which `convert.mesh_from_arrays` alone);
- remainder: whole call - export - round trip - import (connecting to the daemon, operator
  dispatch, the undo push).

A cross-check of the transfer: `debug.echo` of the same input and output arrays (the
protocol's cost alone; each array goes to the daemon and back, so twice the request's bytes),
on a separate connection after each call.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TEST_PATHS = [str(REPO / "tests" / "blender_addon"), str(REPO / "tests"),
              str(REPO / "tests" / "daemon"), str(REPO / "python")]

#: The steps of one call, in report order: (key, label, what).
STEPS = [
    ("total", "**whole operator**", "`bpy.ops.tessd.simplify(...)` call to the new object"),
    ("export", "read (Blender export)", "`common.arrays_of` (from the job's tick): object → arrays"),
    ("mesh_to_arrays", "  of which `mesh_to_arrays`", "the `foreach_get` reads alone (the rest: "
     "depsgraph and `to_mesh` where the object is evaluated)"),
    ("transfer", "transfer (both directions)", "request round trip − daemon work"),
    ("daemon", "daemon work", "`elapsed_ms` of the daemon's `ok` frame (`Job.elapsed_ms`)"),
    ("import", "build (Blender import)", "the operator's `apply_task`: arrays → mesh with "
     "`foreach_set`, object creation"),
    ("mesh_from_arrays", "  of which `mesh_from_arrays`", "the `foreach_set` writes and "
     "`mesh.update`"),
    ("remainder", "remainder", "connect, the complexity target from the arrays, operator "
     "dispatch, undo push"),
]


def nbytes(arrays):
    return sum(getattr(a, "nbytes", 0) for a in arrays.values())


class Probe:
    """Timing wrappers around the add-on's own functions (restored by `close`)."""

    def __init__(self, addon_name):
        self.ops = sys.modules[addon_name + ".ops_simplify"].TESSD_OT_simplify
        self.jobs = sys.modules[addon_name + ".jobs"]
        self.convert = sys.modules[addon_name + ".convert"]
        self.common = sys.modules[addon_name + ".common"]
        self.saved = [(self.common, "arrays_of", self.common.arrays_of),
                      (self.ops, "apply_task", self.ops.apply_task),
                      (self.jobs.Job, "_submit", self.jobs.Job._submit),
                      (self.convert, "mesh_to_arrays", self.convert.mesh_to_arrays),
                      (self.convert, "mesh_from_arrays", self.convert.mesh_from_arrays)]
        self.reset()
        probe = self

        def timed(key, fn):
            def wrapper(*a, **kw):
                t0 = time.perf_counter()
                try:
                    return fn(*a, **kw)
                finally:
                    probe.t[key] = probe.t.get(key, 0.0) + time.perf_counter() - t0
            return wrapper

        arrays_of, apply_task, submit = self.common.arrays_of, self.ops.apply_task, self.jobs.Job._submit

        def arrays_of_w(*a, **kw):
            arrays, params, sent = timed("export", arrays_of)(*a, **kw)
            probe.sent += nbytes(arrays)
            probe.inputs.append(arrays)
            return arrays, params, sent

        def apply_w(op, context, task, created):
            probe.received += sum(nbytes(r.arrays_out) for r in task.requests)
            probe.outputs += [r.arrays_out for r in task.requests]
            return timed("import", apply_task)(op, context, task, created)

        def submit_w(job, task):
            submit(job, task)
            probe.job = job
            probe.client_jobs.append(job._current)

        self.common.arrays_of, self.ops.apply_task, self.jobs.Job._submit = arrays_of_w, apply_w, submit_w
        self.convert.mesh_to_arrays = timed("mesh_to_arrays", self.convert.mesh_to_arrays)
        self.convert.mesh_from_arrays = timed("mesh_from_arrays", self.convert.mesh_from_arrays)

    def reset(self):
        self.t = {}
        self.job = None
        self.client_jobs = []
        self.inputs, self.outputs = [], []
        self.sent = self.received = 0

    def close(self):
        for owner, name, fn in self.saved:
            setattr(owner, name, fn)


def machine():
    model = ""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return "%s%d cores, %s" % ((model + ", ") if model else "", os.cpu_count() or 0, platform.system())


def scenario(zip_path, socket, subdivisions, target, repeats):
    """In this (fresh) Python: installs the extension `zip_path` against the daemon at
    `socket`, makes one uncounted call, then `repeats` measured ones; prints `RESULT <json>`
    with the rows and what was sent."""
    sys.path[:0] = TEST_PATHS
    import bpy

    from addon_env import ADDON, install_addon, uninstall_addon

    repo_dir = Path(tempfile.mkdtemp(prefix="tessd-repo-"))
    install_addon(zip_path, repo_dir, socket)
    tessd = sys.modules[ADDON + ".client"].tessd
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions)
    obj = bpy.context.object
    info = {"vertices": len(obj.data.vertices), "triangles": len(obj.data.polygons),
            "blender": bpy.app.version_string, "numpy": __import__("numpy").__version__}
    probe = Probe(ADDON)
    rows = []
    try:
        for rep in range(repeats + 1):
            for o in list(bpy.context.selected_objects):
                o.select_set(False)
            obj.select_set(True)
            bpy.context.view_layer.objects.active = obj
            probe.reset()
            t0 = time.perf_counter()
            r = bpy.ops.tessd.simplify(method='COMPLEXITY', target=target, target_is_percent=True)
            total = time.perf_counter() - t0
            assert r == {'FINISHED'}, r
            (label, round_trip), = probe.job.timings
            daemon = probe.client_jobs[-1].elapsed_ms / 1e3
            result = bpy.data.objects[obj.name + "_simplified"]
            out_tris = len(result.data.polygons)
            with tessd.Client(socket) as c:
                t1 = time.perf_counter()
                c.call("debug.echo", {}, probe.inputs[0])
                c.call("debug.echo", {}, probe.outputs[0])
                echo = time.perf_counter() - t1
            row = {"total": total, "export": probe.t["export"],
                   "mesh_to_arrays": probe.t["mesh_to_arrays"], "round_trip": round_trip,
                   "daemon": daemon, "transfer": round_trip - daemon,
                   "import": probe.t["import"], "mesh_from_arrays": probe.t["mesh_from_arrays"],
                   "echo": echo, "sent": probe.sent, "received": probe.received,
                   "out_tris": out_tris}
            row["remainder"] = total - row["export"] - round_trip - row["import"]
            info["sent_names"] = sorted(probe.inputs[0])
            if rep > 0:
                rows.append(row)
            print("%s %d: %s" % ("repeat" if rep else "warm-up", rep, "  ".join(
                "%s %.3f" % (k, v) for k, v in row.items() if isinstance(v, float))),
                file=sys.stderr)
            mesh = result.data
            bpy.data.objects.remove(result)
            bpy.data.meshes.remove(mesh)
            bpy.context.view_layer.update()
            probe.inputs, probe.outputs = [], []
    finally:
        probe.close()
    uninstall_addon()
    shutil.rmtree(repo_dir, ignore_errors=True)
    print("RESULT " + json.dumps({"rows": rows, "info": info}))


def run_scenario(zip_path, socket, args, repeats):
    """:func:`scenario` in a fresh Python with a throw-away Blender profile."""
    user = tempfile.mkdtemp(prefix="tessd-blender-user-")
    env = dict(os.environ, BLENDER_USER_RESOURCES=user)
    try:
        proc = subprocess.run(
            [sys.executable, __file__, "--scenario", str(zip_path), socket,
             str(args.subdivisions), str(args.target), str(repeats)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    finally:
        shutil.rmtree(user, ignore_errors=True)
    sys.stderr.write("".join(l + "\n" for l in proc.stderr.splitlines()
                             if l.startswith(("repeat", "warm-up"))))
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    if not lines:
        raise SystemExit("the scenario failed for %s:\n%s\n%s" % (zip_path, proc.stdout[-3000:],
                                                                 proc.stderr[-3000:]))
    return json.loads(lines[-1][len("RESULT "):])


def build_zip(tree, out, binary):
    """The extension zip of the add-on in `tree` (the working tree or an archived revision,
    which has no target folder of its own: `binary` is bundled)."""
    script = tree / "blender_addon" / "build.py"
    # Revisions before the daemon was bundled have no --binary.
    extra = ["--binary", binary] if "--binary" in script.read_text() else []
    subprocess.run([sys.executable, str(script), "--out", str(out), "--no-validate"] + extra,
                   check=True, stdout=subprocess.DEVNULL)
    return next(Path(out).glob("tessd-*.zip"))


def stats(rows):
    keys = rows[0].keys()
    return ({k: statistics.median(r[k] for r in rows) for k in keys},
            {k: min(r[k] for r in rows) for k in keys}, {k: max(r[k] for r in rows) for k in keys})


def fmt_ms(med, lo, hi, key):
    return "%.0f (%.0f–%.0f)" % (1e3 * med[key], 1e3 * lo[key], 1e3 * hi[key])


#: How the add-on reads and builds (issue 33), printed with the figures.
NOTES = """What the add-on does (issue 33, "What the user waits for"): it reads only what the mesh
has, each array once with `foreach_get` into a numpy array of the attribute's own dtype
(`position`, `.corner_vert`, the UV map, each generic attribute: Blender then copies the
whole array at once instead of converting element by element through Python's RNA layer,
~1 ms instead of ~100 ms per million values); a mesh of triangles sends `face_indices`
[F, 3] and no `face_sizes` (nothing to read: 3 × faces corners means only triangles); an
object without modifiers is read from its own mesh, without evaluating the depsgraph or
`to_mesh`; a `sharp_face` that is the same on every face does not travel (all true: the
result is made flat). The result is built the same way (`foreach_set` in the attribute's own
dtype, the faces' starts, one `mesh.update(calc_edges=True)`); the pass that flattens faces
with a corner normal more than 90° off is skipped when every face is flat. Vertex groups of
meshes of ≥ 20 000 vertices are read through a temporary geometry-nodes tree
(blender_addon/vertex_groups.py) instead of a Python loop over the vertices. In the UI (a
modal job, which this script does not use: it calls the operator as a script does), the
first tick now runs at once and the job ticks every 0.02 s instead of every 0.1 s, so a
reply is taken up to 20 ms after it came instead of up to 100 ms."""


def daemon_label(path):
    """The daemon's path (relative to the repository when inside it) and its build time."""
    label = os.path.relpath(path, REPO) if path.startswith(str(REPO)) else path
    when = datetime.datetime.fromtimestamp(os.path.getmtime(path), datetime.timezone.utc)
    return "%s`, built %s UTC" % (label, when.strftime("%Y-%m-%d %H:%M"))


def load_average():
    try:
        return "%.2f / %.2f / %.2f" % os.getloadavg()
    except OSError:
        return "?"


def report(args, results, load_before, load_after):
    after = results["after"]
    info = after["info"]
    med, lo, hi = stats(after["rows"])
    mib = 2 ** 20
    cmd = ".venv/bin/python bench/blender_roundtrip.py" + "".join(
        " --%s %s" % (k, v) for k, v in (("subdivisions", args.subdivisions),
                                        ("target", "%g" % args.target), ("repeats", args.repeats),
                                        ("rounds", args.rounds)))
    if args.before:
        cmd += " --before %s" % args.before
        if args.before_daemon:
            cmd += " --before-daemon %s" % args.before_daemon
    thousands = lambda n: format(int(n), ",").replace(",", " ")
    lines = [
        "# Blender round trip: Simplify from the operator call to the new object",
        "",
        "Machine: %s: **shared and noisy** (other jobs ran beside it; read the split, not "
        "the last digit; load average 1 / 5 / 15 min: %s before, %s after); Blender %s (PyPI "
        "`bpy`), numpy %s; %s." % (machine(), load_before, load_after, info["blender"],
                                   info["numpy"], datetime.date.today().isoformat()),
        "Command: `%s` (daemon: `%s%s)." % (
            cmd, daemon_label(args.binary),
            "; before: `%s" % daemon_label(args.before_daemon) if args.before_daemon else ""),
        "",
        "Input: ico sphere, %s vertices, %s triangles, through `bpy.ops.tessd.simplify(method="
        "'COMPLEXITY', target=%g, target_is_percent=True)` (barycentre representatives; the "
        "evaluated mesh; Blender's normals, so no corner normals are sent) → %s triangles. "
        "Arrays sent: %.1f MiB (%s); received: %.1f MiB." % (
            thousands(info["vertices"]), thousands(info["triangles"]), args.target,
            thousands(med["out_tris"]), med["sent"] / mib,
            ", ".join("`%s`" % n for n in info["sent_names"]), med["received"] / mib),
        "",
    ]
    if "before" in results:
        binfo = results["before"]["info"]
        bmed, blo, bhi = stats(results["before"]["rows"])
        lines += [
            "Before: the add-on of `%s`, sending %.1f MiB (%s), receiving %.1f MiB. Median of %d "
            "calls each (ms; range min–max), in %d alternating rounds:" % (
                args.before, bmed["sent"] / mib, ", ".join("`%s`" % n for n in binfo["sent_names"]),
                bmed["received"] / mib, len(after["rows"]), args.rounds),
            "",
            "| step | before | after | after / before | what |",
            "|---|---|---|---|---|",
        ]
        for key, label, what in STEPS:
            ratio = med[key] / bmed[key] if bmed[key] > 0 else float("nan")
            lines.append("| %s | %s | %s | %.2f× | %s |" % (
                label, fmt_ms(bmed, blo, bhi, key), fmt_ms(med, lo, hi, key), ratio, what))
        lines += ["", "Request round trip (submit → reply, = transfer + daemon work): %.0f ms "
                  "before, %.0f ms after." % (1e3 * bmed["round_trip"], 1e3 * med["round_trip"])]
    else:
        lines += ["Median of %d calls (ms; range min–max):" % len(after["rows"]), "",
                  "| step | median | range | share | what |", "|---|---|---|---|---|"]
        for key, label, what in STEPS:
            lines.append("| %s | %.0f | %.0f–%.0f | %.0f %% | %s |" % (
                label, 1e3 * med[key], 1e3 * lo[key], 1e3 * hi[key],
                100.0 * med[key] / med["total"], what))
        lines += ["", "Request round trip (submit → reply, = transfer + daemon work): %.0f ms."
                  % (1e3 * med["round_trip"])]
    lines += [
        "Cross-check of the transfer: `debug.echo` of the same input arrays and then of the "
        "output arrays, on a fresh connection, takes %.0f ms (median, after), for twice the bytes "
        "of the request (each array goes to the daemon and back: %.1f MiB in all), so one "
        "request's transfer should be about half of it." % (
            1e3 * med["echo"], 2 * (med["sent"] + med["received"]) / mib),
        "",
        NOTES,
        "",
    ]
    return "\n".join(lines)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--scenario":
        zip_path, socket, subdivisions, target, repeats = sys.argv[2:7]
        return scenario(zip_path, socket, int(subdivisions), float(target), int(repeats))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--subdivisions", type=int, default=9,
                    help="ico sphere subdivisions (9: 1 310 720 triangles)")
    ap.add_argument("--target", type=float, default=10.0, help="complexity goal, %% of vertices")
    ap.add_argument("--repeats", type=int, default=6, help="counted calls per add-on")
    ap.add_argument("--rounds", type=int, default=None,
                    help="alternating rounds (default 3 with --before, else 1)")
    ap.add_argument("--before", help="git revision of the add-on to compare against")
    ap.add_argument("--before-daemon", help="the daemon binary for the before runs (default: "
                                            "the same as after)")
    ap.add_argument("--out", default=str(REPO / "bench" / "results" / "blender_roundtrip.md"),
                    help="markdown report ('' for none)")
    args = ap.parse_args()
    if args.rounds is None:
        args.rounds = 3 if args.before else 1
    args.rounds = max(1, min(args.rounds, args.repeats))
    sys.path[:0] = TEST_PATHS
    import locate
    from daemon_util import DaemonProcess, short_tmpdir

    binary = args.binary = str(locate.tessd_bin())
    tmp = Path(tempfile.mkdtemp(prefix="tessd-roundtrip-"))
    zips = {"after": build_zip(REPO, tmp / "dist_after", binary)}
    if args.before:
        old = tmp / "old"
        old.mkdir()
        archive = subprocess.run(["git", "archive", args.before, "blender_addon", "python/tessd"],
                                 cwd=REPO, stdout=subprocess.PIPE, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
        zips["before"] = build_zip(old, tmp / "dist_before", args.before_daemon or binary)
    per_round = [args.repeats // args.rounds + (1 if i < args.repeats % args.rounds else 0)
                 for i in range(args.rounds)]
    load_before = load_average()
    results = {k: {"rows": []} for k in zips}
    with short_tmpdir() as d:
        daemons = {"after": DaemonProcess(binary, os.path.join(d, "a.sock")).start()}
        try:
            if args.before:
                daemons["before"] = (DaemonProcess(args.before_daemon, os.path.join(d, "b.sock")).start()
                                     if args.before_daemon else daemons["after"])
            for n in per_round:
                for which in [k for k in ("before", "after") if k in zips]:
                    res = run_scenario(zips[which], daemons[which].socket, args, n)
                    results[which]["rows"] += res["rows"]
                    results[which]["info"] = res["info"]
        finally:
            for proc in {id(p): p for p in daemons.values()}.values():
                proc.stop()
    shutil.rmtree(tmp, ignore_errors=True)
    text = report(args, results, load_before, load_average())
    print(text)
    if args.out:
        Path(args.out).write_text(text)
        print("wrote", args.out)


if __name__ == "__main__":
    main()
