"""Round trip from FreeCAD (issue 14's acceptance): a ~1 000-face STEP assembly, click to result,
for the workbench's Tessellate (0.1 mm) and Simplify, split into FreeCAD-side work, transfer and
daemon work, beside FreeCAD's own `MeshPart.meshFromShape` at the same tolerance (and, for
Simplify, FreeCAD's `Mesh.decimate`). Runs inside FreeCAD's console:

    bash bench/run_freecad.sh        # installs the workbench in a throw-away HOME, runs this

The assembly: shared parts (featuretype.step ×6, CrankArm.brep ×4, bottle.brep ×3: 1 001 faces)
placed side by side, written as one STEP assembly with FreeCAD's Import module and read back
(`Part.read`, one Part::Feature per part of the assembly: FreeCAD 0.20's OCAF importer
crashes in the console). Every figure is
the median of RUNS runs; the workbench's tessellation cache is cleared before each run.

The split of the workbench's time (instrumented by wrapping the functions the tasks call):
- prepare: `api.prepare_tessellate` on the GUI thread (reading the objects, copying the shapes);
- export: the B-Rep export: OpenCASCADE's BREP text (`Shape.exportBrepToString()`, C++; the
  daemon reads it, core/brep/src/occt) as shipped, or — the "Python export" row, the fallback
  for geometry that reader refuses — the tessd-brep document of tessd.brep.freecad (Python,
  FreeCAD's Part API);
- wait: time the worker thread is blocked on daemon requests (`Task.wait`);
- daemon: the daemon's own time for its requests (`elapsed_ms` of each job, summed);
- build: welding and building the FreeCAD meshes; apply: creating the document objects.
The shipped workbench pipelines the parts (tessellation.IN_FLIGHT = 2: the next part is exported
while the daemon tessellates the previous one, so daemon time hides behind the export); the
sequential run (one request at a time) shows the transfer: wait − daemon.
"""

import json
import os
import statistics
import sys
import tempfile
import time

import FreeCAD
import Import
import Mesh
import MeshPart
import Part

RUNS = int(os.environ.get("RUNS", "5"))
OUT = os.environ.get("BENCH_OUT", "bench/results/freecad_roundtrip.json")
SHARED = os.environ.get("TESSD_SHARED_DATA", os.path.join(os.getcwd(), "../shared/data"))
TOLERANCE_MM = 0.1
ANGLE = 0.5


def read_part(name):
    path = os.path.join(SHARED, "brep", name)
    if name.endswith(".step"):
        shape = Part.read(path)
    else:
        shape = Part.Shape()
        shape.read(path)
    return shape


def build_assembly(path):
    """The STEP assembly: copies of shared parts on a grid, one Part::Feature each."""
    doc = FreeCAD.newDocument("assembly_src")
    parts = [("featuretype.step", 6), ("CrankArm.brep", 4), ("bottle.brep", 3)]
    objs, x = [], 0.0
    for name, copies in parts:
        shape = read_part(name)
        size = shape.BoundBox.DiagonalLength
        for k in range(copies):
            o = doc.addObject("Part::Feature", "%s_%d" % (name.split(".")[0], k))
            o.Shape = shape.copy()
            o.Placement = FreeCAD.Placement(FreeCAD.Vector(x, 0, 0), FreeCAD.Rotation())
            x += 1.2 * size
            objs.append(o)
    doc.recompute()
    Import.export(objs, path)
    FreeCAD.closeDocument(doc.Name)


def median(xs):
    return statistics.median(xs) if xs else 0.0


