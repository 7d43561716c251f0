"""Round trip of the add-on's Simplify on a ~1.3 M-triangle object, from the operator call to
the new object, split into Blender export, transfer, daemon work and Blender import.

    .venv/bin/python bench/blender_roundtrip.py [--subdivisions 9] [--target 10] [--repeats 5]
                                                [--out bench/results/blender_roundtrip.md]

Real Blender (the PyPI `bpy` module in .venv), the extension built and installed as the tests
do (tests/blender_addon/addon_env.py), a real daemon (target/release/tessd or $TESSD_BIN).
Every number comes from the one real `bpy.ops.tessd.simplify(...)` call, instrumented from the
outside (nothing in the add-on is changed):

- export: the conversion of the object, `common.arrays_of` (evaluated mesh -> protocol arrays,
  `foreach_get` + numpy; of which `convert.mesh_to_arrays` alone), run from the job's tick;
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
sys.path[:0] = [str(REPO / "tests" / "blender_addon"), str(REPO / "tests"),
                str(REPO / "tests" / "daemon"), str(REPO / "python")]
_USER = tempfile.mkdtemp(prefix="tessd-blender-user-")
os.environ.setdefault("BLENDER_USER_RESOURCES", _USER)


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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--subdivisions", type=int, default=9,
                    help="ico sphere subdivisions (9: 1 310 720 triangles)")
    ap.add_argument("--target", type=float, default=10.0, help="complexity goal, %% of vertices")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(REPO / "bench" / "results" / "blender_roundtrip.md"),
                    help="markdown report ('' for none)")
    args = ap.parse_args()

    import bpy

    import locate
    from addon_env import ADDON, install_addon, uninstall_addon
    from daemon_util import DaemonProcess, short_tmpdir

    dist = Path(tempfile.mkdtemp(prefix="tessd-dist-"))
    subprocess.run([sys.executable, str(REPO / "blender_addon" / "build.py"), "--out", str(dist),
                    "--no-validate"], check=True, stdout=subprocess.DEVNULL)
    rows = []
    with short_tmpdir() as d:
        proc = DaemonProcess(str(locate.tessd_bin()), os.path.join(d, "t.sock")).start()
        try:
            install_addon(next(dist.glob("tessd-*.zip")), dist / "repo", proc.socket)
            tessd = sys.modules[ADDON + ".client"].tessd
            bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=args.subdivisions)
            obj = bpy.context.object
            n_tris, n_verts = len(obj.data.polygons), len(obj.data.vertices)
            probe = Probe(ADDON)
            try:
                for rep in range(args.repeats):
                    for o in list(bpy.context.selected_objects):
                        o.select_set(False)
                    obj.select_set(True)
                    bpy.context.view_layer.objects.active = obj
                    probe.reset()
                    t0 = time.perf_counter()
                    r = bpy.ops.tessd.simplify(method='COMPLEXITY', target=args.target,
                                               target_is_percent=True)
                    total = time.perf_counter() - t0
                    assert r == {'FINISHED'}, r
                    (label, round_trip), = probe.job.timings
                    daemon = probe.client_jobs[-1].elapsed_ms / 1e3
                    result = bpy.data.objects[obj.name + "_simplified"]
                    out_tris = len(result.data.polygons)
                    with tessd.Client(proc.socket) as c:
                        t1 = time.perf_counter()
                        c.call("debug.echo", {}, probe.inputs[0])
                        c.call("debug.echo", {}, probe.outputs[0])
                        echo = time.perf_counter() - t1
                    sent_names = sorted(probe.inputs[0])
                    row = {"total": total, "export": probe.t["export"],
                           "mesh_to_arrays": probe.t["mesh_to_arrays"], "round_trip": round_trip,
                           "daemon": daemon, "transfer": round_trip - daemon,
                           "import": probe.t["import"], "mesh_from_arrays": probe.t["mesh_from_arrays"],
                           "echo": echo, "sent": probe.sent, "received": probe.received,
                           "out_tris": out_tris}
                    row["remainder"] = total - row["export"] - round_trip - row["import"]
                    rows.append(row)
                    print("repeat %d: %s" % (rep + 1, "  ".join(
                        "%s %.3f" % (k, v) for k, v in row.items() if isinstance(v, float))))
                    mesh = result.data
                    bpy.data.objects.remove(result)
                    bpy.data.meshes.remove(mesh)
                    bpy.context.view_layer.update()
                    probe.inputs, probe.outputs = [], []
            finally:
                probe.close()
            uninstall_addon()
        finally:
            proc.stop()
    shutil.rmtree(dist, ignore_errors=True)
    shutil.rmtree(_USER, ignore_errors=True)

    med = {k: statistics.median(r[k] for r in rows) for k in rows[0]}
    lo = {k: min(r[k] for r in rows) for k in rows[0]}
    hi = {k: max(r[k] for r in rows) for k in rows[0]}
    mib = 2 ** 20

    def line(name, key, what):
        share = 100.0 * med[key] / med["total"]
        return "| %s | %.0f | %.0f–%.0f | %.0f %% | %s |" % (
            name, 1e3 * med[key], 1e3 * lo[key], 1e3 * hi[key], share, what)

    cmd = ".venv/bin/python bench/blender_roundtrip.py" + "".join(
        " --%s %s" % (k, v) for k, v in (("subdivisions", args.subdivisions), ("target", "%g" % args.target),
                                        ("repeats", args.repeats)))
    report = "\n".join([
        "# Blender round trip: Simplify from the operator call to the new object",
        "",
        "Machine: %s: **shared and noisy** (other jobs ran beside it; read the split, not "
        "the last digit); Blender %s (PyPI `bpy`), numpy %s; %s." % (
            machine(), bpy.app.version_string, __import__("numpy").__version__,
            datetime.date.today().isoformat()),
        "Command: `%s` (daemon: `target/release/tessd serve`)." % cmd,
        "",
        "Input: ico sphere, %s vertices, %s triangles, through `bpy.ops.tessd.simplify(method="
        "'COMPLEXITY', target=%g, target_is_percent=True)` (barycentre representatives; the "
        "evaluated mesh; Blender's normals, so no corner normals are sent) → %s triangles. "
        "Arrays sent: %.1f MiB (%s); received: %.1f MiB." % (
            format(n_verts, ",").replace(",", " "), format(n_tris, ",").replace(",", " "),
            args.target, format(int(med["out_tris"]), ",").replace(",", " "),
            med["sent"] / mib, ", ".join("`%s`" % n for n in sent_names), med["received"] / mib),
        "",
        "Median of %d calls (ms; range min–max):" % len(rows),
        "",
        "| step | median | range | share | what |",
        "|---|---|---|---|---|",
        line("**whole operator**", "total", "`bpy.ops.tessd.simplify(...)` call to the new object"),
        line("Blender export", "export", "`common.arrays_of` (from the job's tick): evaluated mesh → arrays, "
             "`foreach_get` + numpy"),
        line("  of which `mesh_to_arrays`", "mesh_to_arrays", "the `foreach_get` reads alone "
             "(the rest: `to_mesh` of the evaluated object)"),
        line("transfer (both directions)", "transfer", "request round trip − daemon work"),
        line("daemon work", "daemon", "`elapsed_ms` of the daemon's `ok` frame (`Job.elapsed_ms`)"),
        line("Blender import", "import", "the operator's `apply_task`: arrays → mesh with "
             "`foreach_set`, object creation"),
        line("  of which `mesh_from_arrays`", "mesh_from_arrays", "the `foreach_set` writes and "
             "`mesh.update`"),
        line("remainder", "remainder", "connect, the complexity target from the arrays, operator "
             "dispatch, undo push"),
        "",
        "Request round trip (submit → reply, = transfer + daemon work): %.0f ms. Cross-check of "
        "the transfer: `debug.echo` of the same input arrays and then of the output arrays, on a "
        "fresh connection, takes %.0f ms (median), for twice the bytes of the request (each array "
        "goes to the daemon and back: %.1f MiB in all), so one request's transfer should be about "
        "half of it." % (1e3 * med["round_trip"], 1e3 * med["echo"],
                         2 * (med["sent"] + med["received"]) / mib),
        "",
    ])
    print(report)
    if args.out:
        Path(args.out).write_text(report)
        print("wrote", args.out)


if __name__ == "__main__":
    main()
