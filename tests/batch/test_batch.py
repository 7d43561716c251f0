"""tessd.batch end to end: a real Dask LocalCluster (2 worker processes), the real daemon (one
per node, shared by the workers), the shared meshes and CAD parts, usd-core on the results.

1. every shared mesh's LOD chain and every shared part tessellated (thumbnails and a turntable
   for a few) → all ok, the library and each asset re-open in usd-core with their references
   resolved and LOD triangle counts decreasing;
2. the same batch again → every step ``skipped``, no file rewritten;
3. a worker SIGKILLed mid-batch (while it renders a long turntable) → the task is resubmitted,
   the batch completes all ok, no temporary or partial file is left;
4. bad inputs (a truncated PLY, a garbage STEP, a missing file) through the CLI → errors with
   clear messages in the summary, exit status 1, the rest done, nothing retried.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from batch_util import REPO, files_with_mtimes, png_size, usd_check

from tessd.batch import layout, manifest, summary
from tessd.batch.cluster import daemon_info
from tessd.batch.runner import run

MESHES = ["bun_zipper.ply", "double_torus.off", "draco_non_manifold_wrap.obj", "draco_test_nm.obj",
          "fandisk.obj", "mpi_polygons.off", "quadknot.obj", "spot_control_mesh.obj",
          "spot_quadrangulated.obj", "spot_triangulated.obj", "stanford_bunny.obj", "suzanne.obj"]
PARTS = ["CrankArm.brep", "M6-1x12-countersunk-screw.step", "Pump_Nut.brep", "bottle.brep",
         "face2.brep", "featuretype.step", "freecad_drilling1_body.brep", "hammer.iges",
         "red_cube_blue_cylinder.step", "screw.step", "shell1.brep"]
THUMBS = {"bun_zipper.ply", "suzanne.obj", "spot_quadrangulated.obj", "screw.step", "bottle.brep"}


def _name(filename: str) -> str:
    return manifest.identifier(os.path.splitext(filename)[0])


@pytest.fixture(scope="module")
def library(tmp_path_factory, shared_data, dask_client):
    """Test 1's batch, run once for the module: (manifest path, outdir, result)."""
    rows = []
    for f in MESHES:
        ops = ["lod=50%,20%,5%"]
        if f in THUMBS:
            ops.append("thumbnail=256x256")
        if f == "suzanne.obj":
            ops.append({"op": "turntable", "frames": 4, "size": "128x128"})
        rows.append({"input": str(shared_data / "mesh" / f), "operations": ops})
    for f in PARTS:
        ops = ["tessellate=0.1%"]
        if f in THUMBS:
            ops.append("thumbnail=256x256")
        if f == "screw.step":
            ops.append("lod=50%,20%")
        rows.append({"input": str(shared_data / "brep" / f), "operations": ops})
    rows[1]["host"] = rows[-1]["host"] = "127.0.0.1"  # locality: the (local) workers' host
    base = tmp_path_factory.mktemp("batch1")
    m = base / "manifest.json"
    m.write_text(json.dumps(rows, indent=1))
    out = base / "out"
    result = run(str(m), str(out), client=dask_client, show_progress=False)
    return m, out, result


def _errors(rows):
    return ["%s %s: %s" % (r["asset"], r["step"], r["error"]) for r in rows if r["status"] == "error"]


# ---------------------------------------------------------------------------------------------
# 1. the library


