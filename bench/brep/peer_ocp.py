#!/usr/bin/env python3
"""OCP side of the B-Rep benchmark (bench/run_brep.sh): the parts exported to tessd-brep JSON,
and OCP's own static tessellation (`BRepMesh_IncrementalMesh`) timed and counted on the same
shapes.

    peer_ocp.py export --data DIR --work WORK
    peer_ocp.py mesh --manifest WORK/parts.json --jsonl FILE [--deflections 0.1,0.01]
                     [--parallel 0,1] [--budget 2] [--min-repeat 3] [--max-repeat 9]
                     [--slow-s 5] [--only NAME,..]

Run with the CAD venv's interpreter (/work/main/.venv-cad/bin/python: OCP 7.9) or the build123d
venv's (.venv-b123d: OCP 8.0) and PYTHONPATH=python (the exporter `tessd.brep`): the parts are
built with OCP alone and the OCP names that 8.0 moved come from tessd.brep.ocp_compat.

`export` writes, under WORK: `json/<part>.json` (the document, `tessd.brep` exporter, units mm),
`shapes/<part>.brep` for the cadquery parts (so that `mesh` re-reads exactly the exported
shape), and `parts.json` (the manifest: name, kind, source, paths, face count, export time or
the error, and the faces whose edges OCP tolerates more than 0.01 mm off the surface). The parts:
every .step/.stp/.iges/.igs/.brep/.brp file in DIR, the OCP-built parts of tests/brep/ocp_parts.py
(its `PARTS` dict, imported; named `cq_*` as when cadquery built them, so results compare) and
`plate_540_holes` built here (a plate with 540 through holes, the "face with hundreds of trims"
case of the paper's figure 1).

`mesh` times `BRepMesh_IncrementalMesh(shape, deflection, False, 0.5, parallel)` (absolute
linear deflection in the shape's unit, mm; angular deflection 0.5 rad, the default) for each
part, deflection and parallel flag: the shape is read once (untimed), then before every run its
triangulations are removed (`BRepTools.Clean_s`, untimed) so each run meshes from scratch; one
warm-up run, then budget / warm-up time runs clamped to [min-repeat, max-repeat] (a part whose
warm-up takes more than --slow-s seconds gets only the warm-up run, reported as such). After the
last run the Poly_Triangulation of every face is counted: its nodes (vertices; OCP keeps a node
array per face, so an edge's points count once per face, as in a static tessellation uploaded
face by face) and triangles. `bytes_36` = 36 bytes × vertices, the paper's table-3 rule
(coordinates, normal, colour). One JSON line per (part, deflection, parallel), `tool` = "ocp".
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
import traceback
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
for p in (REPO / "python", REPO / "tests", REPO / "tests" / "brep"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

EXTENSIONS = (".step", ".stp", ".iges", ".igs", ".brep", ".brp")


def plate_540_holes():
    """A 300 × 200 × 5 mm plate with 27 × 20 = 540 through holes of 4 mm: its two large faces
    carry 541 loops each (the paper's figure 1 case). The holes are cut at once (one compound
    tool): one boolean, not 540."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    import ocp_parts  # tests/brep

    tools, b = TopoDS_Compound(), BRep_Builder()
    b.MakeCompound(tools)
    for i in range(27):
        for j in range(20):
            b.Add(tools, ocp_parts.cylinder(2.0, 7.0, (10.0 * (i - 13), 9.0 * (j - 9.5), -3.5)))
    return ocp_parts.cut(ocp_parts.box(300, 200, 5), tools)


def cadquery_parts():
    """name -> builder: the test suite's OCP-built PARTS (tests/brep/ocp_parts.py; `cq_` names,
    as when cadquery built them) plus the plate with 540 holes."""
    import ocp_parts  # tests/brep: OCP only (7.9 or 8.0)

    parts = {f"cq_{name}": fn for name, fn in ocp_parts.PARTS.items()}
    parts["cq_plate_540_holes"] = plate_540_holes
    return parts


