"""Issue 34's goal rows and bit budget table for the codec benchmark (run_codec.py calls these).

`goal_rows` measures what the per-mesh rows do not: the bunny in one nSP-cell, each mesh with
unreferenced vertices compressed again without them (Draco drops them: the size ratio then
compares the same points), and the one-core user time (RAYON_NUM_THREADS=1, GNU time %U,
median of 3) of `tessd compress` at 12 and 16 bits and `tessd decompress` on a ~1.1 M-triangle
torus. `goal_section` turns those rows and the per-mesh rows into Markdown: every goal of issue
34, reported even where missed, and the bit budget per family, before (the v1 figures stored by
budget_before.py in bench/results/codec_budget_before.json) and after (this run).
"""

import json
import math
import os
import statistics
import struct
import subprocess
from pathlib import Path

import numpy as np

import peers

ONE_CELL = "1000000000"
GD02 = {"geometry": 14.0, "connectivity": 3.5}
CONNECTIVITY = ("TriangleOnce", "Twice", "Thrice", "Point")
GEOMETRY = ("Split", "Ahead")
BEFORE = Path(__file__).resolve().parents[1] / "results" / "codec_budget_before.json"


def tsc_layout(path):
    """(head bytes, trailer bytes with its tail, tables bytes: none since version 2) of a version-2 or -3
    .tsc file (see core/codec/src/format.rs), or None for another version."""
    b = Path(path).read_bytes()
    if len(b) < 13 or b[:4] != b"TSC\x1a" or struct.unpack_from("<H", b, 4)[0] not in (2, 3):
        return None
    mask = b[8]
    at = 9 + sum(4 if mask >> i & 1 else 8 for i in range(4))
    while b[at] & 0x80:  # N_min varint
        at += 1
    head = at + 1
    trailer = struct.unpack_from("<I", b, len(b) - 4)[0]
    return head, trailer + 4, 0


def user_time(argv, repeats=3):
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    out = []
    for _ in range(repeats):
        r = subprocess.run(["/usr/bin/time", "-f", "%U", *map(str, argv)], capture_output=True, text=True,
                           env=env)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(map(str, argv))}: {r.stderr.strip()[-800:]}")
        out.append(float(r.stderr.strip().splitlines()[-1]))
    return out


def compress_json(binary, mesh, tsc, bits, args):
    r = subprocess.run([str(binary), "compress", str(mesh), str(tsc), "--bits", str(bits), *args, "--json"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr.strip()[-800:])
    js = json.loads(r.stdout)
    js["layout"] = tsc_layout(tsc)
    return js


def write_referenced_ply(verts, tris, path):
    """A binary PLY of the referenced vertices only (float32, as read) and the triangles."""
    used = np.zeros(len(verts), bool)
    used[tris.reshape(-1)] = True
    remap = np.cumsum(used) - 1
    v = verts[used].astype("<f4")
    t = remap[tris].astype("<i4")
    with open(path, "wb") as fh:
        fh.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\n"
                  f"property float y\nproperty float z\nelement face {len(t)}\n"
                  "property list uchar int vertex_indices\nend_header\n").encode())
        rec = np.zeros(len(t), dtype=[("n", "u1"), ("i", "<i4", 3)])
        rec["n"], rec["i"] = 3, t
        fh.write(v.tobytes())
        fh.write(rec.tobytes())
    return int(used.sum())


def speed_mesh(work, binary_dir):
    """The ~1.1 M-triangle torus ($CODEC_SPEED_MESH, else generated once into the work folder
    with bench-simplify)."""
    for p in (os.environ.get("CODEC_SPEED_MESH"), Path(work) / "torus1m.ply"):
        if p and Path(p).is_file():
            return Path(p)
    gen = Path(binary_dir) / "bench-simplify"
    out = Path(work) / "torus1m.ply"
    subprocess.run([str(gen), "gen", "1100000", str(out)], check=True, capture_output=True)
    return out