def test_library_of_the_shared_data(library, dask_client):
    m, out, result = library
    assert _errors(result.rows) == []
    names = {_name(f) for f in MESHES + PARTS}
    assert {r["asset"] for r in result.rows} == names
    assert {r["status"] for r in result.rows} == {"ok"}
    assert result.totals["assets_ok"] == len(names)
    for r in result.rows:
        assert r["worker"] and r["pid"], r
        assert r["worker_losses"] == 0, r
    # both workers did some of it, on one daemon (scope "node": shared by the node's workers)
    assert len({r["worker"] for r in result.rows}) == 2
    infos = dask_client.run(daemon_info)
    assert len({i["socket"] for i in infos.values()}) == 1, infos
    assert len({i["pid"] for i in infos.values()}) == 1, infos
    assert all(i["holders"] == 2 for i in infos.values()), infos

    # the files
    assert (out / "library.usda").is_file()
    assert (out / "summary.csv").is_file() and (out / "summary.json").is_file()
    assert layout.find_temps(str(out)) == []
    for n in names:
        d = out / "assets" / n
        assert (d / (n + ".usda")).is_file(), n
    for f in MESHES:
        assert (out / "assets" / _name(f) / (_name(f) + "_lod.usda")).is_file()
    for f in PARTS:
        assert (out / "assets" / _name(f) / (_name(f) + "_tess.usda")).is_file()
    for f in ("M6-1x12-countersunk-screw.step", "featuretype.step", "hammer.iges",
              "red_cube_blue_cylinder.step", "screw.step"):
        assert (out / "assets" / _name(f) / (_name(f) + "_brep.json")).is_file(), f
    for f in THUMBS:
        assert png_size(out / "assets" / _name(f) / (_name(f) + "_thumb.png")) == (256, 256)
    frames = sorted((out / "assets" / "suzanne" / "turntable").iterdir())
    assert [p.name for p in frames] == ["suzanne_%03d.png" % i for i in range(4)]
    assert all(png_size(p) == (128, 128) for p in frames)

    # the summary files agree with the result
    doc = summary.read(str(out))
    assert doc["totals"]["steps"] == {"ok": len(result.rows), "error": 0, "skipped": 0}
    assert doc["assets_in_library"] == len(names)
    csv_lines = (out / "summary.csv").read_text().splitlines()
    assert csv_lines[0].split(",") == list(summary.COLUMNS)
    assert len(csv_lines) == 1 + len(result.rows)
    by_step = {(r["asset"], r["step"]): r for r in doc["rows"]}
    assert by_step[("hammer", "export")]["faces_out"] > 0
    assert by_step[("hammer", "tessellate")]["faces_out"] > 0
    assert by_step[("bun_zipper", "lod")]["faces_out"][0] == 69451


def test_library_reopens_in_usd_core(library):
    m, out, result = library
    check = usd_check(out)
    lib = check["library"]
    names = {_name(f) for f in MESHES + PARTS}
    assert lib["opened"] and lib["default_prim"] == "Library" and lib["kind"] == "assembly"
    assert lib["composition_errors"] == [] and lib["validation"] == []
    assert set(lib["children"]) == names
    for n, child in lib["children"].items():
        # the reference resolved: the asset's mesh is reachable from the library
        assert child["has_reference"] and child["kind"] == "component", (n, child)
        assert child["meshes"] >= 1 and child["faces"] > 0, (n, child)
    for f in PARTS:  # CAD parts are in mm: scaled into the library's metres
        assert lib["children"][_name(f)]["scale"] == pytest.approx(0.001), f
    for f in MESHES:
        assert lib["children"][_name(f)]["scale"] == pytest.approx(1.0), f

    lods = {(r["asset"]): r for r in result.rows if r["step"] == "lod"}
    for n in names:
        a = check["assets"][n]
        assert a["opened"] and a["default_prim"] == n and a["kind"] == "component", a
        assert a["asset_name"] == n and a["asset_identifier"] == "./%s.usda" % n
        assert a["composition_errors"] == [] and a["validation"] == [], (n, a["validation"])
        if n in lods:
            levels = a["lod"]
            assert [lv["variant"] for lv in levels] == ["LOD%d" % i for i in range(len(levels))]
            tris = [lv["triangles"] for lv in levels]
            points = [lv["points"] for lv in levels]
            assert all(lv["meshes"] == 1 for lv in levels), (n, levels)
            # each level no finer than the one before, the coarsest well below LOD0
            assert all(b <= a_ for a_, b in zip(tris, tris[1:])), (n, tris)
            assert tris[-1] < tris[0], (n, tris)
            assert all(b <= a_ for a_, b in zip(points, points[1:])), (n, points)
            # what the summary says is what the file holds (LOD0: after the triangulation)
            assert lods[n]["faces_out"] == tris, (n, lods[n]["faces_out"], tris)
        else:
            assert a["mesh"]["meshes"] == 1 and a["mesh"]["faces"] > 0, (n, a)
            assert a["meters_per_unit"] == pytest.approx(0.001)
    assert len(check["assets"]["screw"]["lod"]) == 3  # a CAD part's LOD chain, of its tessellation
    for f in THUMBS:
        assert check["assets"][_name(f)]["thumbnail_exists"], f
    assert check["assets"]["suzanne"]["turntable_exist"]
    assert len(check["assets"]["suzanne"]["turntable"]) == 4