def quiet_stdout():
    """OCCT's readers print to standard output; send fd 1 to standard error meanwhile."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    return saved


def restore_stdout(saved):
    sys.stdout.flush()
    os.dup2(saved, 1)
    os.close(saved)


def loose_edges(shape, above=0.01, most=6):
    """The faces whose edges OCP tolerates farthest off the surface (`BRep_Tool.Tolerance` of
    the edges, the data's own gap), above `above` (mm): [[face id, largest edge tolerance], ..],
    the largest first, at most `most` of them. A mesh cannot be closer to the surface than its
    boundary is."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS

    from tessd.brep.ocp_compat import TopTools_IndexedMapOfShape, static

    fmap = TopTools_IndexedMapOfShape()
    static(TopExp, "MapShapes")(shape, TopAbs_FACE, fmap)
    out = []
    for i in range(1, fmap.Extent() + 1):
        emap = TopTools_IndexedMapOfShape()
        static(TopExp, "MapShapes")(fmap.FindKey(i), TopAbs_EDGE, emap)
        tol = max((static(BRep_Tool, "Tolerance")(static(TopoDS, "Edge")(emap.FindKey(k)))
                   for k in range(1, emap.Extent() + 1)), default=0.0)
        if tol > above:
            out.append([i, tol])
    return sorted(out, key=lambda ft: -ft[1])[:most]


def export(args):
    from OCP.BRepTools import BRepTools

    from tessd.brep import ocp
    from tessd.brep.ocp_compat import static

    work = Path(args.work)
    (work / "json").mkdir(parents=True, exist_ok=True)
    (work / "shapes").mkdir(parents=True, exist_ok=True)
    data = Path(args.data)
    files = sorted(p for p in data.glob("*") if p.suffix.lower() in EXTENSIONS) if data.is_dir() else []
    if not files:
        print(f"peer_ocp: no B-Rep files in {data}", file=sys.stderr)
    manifest = []

    def write(name, kind, source, shape_path, build):
        entry = {"name": name, "kind": kind, "source": source, "shape": str(shape_path)}
        t0 = time.perf_counter()
        try:
            shape, doc = build()
            t1 = time.perf_counter()
            text = json.dumps(doc, allow_nan=False, separators=(",", ":"))
            out = work / "json" / f"{name}.json"
            out.write_text(text)
            entry.update(json=str(out), faces=len(doc["faces"]), edges=len(doc.get("edges") or []),
                         units=doc["units"], export_ms=1000 * (t1 - t0), json_bytes=len(text))
            entry["loose_faces"] = loose_edges(shape)
            if kind == "cadquery":
                static(BRepTools, "Write")(shape, str(shape_path))
        except Exception as e:  # noqa: BLE001 - reported, the run goes on
            entry["error"] = f"{type(e).__name__}: {e}"
            traceback.print_exc()
        manifest.append(entry)
        print(f"peer_ocp export: {name}: " + (entry.get("error") or
              f"{entry['faces']} faces, {entry['export_ms']:.0f} ms"), file=sys.stderr)

    for path in files:
        def build(path=path):
            saved = quiet_stdout()
            try:
                shape = ocp.read_file(str(path), units="mm")
            finally:
                restore_stdout(saved)
            return shape, ocp.export_topods(shape, units="mm", source=path.name)

        write(path.name, "file", str(path), path, build)

    try:
        parts = cadquery_parts()
    except Exception as e:  # noqa: BLE001
        print(f"peer_ocp: cannot import the cadquery parts: {e}", file=sys.stderr)
        manifest.append({"name": "cadquery parts", "kind": "cadquery", "error": f"import: {e}"})
        parts = {}
    for name, fn in parts.items():
        def build(fn=fn, name=name):
            shape = ocp.to_topods(fn())
            return shape, ocp.export_topods(shape, units="mm", source=name)

        write(name, "cadquery", f"tests/brep/test_brep_export.py PARTS[{name[3:]!r}]"
              if name != "cq_plate_540_holes" else "bench/brep/peer_ocp.py plate_540_holes",
              work / "shapes" / f"{name}.brep", build)
    (work / "parts.json").write_text(json.dumps(manifest, indent=1))
    return 0


def read_shape(path):
    from tessd.brep import ocp

    saved = quiet_stdout()
    try:
        return ocp.read_file(str(path), units="mm")
    finally:
        restore_stdout(saved)


def count(shape):
    """(vertices, triangles, faces, faces without a triangulation) over the shape's faces."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    from tessd.brep.ocp_compat import TopTools_IndexedMapOfShape, static

    fmap = TopTools_IndexedMapOfShape()
    static(TopExp, "MapShapes")(shape, TopAbs_FACE, fmap)
    nv = nt = missing = 0
    for i in range(1, fmap.Extent() + 1):
        loc = TopLoc_Location()
        tri = static(BRep_Tool, "Triangulation")(static(TopoDS, "Face")(fmap.FindKey(i)), loc)
        if tri is None or tri.NbTriangles() == 0:
            missing += 1
        else:
            nv += tri.NbNodes()
            nt += tri.NbTriangles()
    return nv, nt, fmap.Extent(), missing


def distance_to_surface(surf, c, u, v, bounds, steps=6):
    """The distance from point `c` (x, y, z) to the surface adaptor `surf`, projecting with
    Gauss-Newton steps from (u, v), parameters clamped to `bounds` (as bench-brep does)."""
    from OCP.gp import gp_Pnt, gp_Vec

    u0, u1, v0, v1 = bounds
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    best = math.inf
    for _ in range(steps + 1):
        surf.D1(u, v, p, du, dv)
        r = (c[0] - p.X(), c[1] - p.Y(), c[2] - p.Z())
        best = min(best, math.sqrt(r[0] ** 2 + r[1] ** 2 + r[2] ** 2))
        a = du.X() ** 2 + du.Y() ** 2 + du.Z() ** 2
        d = dv.X() ** 2 + dv.Y() ** 2 + dv.Z() ** 2
        b = du.X() * dv.X() + du.Y() * dv.Y() + du.Z() * dv.Z()
        det = a * d - b * b
        if not (abs(det) > 1e-30 and math.isfinite(det)):
            break
        gu = du.X() * r[0] + du.Y() * r[1] + du.Z() * r[2]
        gv = dv.X() * r[0] + dv.Y() * r[1] + dv.Z() * r[2]
        u = min(max(u + (d * gu - b * gv) / det, u0), u1)
        v = min(max(v + (a * gv - b * gu) / det, v0), v1)
    return best


def deviation(shape, tol, limit):
    """Centroid deviation of the shape's triangulation, as bench-brep measures tessd's: the
    distance from a triangle's centroid to the face's surface (`BRepAdaptor_Surface`, location
    included), projected by Gauss-Newton from the mean of its corners' (u, v). At most `limit`
    triangles, evenly strided over all of them. Returns the max, p99, fraction over tol,
    triangles measured and the worst face's index (OCP's face map, 1-based = the exported id)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    from tessd.brep.ocp_compat import TopTools_IndexedMapOfShape, static

    fmap = TopTools_IndexedMapOfShape()
    static(TopExp, "MapShapes")(shape, TopAbs_FACE, fmap)
    face_of = static(TopoDS, "Face")
    tris = []
    for i in range(1, fmap.Extent() + 1):
        loc = TopLoc_Location()
        t = static(BRep_Tool, "Triangulation")(face_of(fmap.FindKey(i)), loc)
        if t is not None and t.HasUVNodes():
            tris.append((i, t, loc))
    total = sum(t.NbTriangles() for _, t, _ in tris)
    if total == 0:
        return None
    stride = max(1, total // limit)
    ds, worst, seen = [], (0.0, None), 0
    for i, t, loc in tris:
        surf = BRepAdaptor_Surface(face_of(fmap.FindKey(i)))
        bounds = (surf.FirstUParameter(), surf.LastUParameter(), surf.FirstVParameter(), surf.LastVParameter())
        trsf = loc.Transformation()
        n = t.NbTriangles()
        first = (-seen) % stride
        seen += n
        for k in range(first + 1, n + 1, stride):
            a, b, c = t.Triangle(k).Get()
            cx = cy = cz = u = v = 0.0
            for idx in (a, b, c):
                p = t.Node(idx).Transformed(trsf)
                q = t.UVNode(idx)
                cx += p.X(); cy += p.Y(); cz += p.Z(); u += q.X(); v += q.Y()
            d = distance_to_surface(surf, (cx / 3, cy / 3, cz / 3), u / 3, v / 3, bounds)
            ds.append(d)
            if d > worst[0]:
                worst = (d, i)
    ds.sort()
    return {"deviation_max": ds[-1], "deviation_p99": ds[min(len(ds) - 1, int(0.99 * len(ds)))],
            "deviation_over_fraction": sum(1 for d in ds if d > tol) / len(ds),
            "deviation_measured": len(ds), "deviation_worst_face": worst[1]}


def mesh_one(shape, deflection, parallel, args, measure_deviation):
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.BRepTools import BRepTools

    from tessd.brep.ocp_compat import static

    clean = static(BRepTools, "Clean")

    def once():
        clean(shape)
        c0 = time.process_time()
        t0 = time.perf_counter()
        m = BRepMesh_IncrementalMesh(shape, deflection, False, 0.5, parallel)
        dt = time.perf_counter() - t0
        return dt, time.process_time() - c0, m

    warm, warm_cpu, m = once()
    runs, cpu = [], []
    if warm < args.slow_s:
        n = max(args.min_repeat, min(args.max_repeat, int(args.budget / max(warm, 1e-6))))
        for _ in range(n):
            dt, c, m = once()
            runs.append(dt)
            cpu.append(c)
    only_warm = not runs
    if only_warm:
        runs, cpu = [warm], [warm_cpu]
    nv, nt, nf, missing = count(shape)
    rec = {
        "time_ms": 1000 * statistics.median(runs),
        "runs_ms": [1000 * r for r in runs],
        "cpu_ms": 1000 * statistics.median(cpu),
        "warmup_ms": 1000 * warm,
        "only_warmup": only_warm,
        "done": bool(m.IsDone()),
        "status_flags": int(m.GetStatusFlags()),
        "vertices": nv,
        "triangles": nt,
        "faces": nf,
        "faces_without_triangulation": missing,
        "bytes_36": 36 * nv,
    }
    if measure_deviation:
        rec.update(deviation(shape, deflection, args.deviation_samples) or {})
    return rec


def mesh(args):
    manifest = json.loads(Path(args.manifest).read_text())
    deflections = [float(x) for x in args.deflections.split(",")]
    # parallel first: a part too slow with it is not tried sequentially
    parallels = sorted({bool(int(x)) for x in args.parallel.split(",")}, reverse=True)
    only = set(args.only.split(",")) if args.only else None
    with open(args.jsonl, "a") as out:
        for entry in manifest:
            if "error" in entry or (only and entry["name"] not in only):
                continue
            try:
                t0 = time.perf_counter()
                shape = read_shape(entry["shape"])
                read_ms = 1000 * (time.perf_counter() - t0)
            except Exception as e:  # noqa: BLE001
                out.write(json.dumps({"tool": "ocp", "part": entry["name"], "error": f"read: {e}"}) + "\n")
                continue
            for d in deflections:
                slow = None
                for k, par in enumerate(parallels):
                    rec = {"tool": "ocp", "part": entry["name"], "deflection": d, "parallel": par,
                           "angular": 0.5, "read_ms": read_ms}
                    if slow:
                        rec["skipped"] = slow
                        out.write(json.dumps(rec) + "\n")
                        continue
                    try:
                        rec.update(mesh_one(shape, d, par, args, measure_deviation=(k == len(parallels) - 1)))
                    except Exception as e:  # noqa: BLE001
                        rec["error"] = f"{type(e).__name__}: {e}"
                    if rec.get("only_warmup"):
                        slow = f"not run: parallel={par} took over {args.slow_s} s"
                        if k + 1 < len(parallels):
                            rec.update(deviation(shape, d, args.deviation_samples) or {})
                    out.write(json.dumps(rec) + "\n")
                    out.flush()
                    print(f"peer_ocp mesh: {entry['name']:34} d={d:<5} parallel={int(par)} "
                          + (rec.get("error") or f"{rec['time_ms']:9.1f} ms  {rec['triangles']:8d} tri  "
                             f"{len(rec['runs_ms'])} runs"), file=sys.stderr)
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    ex = sub.add_parser("export", help="every part to tessd-brep JSON + the manifest")
    ex.add_argument("--data", required=True, help="folder of STEP / IGES / .brep files")
    ex.add_argument("--work", required=True, help="output folder")
    me = sub.add_parser("mesh", help="BRepMesh_IncrementalMesh timings and counts")
    me.add_argument("--manifest", required=True)
    me.add_argument("--jsonl", required=True, help="JSON lines to append to")
    me.add_argument("--deflections", default="0.1,0.01", help="linear deflections (mm)")
    me.add_argument("--parallel", default="0,1", help="BRepMesh's isInParallel flags (0,1)")
    me.add_argument("--budget", type=float, default=2.0, help="seconds of runs per configuration")
    me.add_argument("--min-repeat", type=int, default=3)
    me.add_argument("--max-repeat", type=int, default=9)
    me.add_argument("--slow-s", type=float, default=5.0,
                    help="a warm-up longer than this is the only run")
    me.add_argument("--only", default="", help="comma-separated part names")
    me.add_argument("--deviation-samples", type=int, default=20000,
                    help="most triangles measured for the centroid deviation")
    args = ap.parse_args(argv)
    return export(args) if args.cmd == "export" else mesh(args)


if __name__ == "__main__":
    sys.exit(main())