def goal_rows(binary, files, work, tessd_args, bits=12, speed=True, repeats=3, gen_dir="target/release"):
    """The extra measurements of the goal rows, as "goal" JSON lines."""
    work = Path(work)
    rows = []
    args = tessd_args.split()
    one_cell = [a for a in args]
    if "--min-cell" in one_cell:
        one_cell[one_cell.index("--min-cell") + 1] = ONE_CELL
    else:
        one_cell += ["--min-cell", ONE_CELL]
    for path in files:
        verts, tris, nfaces = peers.load_mesh(str(path))
        row = {"record": "goal", "kind": "mesh", "mesh": path.stem, "p": bits}
        try:
            if path.stem in ("bun_zipper", "stanford_bunny", "fandisk"):
                row["default"] = compress_json(binary, path, work / f"{path.stem}_p{bits}_goal.tsc", bits, args)
                row["one_cell"] = compress_json(binary, path, work / f"{path.stem}_p{bits}_one.tsc", bits, one_cell)
            nref = len(np.unique(tris.reshape(-1))) if len(tris) else 0
            if 0 < nref < len(verts):
                stripped = work / f"{path.stem}_referenced.ply"
                write_referenced_ply(verts, tris, stripped)
                js = compress_json(binary, stripped, work / f"{path.stem}_p{bits}_referenced.tsc", bits, args)
                row["referenced_only"] = {"bytes": js["bytes"], "vertices": nref}
        except Exception as e:  # noqa: BLE001 — reported in the goal section
            row["error"] = str(e)
        rows.append(row)
    if speed:
        row = {"record": "goal", "kind": "speed"}
        try:
            mesh = speed_mesh(work, gen_dir)
            row["mesh"] = str(mesh)
            for b in (12, 16):
                tsc = work / f"speed_p{b}.tsc"
                js = compress_json(binary, mesh, tsc, b, args)
                row["triangles"] = js["input_triangles"]
                row[f"compress_{b}"] = user_time([binary, "compress", mesh, tsc, "--bits", b, *args], repeats)
                row[f"decompress_{b}"] = user_time([binary, "decompress", tsc, work / f"speed_p{b}.ply"], repeats)
        except Exception as e:  # noqa: BLE001
            row["error"] = str(e)
        rows.append(row)
    return rows


def _fam(js, names):
    f = js.get("bits_per_vertex_by_family") or {}
    return sum(f.get(n, 0.0) for n in names)


def _budget(js):
    """Budget rows (b/v) of one compression: families, tables, header + index + padding, file."""
    nv = max(1, js["input_vertices"])
    f = js.get("bits_per_vertex_by_family") or {}
    out = {"geometry (split codes)": f.get("Split", 0.0) + f.get("Ahead", 0.0),
           "triangles holding the split vertex once": f.get("TriangleOnce", 0.0),
           "held twice": f.get("Twice", 0.0), "held three times": f.get("Thrice", 0.0),
           "isolated points": f.get("Point", 0.0)}
    tables = js.get("tables_bytes")
    if tables is None and js.get("layout"):
        tables = js["layout"][2]
    out["tables"] = 8.0 * (tables or 0) / nv
    out["file"] = 8.0 * js["bytes"] / nv
    out["header, index, padding"] = out["file"] - sum(v for k, v in out.items() if k != "file")
    return out


def _mark(ok):
    return "–" if ok is None else ("**met**" if ok else "missed")


def _f(x, nd=2):
    return "–" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.{nd}f}"