# ---------------------------------------------------------------------------------------------
# 2. a re-run


def test_rerun_skips_everything_and_rewrites_nothing(library, dask_client):
    m, out, first = library
    before = files_with_mtimes(out)
    time.sleep(0.05)  # a rewrite would show as a later mtime
    # (in chunks of 5 assets per task this time: what is complete is complete however grouped)
    result = run(str(m), str(out), client=dask_client, show_progress=False, chunk=5)
    assert _errors(result.rows) == []
    assert {r["status"] for r in result.rows} == {"skipped"}
    assert len(result.rows) == len(first.rows)
    assert files_with_mtimes(out) == before
    # the skipped rows still carry the counts of the run that made the files
    old = {(r["asset"], r["step"]): r for r in first.rows}
    for r in result.rows:
        assert r["faces_out"] == old[(r["asset"], r["step"])]["faces_out"], r
        assert r["files"] == old[(r["asset"], r["step"])]["files"], r
    assert summary.read(str(out))["totals"]["steps"]["skipped"] == len(result.rows)


# ---------------------------------------------------------------------------------------------
# 3. a worker killed mid-batch


def test_worker_killed_mid_batch(tmp_path, shared_data, dask_client):
    rows = [{"input": str(shared_data / "mesh" / f), "operations": "lod=50%,20%,5%"}
            for f in MESHES if f != "bun_zipper.ply"]
    # the long task the worker is killed in: 60 turntable frames of the bunny (a few seconds)
    rows.insert(0, {"input": str(shared_data / "mesh" / "bun_zipper.ply"),
                    "operations": "lod=50%,20%,5%; turntable=60; thumbnail"})
    m = tmp_path / "manifest.json"
    m.write_text(json.dumps(rows))
    out = tmp_path / "out"
    before = dask_client.run(os.getpid)
    killed = {}

    def killer():
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not killed:
            for addr, keys in dask_client.processing().items():
                if any(str(k).endswith("-bun_zipper") for k in keys):
                    time.sleep(1.0)  # well into the turntable: frames are being written
                    if not any(str(k).endswith("-bun_zipper")
                               for k in dask_client.processing().get(addr, ())):
                        break  # it finished first (should not happen): look again
                    pid = dask_client.run(os.getpid, workers=[addr])[addr]
                    os.kill(pid, signal.SIGKILL)
                    killed.update(addr=addr, pid=pid)
                    return
            time.sleep(0.05)

    t = threading.Thread(target=killer, daemon=True)
    t.start()
    result = run(str(m), str(out), client=dask_client, show_progress=False)
    t.join(5)
    assert killed, "the long task was never seen running"
    assert _errors(result.rows) == []
    assert {r["status"] for r in result.rows} == {"ok"}
    bunny = [r for r in result.rows if r["asset"] == "bun_zipper"]
    assert all(r["worker_losses"] >= 1 for r in bunny), bunny
    turntable = next(r for r in bunny if r["step"] == "turntable")
    assert turntable["pid"] != killed["pid"]  # finished by another (or the restarted) worker

    # no temporary file, no partial file under a final name, every record complete
    assert layout.find_temps(str(out)) == []
    frames = sorted((out / "assets" / "bun_zipper" / "turntable").iterdir())
    assert len(frames) == 60
    assert all(png_size(p) == (256, 256) for p in frames)
    for r in result.rows:
        rec = layout.load_record(layout.record_path(str(out), r["asset"], r["step"]))
        assert rec is not None and rec["run_id"] == result.run_id
        for rel, size in rec["files"].items():
            assert os.path.getsize(out / "assets" / r["asset"] / rel) == size
    check = usd_check(out)
    assert set(check["library"]["children"]) == {_name(f) for f in MESHES}
    assert check["assets"]["bun_zipper"]["validation"] == []

    # the nanny restarted the killed worker, which joined the node's daemon again
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        after = dask_client.run(os.getpid)
        if len(after) == 2:
            break
        time.sleep(0.2)
    assert len(after) == 2 and killed["pid"] not in after.values(), (before, after)
    infos = dask_client.run(daemon_info)
    assert len({i["pid"] for i in infos.values()}) == 1 and all(
        i["holders"] == 2 for i in infos.values()), infos