def main():
    from freecad.tessd import api, daemon_link, meshes, task, tessellation

    tmp = tempfile.mkdtemp(prefix="tessd_fc_bench_")
    # A private socket: the workbench starts its own daemon from $TESSD_BIN, never one that
    # some earlier session left running on the default socket (another build).
    prefs = FreeCAD.ParamGet(daemon_link.PARAM_PATH)
    prefs.SetString("Socket", os.path.join(tmp, "d.sock"))
    prefs.SetString("BinaryPath", "")
    step = os.path.join(tmp, "assembly.step")
    build_assembly(step)
    doc = FreeCAD.newDocument("bench")
    # Read back one object per part of the assembly (Import.insert's OCAF reader crashes in
    # FreeCAD 0.20's console; Part.read reads the same STEP file as one compound).
    assembly = Part.read(step)
    parts = []
    for k, child in enumerate(assembly.childShapes()):
        o = doc.addObject("Part::Feature", "part_%02d" % k)
        o.Shape = child
        parts.append(o)
    doc.recompute()
    faces = sum(len(o.Shape.Faces) for o in parts)
    print("assembly: %s, %d objects, %d faces" % (os.path.basename(step), len(parts), faces))

    # Instrumentation: time what the task calls.
    clock = {}

    def timed(key, fn):
        def wrapper(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                clock[key] = clock.get(key, 0.0) + time.perf_counter() - t
        return wrapper

    tessellation.export_shape = timed("export", tessellation.export_shape)
    tessellation.brep_text = timed("export", tessellation.brep_text)
    meshes.weld = timed("build", meshes.weld)
    meshes.build_mesh = timed("build", meshes.build_mesh)
    original_wait = task.Task.wait
    daemon = []

    def wait(self, job, *a, **k):
        t = time.perf_counter()
        out = original_wait(self, job, *a, **k)
        clock["wait"] = clock.get("wait", 0.0) + time.perf_counter() - t
        daemon.append((job.elapsed_ms or 0.0) / 1e3)
        return out
    task.Task.wait = wait

    def tessd_tessellate(in_flight, native=True):
        tessellation.IN_FLIGHT = in_flight
        tessellation.NATIVE_BREP = native
        tessellation._cache.clear()
        clock.clear()
        daemon.clear()
        t0 = time.perf_counter()
        t = api.prepare_tessellate(parts, tolerance="%gmm" % TOLERANCE_MM, angle=ANGLE, doc=doc)
        t1 = time.perf_counter()
        t.run()
        t2 = time.perf_counter()
        feats = t.apply(doc)
        t3 = time.perf_counter()
        tri = sum(f.Mesh.CountFacets for f in feats)
        for f in feats:
            doc.removeObject(f.Name)
        d = sum(daemon)
        return {
            "total": t3 - t0, "prepare": t1 - t0, "export": clock.get("export", 0.0),
            "wait": clock.get("wait", 0.0), "daemon": d, "build": clock.get("build", 0.0),
            "apply": t3 - t2, "triangles": tri,
        }

    def freecad_mesh():
        t0 = time.perf_counter()
        tri = 0
        for o in parts:
            m = MeshPart.meshFromShape(Shape=o.Shape, LinearDeflection=TOLERANCE_MM,
                                       AngularDeflection=ANGLE, Relative=False)
            f = doc.addObject("Mesh::Feature", o.Name + "_fc")
            f.Mesh = m
            tri += m.CountFacets
        t1 = time.perf_counter()
        for o in list(doc.Objects):
            if o.Name.endswith("_fc"):
                doc.removeObject(o.Name)
        return {"total": t1 - t0, "triangles": tri}

    rows = {"tessd": [], "sequential": [], "python_export": [], "meshFromShape": []}
    for _ in range(RUNS):
        rows["meshFromShape"].append(freecad_mesh())
        rows["tessd"].append(tessd_tessellate(2))
        rows["sequential"].append(tessd_tessellate(1))
        rows["python_export"].append(tessd_tessellate(2, native=False))
    tessellation.IN_FLIGHT = 2
    tessellation.NATIVE_BREP = True

    # Simplify the tessellated meshes to 20 % of their vertices (complexity goal, quadric).
    feats = api.tessellate(parts, tolerance="%gmm" % TOLERANCE_MM, angle=ANGLE, doc=doc)
    simp, decimate = [], []
    for _ in range(RUNS):
        clock.clear()
        daemon.clear()
        t0 = time.perf_counter()
        t = api.prepare_simplify(feats, method="complexity", target="20%", doc=doc)
        t1 = time.perf_counter()
        t.run()
        t2 = time.perf_counter()
        out = t.apply(doc)
        t3 = time.perf_counter()
        d = sum(daemon)
        simp.append({"total": t3 - t0, "prepare": t1 - t0, "daemon": d,
                     "transfer": clock.get("wait", 0.0) - d, "build": clock.get("build", 0.0),
                     "apply": t3 - t2,
                     "vertices": sum(o.Mesh.CountPoints for o in out)})
        for o in out:
            doc.removeObject(o.Name)
        t0 = time.perf_counter()
        verts = 0
        for f in feats:
            m = f.Mesh.copy()
            m.decimate(TOLERANCE_MM, 0.8)  # Mesh.decimate(tolerance, reduction): remove 80 %
            verts += m.CountPoints
        decimate.append({"total": time.perf_counter() - t0, "vertices": verts})

    def med(rows, key):
        return median([r[key] for r in rows])

    report = {
        "assembly": {"objects": len(parts), "faces": faces, "tolerance_mm": TOLERANCE_MM,
                     "angle": ANGLE, "runs": RUNS},
        "freecad": FreeCAD.Version()[:3],
        "tessellate": {k: med(rows["tessd"], k) for k in rows["tessd"][0]},
        "sequential": {k: med(rows["sequential"], k) for k in rows["sequential"][0]},
        "python_export": {k: med(rows["python_export"], k) for k in rows["python_export"][0]},
        "meshFromShape": {k: med(rows["meshFromShape"], k) for k in rows["meshFromShape"][0]},
        "simplify": {k: med(simp, k) for k in simp[0]},
        "decimate": {k: med(decimate, k) for k in decimate[0]},
        "input_vertices": sum(f.Mesh.CountPoints for f in feats),
    }
    daemon_link.release_all()
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w") as fh:
        json.dump(report, fh, indent=1)
    print(json.dumps(report, indent=1))


main()