def goal_section(rows, by, before_path=BEFORE):
    """Markdown lines: the goal table and the budget table. `by` maps (mesh, p, variant) to the
    per-mesh rows of run_codec.py."""
    goals = {r["mesh"]: r for r in rows if r.get("record") == "goal" and r.get("kind") == "mesh"}
    speed = next((r for r in rows if r.get("record") == "goal" and r.get("kind") == "speed"), None)
    before = json.loads(Path(before_path).read_text()) if Path(before_path).is_file() else {}
    bm = before.get("meshes", {})
    L = ["## Issue 34's goals\n",
         "Every goal of issue 34, reported even where missed. *before*: the v1 binary (commit 6598afde, "
         "format 1, `bench/results/codec_budget_before.json`, written by `bench/codec/budget_before.py`); "
         "*now*: this run. Bits per vertex over every input vertex; family bits as `tessd compress --json` "
         "reports them (v1: ideal lengths under the file's static tables). Geometry = split codes (+ ahead), "
         "connectivity = triangles held once, twice, three times and isolated points.\n",
         "| goal | target | before | now | |", "|---|---|---:|---:|---|"]

    def tjs(mesh, p=12):
        r = by.get((mesh, p, "tessd"))
        return r.get("compress_json") if r and "compress_json" in r else None

    bun = (goals.get("bun_zipper") or {}).get("default") or tjs("bun_zipper")
    bun1 = (goals.get("bun_zipper") or {}).get("one_cell")
    b0, b1 = bm.get("bun_zipper", {}).get("default"), bm.get("bun_zipper", {}).get("one_cell")
    for label, now, old, target in (("bun_zipper p12, default settings, b/v", bun, b0, 18.0),
                                    ("bun_zipper p12, one cell, b/v", bun1, b1, 17.5)):
        v = now["bits_per_vertex"] if now else None
        L.append(f"| {label} | ≤ {target} | {_f(old and old['bits_per_vertex'])} | {_f(v)} | "
                 f"{_mark(None if v is None else v <= target)} |")
    for label, names, gd in (("geometry", GEOMETRY, GD02["geometry"]),
                             ("connectivity", CONNECTIVITY, GD02["connectivity"])):
        for cell, now, old in (("default", bun, b0), ("one cell", bun1, b1)):
            L.append(f"| bun_zipper {label}, {cell}, b/v (GD02 ~{gd}) | – | {_f(old and _fam(old, names))} | "
                     f"{_f(now and _fam(now, names))} | |")
    for mesh in ("bun_zipper", "fandisk"):
        now, old = (goals.get(mesh) or {}).get("default") or tjs(mesh), bm.get(mesh, {}).get("default")
        v = _fam(now, CONNECTIVITY) if now else None
        L.append(f"| {mesh} connectivity, default, b/v | ≤ 4.5 | {_f(old and _fam(old, CONNECTIVITY))} | {_f(v)} | "
                 f"{_mark(None if v is None else v <= 4.5)} |")

    def ratio(mesh, p=12, size=None):
        t, d = by.get((mesh, p, "tessd")), by.get((mesh, p, "draco-10"))
        if not d or not d.get("bytes"):
            return None
        if size is None:
            if not t or "bytes" not in t:
                return None
            ref = (goals.get(mesh) or {}).get("referenced_only")
            size = ref["bytes"] if ref else t["bytes"]
        return size / d["bytes"]

    def old_ratio(mesh):
        o = bm.get(mesh, {}).get("default")
        return ratio(mesh, size=o["bytes"]) if o else None

    for mesh in ("bun_zipper", "stanford_bunny"):
        r = ratio(mesh)
        L.append(f"| {mesh} p12 size ÷ Draco-10 (referenced vertices only) | ≤ 1.3 | {_f(old_ratio(mesh))} | "
                 f"{_f(r)} | {_mark(None if r is None else r <= 1.3)} |")
    meshes = sorted({k[0] for k in by if k[1] == 12})
    rs = [ratio(m) for m in meshes]
    olds = [old_ratio(m) for m in meshes]
    g = math.exp(statistics.mean(math.log(x) for x in rs)) if rs and all(rs) else None
    go = math.exp(statistics.mean(math.log(x) for x in olds)) if olds and all(olds) else None
    L.append(f"| gmean size ÷ Draco-10 over the {len(meshes)} shared meshes, p12 | ≤ 1.4 | {_f(go)} | {_f(g)} | "
             f"{_mark(None if g is None else g <= 1.4)} |")
    per_mesh = ", ".join(f"{m} {_f(r)}" for m, r in zip(meshes, rs))
    sp0 = before.get("speed_one_core", {})
    if speed and "error" not in speed:
        tris = speed["triangles"]
        for key, target in (("compress_12", 1.0), ("compress_16", 0.7), ("decompress_12", 1.5),
                            ("decompress_16", 1.5)):
            u = statistics.median(speed[key])
            v = tris / u / 1e6
            old = sp0.get(key, {}).get("mtri_per_s")
            L.append(f"| {key.replace('_', ' p')} one core, M triangles/s (user time) | ≥ {target} | {_f(old, 3)} | "
                     f"{_f(v, 3)} | {_mark(v >= target)} |")
        L.append("")
        L.append(f"Speed mesh: `{speed['mesh']}` ({tris} triangles), `RAYON_NUM_THREADS=1 /usr/bin/time -f %U`, "
                 f"median of {len(speed['compress_12'])}: user seconds " + ", ".join(
                     f"{k} {statistics.median(speed[k]):.2f}" for k in
                     ("compress_12", "compress_16", "decompress_12", "decompress_16")) + ".")
    elif speed:
        L.append(f"| speed | | | error: {speed['error'][-200:]} | missed |")
    L.append("")
    L.append("Size ratios: tessd's file for the mesh without its unreferenced vertices (Draco drops them; "
             "only where the mesh has some: the bunnies' 1 113) over Draco-10's file on the same quantised "
             "mesh; the *before* column divides the v1 file (with them) by the same Draco file. Geometry and "
             "connectivity of GD02 from paper 003 (~14 + 3.5 b/v on the bunny). Per mesh, now: "
             + per_mesh + ".\n")
    errs = [r for r in rows if r.get("record") == "goal" and "error" in r]
    for r in errs:
        L.append(f"* goal run {r.get('mesh', r.get('kind'))}: error `{r['error'][-300:]}`")
    # the budget table
    L.append("### Bit budget of the bunny (bun_zipper, p = 12), bits/vertex over 35 947 vertices\n")
    cols = [("before, default", b0), ("before, one cell", b1), ("now, default", bun), ("now, one cell", bun1)]
    budgets = [(name, _budget(js) if js else None) for name, js in cols]
    names = ["geometry (split codes)", "triangles holding the split vertex once", "held twice",
             "held three times", "isolated points", "tables", "header, index, padding", "file"]
    cells = " | ".join(f"{n} ({(js or {}).get('nsp_cells', '–')} cells)" for n, js in cols)
    L.append(f"| part | {cells} |")
    L.append("|---|" + "---:|" * len(cols))
    for n in names:
        vals = " | ".join(_f(b[n]) if b else "–" for _, b in budgets)
        L.append(f"| {'**file**' if n == 'file' else n} | {vals} |")
    L.append("")
    lay = [js.get("layout") for _, js in cols[2:] if js]
    if lay and lay[0]:
        L.append(f"Now: head {lay[0][0]} B, trailer (counts + index + 4-byte tail) {lay[0][1]} B, tables "
                 f"{lay[0][2]} B (default); before: header 128 B, index "
                 f"{(b0 or {}).get('index_bytes', '–')} B, tables {(b0 or {}).get('tables_bytes', '–')} B.\n")
    return L