# ---------------------------------------------------------------------------------------------
# 4. bad inputs, through the CLI


def test_bad_inputs_are_reported_not_retried(tmp_path, shared_data):
    data = tmp_path / "in"
    data.mkdir()
    (data / "truncated.ply").write_bytes((shared_data / "mesh" / "bun_zipper.ply").read_bytes()[:1_000_000])
    (data / "garbage.step").write_bytes(b"ISO-10303-21;\nHEADER;\nthis is not a STEP file\n")
    (data / "suzanne.obj").write_bytes((shared_data / "mesh" / "suzanne.obj").read_bytes())
    m = tmp_path / "manifest.csv"
    m.write_text("input,operations\n"
                 'in/truncated.ply,"lod=50%,20%; thumbnail=64x64"\n'
                 "in/garbage.step,\n"
                 'in/suzanne.obj,"lod=50%,20%,5%"\n'
                 "in/missing.obj,lod\n")
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    proc = subprocess.run([sys.executable, "-m", "tessd.batch", str(m), str(out), "--workers", "1",
                           "--daemon-scope", "worker"], capture_output=True, text=True, env=env,
                          timeout=240)
    assert proc.returncode == 1, proc.stderr[-3000:]
    assert "4 assets (1 ok, 3 with errors)" in proc.stderr, proc.stderr[-3000:]
    assert "truncated lod: invalid_mesh" in proc.stderr
    doc = summary.read(str(out))
    rows = {(r["asset"], r["step"]): r for r in doc["rows"]}

    lod = rows[("truncated", "lod")]
    assert lod["status"] == "error"
    assert lod["error"].startswith("invalid_mesh: ") and "truncated.ply" in lod["error"]
    assert "file ends" in lod["error"], lod["error"]
    assert rows[("truncated", "thumbnail")]["status"] == "error"
    assert "invalid_mesh" in rows[("truncated", "thumbnail")]["error"]
    assert rows[("truncated", "asset")]["error"] == "not written: no geometry step succeeded"

    export = rows[("garbage", "export")]
    assert export["status"] == "error" and export["error"] == (
        "ExportError: %s: not readable as STEP" % (data / "garbage.step"))
    for step in ("tessellate", "thumbnail"):
        assert rows[("garbage", step)]["error"] == "not run: export failed"

    assert rows[("missing", "lod")]["error"].startswith("cannot read the input %s" % (data / "missing.obj"))
    assert {r["status"] for r in doc["rows"] if r["asset"] == "suzanne"} == {"ok"}
    # nothing was retried: an error is a result, not a failed task
    assert all(r["worker_losses"] == 0 for r in doc["rows"])
    assert doc["totals"]["assets_ok"] == 1 and doc["assets_in_library"] == 1

    # no file of the bad inputs under a final name, the good one complete
    assert sorted(p.name for p in (out / "assets" / "truncated").iterdir()) == [".batch"]
    assert list((out / "assets" / "truncated" / ".batch").iterdir()) == []
    assert (out / "assets" / "suzanne" / "suzanne_lod.usda").is_file()
    assert layout.find_temps(str(out)) == []
    check = usd_check(out)
    assert set(check["library"]["children"]) == {"suzanne"}
    assert [lv["triangles"] for lv in check["assets"]["suzanne"]["lod"]][-1] < 968


