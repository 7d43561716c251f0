"""The Blender add-on's shading and data figures of issue 19, before and after: for a given
revision of the add-on and for the working tree, build its extension zip, install it into a
throw-away Blender profile (real `bpy` from .venv, as the tests do), run it against one real
daemon (target/release/tessd or $TESSD_BIN) and count:

- corners whose normal is more than 90° from their face (black specks) on the smooth-shaded
  Stanford bunny's LOD chain 20 %/5 %/1 % (complexity goal, quadric representatives), on a
  flat-shaded Suzanne simplified to 2 %, on a flat cube subdivided twice; smooth faces there;
- what LOD0..LOD2 of a Suzanne with a second UV map, a colour attribute, a generic attribute,
  a vertex group and a shape key still have;
- a 1 986-vertex sphere and an 8-vertex cube simplified together to 500 vertices.

    .venv/bin/python bench/blender_addon_quality.py [--before e38c85f]
                                                    [--out bench/results/blender_addon_quality.md]
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BUNNY = Path(os.environ.get("TESSD_SHARED_DATA", REPO.parent / "shared" / "data")) / "mesh" / "bun_zipper.ply"


def run_scenario(zip_path, sock):
    """Runs this file in a fresh Python with bpy for one zip; returns its figures."""
    user = tempfile.mkdtemp(prefix="tessd-bench-")
    env = dict(os.environ, BLENDER_USER_RESOURCES=user)
    try:
        proc = subprocess.run([sys.executable, __file__, "--scenario", str(zip_path), sock],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env)
    finally:
        shutil.rmtree(user, ignore_errors=True)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    if not lines:
        raise SystemExit("the scenario failed for %s:\n%s" % (zip_path, proc.stdout[-3000:]))
    out = json.loads(lines[-1][7:])
    out["reports"] = [l for l in proc.stdout.splitlines() if l.startswith(("Warning:", "Error:"))]
    return out


def scenario(zip_path, sock):
    sys.path[:0] = [str(REPO / "tests" / "blender_addon")]
    import bpy
    import numpy as np
    from addon_env import install_addon

    repo = os.path.join(os.environ["BLENDER_USER_RESOURCES"], "repo")
    os.makedirs(repo, exist_ok=True)
    install_addon(zip_path, repo, sock)

    def clear():
        for c in (bpy.data.objects, bpy.data.meshes, bpy.data.collections):
            for b in list(c):
                c.remove(b)

    def select(*objs):
        for o in bpy.context.view_layer.objects:
            o.select_set(False)
        for o in objs:
            o.select_set(True)
        bpy.context.view_layer.objects.active = objs[0]

    def angles(mesh):
        sizes = np.empty(len(mesh.polygons), np.int32); mesh.polygons.foreach_get("loop_total", sizes)
        faces = np.repeat(np.arange(len(sizes)), sizes)
        fn = np.empty(len(mesh.polygons) * 3, np.float32); mesh.polygons.foreach_get("normal", fn)
        cn = np.empty(len(mesh.loops) * 3, np.float32); mesh.corner_normals.foreach_get("vector", cn)
        d = np.einsum("ij,ij->i", cn.reshape(-1, 3), fn.reshape(-1, 3)[faces]).clip(-1, 1)
        ang = np.degrees(np.arccos(d))
        bad = ang > 90
        return dict(faces=len(sizes), bad_corners=int(bad.sum()), bad_faces=int(len(np.unique(faces[bad]))),
                    max_angle=round(float(ang.max()), 1),
                    smooth_faces=int(sum(p.use_smooth for p in mesh.polygons)))

    out = {}
    clear()
    bpy.ops.wm.ply_import(filepath=str(BUNNY))
    bunny = bpy.context.object; bunny.name = "Bunny"; bunny.data.shade_smooth()
    select(bunny)
    bpy.ops.tessd.generate_lods(levels="20%,5%,1%", method='COMPLEXITY', representative='QUADRIC')
    out["bunny_lods"] = {i: angles(bpy.data.objects["Bunny_LOD%d" % i].data) for i in (1, 2, 3)}

    clear()
    bpy.ops.mesh.primitive_monkey_add(); s = bpy.context.object; s.name = "Suzanne"
    select(s)
    bpy.ops.tessd.simplify(method='COMPLEXITY', target=2, target_is_percent=True)
    out["flat_suzanne_2pct"] = angles(bpy.data.objects["Suzanne_simplified"].data)

    clear()
    bpy.ops.mesh.primitive_cube_add(); c = bpy.context.object; c.name = "Cube"
    select(c)
    bpy.ops.tessd.subdivide(levels=2)
    out["flat_cube_subdiv"] = angles(bpy.data.objects["Cube_subdiv"].data)

    clear()
    bpy.ops.mesh.primitive_monkey_add(); s = bpy.context.object; s.name = "Rich"
    m = s.data
    m.uv_layers.new(name="Lightmap")
    col = m.color_attributes.new("Paint", 'BYTE_COLOR', 'CORNER')
    m.attributes.new("mask", 'FLOAT', 'POINT')
    g = s.vertex_groups.new(name="Bone"); g.add(list(range(len(m.vertices))), 1.0, 'REPLACE')
    s.shape_key_add(name="Basis"); s.shape_key_add(name="Smile")
    select(s)
    bpy.ops.tessd.generate_lods(levels="50%,20%", use_modifiers=False)
    def content(o):
        me = o.data
        return dict(uv_maps=[u.name for u in me.uv_layers], colors=[a.name for a in me.color_attributes],
                    mask="mask" in me.attributes, groups=[g.name for g in o.vertex_groups],
                    keys=(list(me.shape_keys.key_blocks.keys()) if me.shape_keys else []))
    out["attributes"] = {i: content(bpy.data.objects["Rich_LOD%d" % i]) for i in (0, 1, 2)}

    clear()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32); sp = bpy.context.object; sp.name = "Sphere"
    bpy.ops.mesh.primitive_cube_add(location=(3, 0, 0)); cu = bpy.context.object; cu.name = "Cube"
    select(sp, cu)
    try:
        r = bpy.ops.tessd.simplify(method='COMPLEXITY', target=500, target_is_percent=False)
    except RuntimeError as e:
        r = str(e)[:160]
    out["batch"] = dict(result=str(r), objects=sorted(o.name for o in bpy.data.objects),
                        sphere_vertices=len(sp.data.vertices))
    # What carrying everything costs: the same simplify of an ico sphere (subdivisions 9,
    # 655 362 vertices) bare, then with two UV maps, a colour, a generic attribute, four
    # vertex groups and two shape keys (the old add-on sends and gets back the bare part).
    import time
    clear()
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=9)
    ico = bpy.context.object
    ico.name = "Ico"
    select(ico)
    t0 = time.perf_counter()
    bpy.ops.tessd.simplify(method='COMPLEXITY', target=10, target_is_percent=True, use_modifiers=False)
    bare = time.perf_counter() - t0
    me = ico.data
    me.uv_layers.new(name="UVMap")
    me.uv_layers.new(name="Lightmap")
    me.color_attributes.new("Paint", 'BYTE_COLOR', 'CORNER')
    me.attributes.new("mask", 'FLOAT', 'POINT')
    co = np.empty(len(me.vertices) * 3, np.float32)
    me.vertices.foreach_get("co", co)
    x = co[0::3]
    for g in range(4):
        idx = np.flatnonzero((x > -1 + 0.5 * g) & (x <= -0.5 + 0.5 * g + 0.25))
        ico.vertex_groups.new(name="Bone%d" % g).add(idx.tolist(), 1.0, 'REPLACE')
    for k in ("Basis", "A", "B"):
        ico.shape_key_add(name=k)
    select(ico)
    t0 = time.perf_counter()
    bpy.ops.tessd.simplify(method='COMPLEXITY', target=10, target_is_percent=True, use_modifiers=False)
    rich = time.perf_counter() - t0
    out["cost"] = dict(vertices=len(me.vertices), bare_s=round(bare, 3), rich_s=round(rich, 3))
    print("RESULT " + json.dumps(out))


def build_zip(tree, out, binary):
    """The extension zip of the add-on in `tree`, bundling the daemon `binary` (an archived
    revision has no target folder of its own)."""
    script = tree / "blender_addon" / "build.py"
    # Revisions before the daemon was bundled have no --binary.
    extra = ["--binary", binary] if "--binary" in script.read_text() else []
    subprocess.run([sys.executable, str(script), "--out", str(out), "--no-validate"] + extra,
                   check=True, stdout=subprocess.DEVNULL)
    return next(Path(out).glob("tessd-*.zip"))


def table(before, after, rev):
    rows = ["| figure | before (%s) | after (working tree) |" % rev, "|---|---|---|"]
    for i in ("1", "2", "3"):
        b, a = before["bunny_lods"][i], after["bunny_lods"][i]
        rows.append("| bunny LOD%s (%d faces): corners > 90° / faces with one / largest angle / smooth faces | %d / %d / %.1f° / %d | %d / %d / %.1f° / %d |"
                    % (i, a["faces"], b["bad_corners"], b["bad_faces"], b["max_angle"], b["smooth_faces"],
                       a["bad_corners"], a["bad_faces"], a["max_angle"], a["smooth_faces"]))
    for key, name in (("flat_suzanne_2pct", "flat Suzanne at 2 %"), ("flat_cube_subdiv", "flat cube subdivided ×2")):
        b, a = before[key], after[key]
        rows.append("| %s (%d faces): corners > 90° / largest angle / smooth faces | %d / %.1f° / %d | %d / %.1f° / %d |"
                    % (name, a["faces"], b["bad_corners"], b["max_angle"], b["smooth_faces"],
                       a["bad_corners"], a["max_angle"], a["smooth_faces"]))
    for lvl in ("0", "1", "2"):
        fmt = lambda c: "UV %s; colours %s; mask %s; groups %s; keys %s" % (
            "+".join(c["uv_maps"]) or "-", "+".join(c["colors"]) or "-", "yes" if c["mask"] else "no",
            "+".join(c["groups"]) or "-", "+".join(c["keys"]) or "-")
        rows.append("| Suzanne LOD%s carries | %s | %s |" % (lvl, fmt(before["attributes"][lvl]), fmt(after["attributes"][lvl])))
    fmt = lambda r: "%s; objects after: %s" % (r["result"][:90].replace("|", "/"), ", ".join(r["objects"]))
    rows.append("| sphere + cube to 500 vertices | %s | %s |" % (fmt(before["batch"]), fmt(after["batch"])))
    cb, ca = before["cost"], after["cost"]
    full = after["attributes"]["1"]

    def carried(res):
        return "all carried" if res["attributes"]["1"] == full else "all but the active UV map dropped"

    rows.append("| seconds to simplify a %d-vertex ico sphere to 10 %%: bare / with 2 UV maps, a colour, "
                "a generic attribute, 4 vertex groups, 2 shape keys | %.2f / %.2f (%s) | %.2f / %.2f (%s) |"
                % (ca["vertices"], cb["bare_s"], cb["rich_s"], carried(before), ca["bare_s"],
                   ca["rich_s"], carried(after)))
    return "\n".join(rows)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--scenario":
        return scenario(sys.argv[2], sys.argv[3])
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", default="e38c85f", help="revision of the add-on to compare")
    ap.add_argument("--out", default=str(REPO / "bench" / "results" / "blender_addon_quality.md"))
    args = ap.parse_args()
    binary = os.environ.get("TESSD_BIN", str(REPO / "target" / "release" / "tessd"))
    with tempfile.TemporaryDirectory(prefix="tessd-q-") as tmp:
        tmp = Path(tmp)
        old = tmp / "old"
        old.mkdir()
        archive = subprocess.run(["git", "archive", args.before, "blender_addon", "python/tessd"],
                                 cwd=REPO, stdout=subprocess.PIPE, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
        zips = {"before": build_zip(old, tmp / "dist_old", binary),
                "after": build_zip(REPO, tmp / "dist_new", binary)}
        sock = str(tmp / "d.sock")
        daemon = subprocess.Popen([binary, "serve", "--socket", sock], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        try:
            for _ in range(100):
                if os.path.exists(sock):
                    break
                __import__("time").sleep(0.05)
            res = {k: run_scenario(z, sock) for k, z in zips.items()}
        finally:
            daemon.terminate()
            daemon.wait()
    text = ("# The Blender add-on: shading and data, before and after (issue 19)\n\n"
            "`.venv/bin/python bench/blender_addon_quality.py --before %s` (bpy %s, one daemon, "
            "`%s`, for both).\n\n%s\n\nReports of the "
            "batch and LOD runs:\n\n- before: %s\n- after: %s\n"
            % (args.before, "5.0.1", os.path.relpath(binary, REPO) if binary.startswith(str(REPO)) else binary,
               table(res["before"], res["after"], args.before),
               " / ".join(res["before"]["reports"]) or "-", " / ".join(res["after"]["reports"]) or "-"))
    Path(args.out).write_text(text, encoding="utf-8")
    print(text)


if __name__ == "__main__":
    main()