# ---------------------------------------------------------------------------------------------
# The parts that need no cluster


def test_manifest_forms(tmp_path):
    (tmp_path / "a").mkdir()
    for f in ("a/bunny.obj", "a/bunny.ply", "a/part.STEP", "a/notes.txt", "a/.hidden.obj"):
        (tmp_path / f).write_text("x")
    assets = manifest.load(str(tmp_path / "a"))
    assert [(a.name, a.kind) for a in assets] == [("bunny", "mesh"), ("bunny_ply", "mesh"),
                                                   ("part", "cad")]
    assert [op.name for op in assets[0].ops] == ["lod", "thumbnail", "asset"]
    assert assets[0].ops[0].params["levels"] == ["50%", "20%", "5%"]
    assert [op.name for op in assets[2].ops] == ["export", "tessellate", "thumbnail", "asset"]
    assert assets[2].ops[1].params["tolerance"] == "0.1%"

    csv_path = tmp_path / "m.csv"
    csv_path.write_text('# comment\ninput,operations,name,host\na/bunny.obj,"lod=40%,10%; turntable=8",'
                        "Bun-1,node7\na/part.STEP,lod,,\na/bunny.ply,thumbnail,,\n")
    a, b, c = manifest.load(str(csv_path))
    assert a.name == "Bun_1" and a.ops[0].params["levels"] == ["40%", "10%"]
    assert (a.host, b.host) == ("node7", None)
    assert a.ops[1].params["frames"] == 8
    # lod of a part: its tessellation's, tessellate added; a mesh with no geometry op: convert
    assert [(op.name, op.implied) for op in b.ops] == [
        ("export", True), ("tessellate", True), ("lod", False), ("asset", True)]
    assert [op.name for op in c.ops] == ["convert", "thumbnail", "asset"]

    json_path = tmp_path / "m.json"
    json_path.write_text(json.dumps({"assets": [
        {"input": "a/bunny.obj", "operations": [{"op": "lod", "levels": [1000, 100],
                                                  "method": "complexity"}]}]}))
    (only,) = manifest.load(str(json_path))
    assert only.ops[0].params["levels"] == [1000, 100]

    for bad, message in (('"sharpen"', "unknown operation 'sharpen'"),
                         ('"convert=3"', "takes no argument"),
                         ('[{"op": "lod", "level": 3}]', "has no parameter 'level'"),
                         ('"turntable=many"', "frames must be an integer")):
        json_path.write_text('[{"input": "a/bunny.obj", "operations": %s}]' % bad)
        with pytest.raises(manifest.ManifestError, match=message):
            manifest.load(str(json_path))


def test_atomic_write_and_sweep(tmp_path):
    p = tmp_path / "x.usda"
    layout.atomic_write(str(p), b"one")
    assert p.read_bytes() == b"one" and layout.find_temps(str(tmp_path)) == []
    assert layout.write_if_changed(str(p), b"one") is False
    assert layout.write_if_changed(str(p), b"two") is True and p.read_bytes() == b"two"
    # what a writer killed mid-write leaves: a temporary file (ours, or the daemon's pattern)
    left = [tmp_path / ".x.usda.tmp-123-ab12cd34", tmp_path / ".y.png.tmp-77-3"]
    for f in left:
        f.write_bytes(b"partial")
    assert sorted(layout.sweep_temps(str(tmp_path))) == sorted(map(str, left))
    assert sorted(os.listdir(tmp_path)) == ["x.usda"]


def test_import_tessd_does_not_import_dask():
    code = ("import sys, tessd, tessd.batch.manifest, tessd.batch.layout, tessd.batch.summary; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')]; "
            "assert not bad, bad; import tessd.batch; "
            "assert 'distributed' not in sys.modules")
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    subprocess.run([sys.executable, "-c", code], check=True, env=env, timeout=60)
    proc = subprocess.run([sys.executable, "-c", "import tessd, sys; print('tessd.batch' in sys.modules)"],
                          capture_output=True, text=True, env=env, timeout=60, check=True)
    assert proc.stdout.strip() == "False"
