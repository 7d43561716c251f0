"""Every verb and op that writes a `.usda` stage, re-opened with usd-core: its `metersPerUnit`
and `upAxis` (issue 32, point 1). A B-Rep's units decide `metersPerUnit` (mm -> 0.001,
in -> 0.0254, ...) unless `--meters-per-unit` / `meters_per_unit` says otherwise; every mesh
verb takes `--up-axis` and `--meters-per-unit`, every op `up_axis` and `meters_per_unit`."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from pxr import Usd, UsdGeom

import locate
import tessd
from tessd import TessdError
from usd_checks import validate_stage

REPO = Path(__file__).resolve().parents[2]
DATA = locate.shared_data()
CRANK = DATA / "brep" / "CrankArm.brep"
SPOT = DATA / "mesh" / "spot_triangulated.obj"
SPOT_CAGE = DATA / "mesh" / "spot_control_mesh.obj"
#: A tessd-brep JSON document in millimetres (the demo's bottle).
BOTTLE_JSON = REPO / "core" / "tessellate" / "tests" / "data" / "bottle.json"


def run(*args, check: bool = True) -> subprocess.CompletedProcess:
    r = subprocess.run([str(locate.tessd_bin()), *map(str, args)], capture_output=True,
                       text=True, timeout=300)
    if check:
        assert r.returncode == 0, f"tessd {' '.join(map(str, args))}:\n{r.stderr}"
    return r


def run_json(*args) -> dict:
    return json.loads(run(*args, "--json").stdout)


def stage_units(path: Path) -> tuple[float, str]:
    """`metersPerUnit` and `upAxis` as usd-core reads them (the stage also validates)."""
    assert path.is_file(), path
    stage = Usd.Stage.Open(str(path))
    assert stage, path
    assert validate_stage(path) == [], path
    return UsdGeom.GetStageMetersPerUnit(stage), str(UsdGeom.GetStageUpAxis(stage))


def assert_units(path: Path, meters_per_unit: float, up: str) -> None:
    m, axis = stage_units(path)
    assert m == pytest.approx(meters_per_unit, rel=1e-12), (path, m)
    assert axis == up, (path, axis)


# --- tessellate: the B-Rep's units -----------------------------------------------------------

@pytest.mark.parametrize("units, expected", [("mm", 0.001), ("cm", 0.01), ("m", 1.0),
                                             ("in", 0.0254)])
def test_tessellate_brep_units_decide(tmp_path, units, expected):
    out = tmp_path / "crank.usda"
    r = run_json("tessellate", CRANK, out, "--tolerance", "0.1mm", "--units", units)
    assert r["units"] == units and r["meters_per_unit"] == expected and r["up_axis"] == "Z"
    assert_units(out, expected, "Z")


def test_tessellate_brep_default_is_mm(tmp_path):
    # A .brep names no unit: the daemon reads it as mm (the default of --units).
    out = tmp_path / "crank.usda"
    run("tessellate", CRANK, out, "--tolerance", "0.1mm")
    assert_units(out, 0.001, "Z")


def test_tessellate_json_document_units(tmp_path):
    out = tmp_path / "bottle.usda"
    run("tessellate", BOTTLE_JSON, out, "--tolerance", "0.1mm")
    assert_units(out, 0.001, "Z")
    # The same document in inches: the document's own `units` decide.
    doc = json.loads(BOTTLE_JSON.read_text())
    assert doc["units"] == "mm"
    doc["units"] = "in"
    inches = tmp_path / "bottle_in.json"
    inches.write_text(json.dumps(doc))
    run("tessellate", inches, out, "--tolerance", "0.01in")
    assert_units(out, 0.0254, "Z")


def test_tessellate_override(tmp_path):
    out = tmp_path / "crank.usda"
    r = run_json("tessellate", CRANK, out, "--tolerance", "0.1mm", "--units", "mm",
                 "--meters-per-unit", "1", "--up-axis", "Y")
    assert r["meters_per_unit"] == 1.0 and r["up_axis"] == "Y"
    assert_units(out, 1.0, "Y")
    # The override does not change the mesh's coordinates, only the stage's metadata: the
    # points are the same numbers as without it.
    plain = tmp_path / "plain.usda"
    run("tessellate", CRANK, plain, "--tolerance", "0.1mm", "--units", "mm")
    points = []
    for f in (out, plain):
        stage = Usd.Stage.Open(str(f))
        points += [list(UsdGeom.Mesh(p).GetPointsAttr().Get()) for p in stage.Traverse()
                   if p.IsA(UsdGeom.Mesh)]
    assert len(points) == 2 and len(points[0]) > 1000 and points[0] == points[1]


def test_tessellate_other_formats_ignore_stage_options(tmp_path):
    # No stage, nothing to set: an OBJ is written as before.
    out = tmp_path / "crank.obj"
    r = run_json("tessellate", CRANK, out, "--tolerance", "0.1mm", "--meters-per-unit", "0.5")
    assert "meters_per_unit" not in r and out.is_file()


# --- every mesh verb -------------------------------------------------------------------------

STAGE_FLAGS = ("--up-axis", "Y", "--meters-per-unit", "0.01")


def test_convert(tmp_path):
    out = tmp_path / "spot.usda"
    run("convert", SPOT, out)
    assert_units(out, 1.0, "Z")  # a mesh file names no unit
    run("convert", SPOT, out, *STAGE_FLAGS)
    assert_units(out, 0.01, "Y")


def test_simplify(tmp_path):
    out, boxes = tmp_path / "s.usda", tmp_path / "cells.usda"
    run("simplify", SPOT, out, "--method", "complexity", "--target-vertices", "20%",
        "--partition", boxes, *STAGE_FLAGS)
    assert_units(out, 0.01, "Y")
    assert_units(boxes, 0.01, "Y")


def test_subdivide(tmp_path):
    out, cage = tmp_path / "smooth.usda", tmp_path / "cage.usda"
    run("subdivide", SPOT_CAGE, out, *STAGE_FLAGS)
    assert_units(out, 0.01, "Y")
    run("subdivide", SPOT_CAGE, cage, "--usd-cage", "--up-axis", "Z", "--meters-per-unit",
        "0.001")
    assert_units(cage, 0.001, "Z")


def test_lod(tmp_path):
    out, levels = tmp_path / "lods.usda", tmp_path / "levels"
    run("lod", SPOT, "--levels", "50%,20%", "--out", out, "--per-level-dir", levels,
        "--per-level-format", "usda", *STAGE_FLAGS)
    assert_units(out, 0.01, "Y")
    files = sorted(levels.iterdir())
    assert [f.name for f in files] == [f"lods_LOD{i}.usda" for i in range(3)]
    for f in files:
        assert_units(f, 0.01, "Y")
    run("lod", SPOT, "--levels", "50%", "--out", out, "--lod-schema", "usdlod")
    assert_units(out, 1.0, "Z")


def test_a_usda_input_keeps_its_conventions(tmp_path):
    """A stage in, a stage out: the input's own metersPerUnit and upAxis carry over to every
    mesh writer unless a flag says otherwise; a flag wins for its own option only."""
    src = tmp_path / "src.usda"
    run("convert", SPOT, src, "--up-axis", "Y", "--meters-per-unit", "0.001")
    assert_units(src, 0.001, "Y")
    out = tmp_path / "out.usda"
    run("convert", src, out)
    assert_units(out, 0.001, "Y")
    run("simplify", src, out, "--method", "complexity", "--target-vertices", "20%")
    assert_units(out, 0.001, "Y")
    run("lod", src, "--levels", "50%", "--out", out)
    assert_units(out, 0.001, "Y")
    run("convert", src, out, "--meters-per-unit", "0.01")
    assert_units(out, 0.01, "Y")
    run("convert", src, out, "--up-axis", "Z")
    assert_units(out, 0.001, "Z")


def test_mesh_units_decide_meters_per_unit(tmp_path):
    """`--units` says what a mesh's coordinates are in (for lengths such as `--max-error
    5mm`): the stage written says so too, unless --meters-per-unit overrides it."""
    out = tmp_path / "s.usda"
    run("simplify", SPOT, out, "--method", "quality", "--max-error", "1mm", "--units", "cm")
    assert_units(out, 0.01, "Z")
    run("simplify", SPOT, out, "--method", "quality", "--max-error", "1mm", "--units", "cm",
        "--meters-per-unit", "1")
    assert_units(out, 1.0, "Z")


def test_decompress_and_view_decode(tmp_path):
    tsc = tmp_path / "spot.tsc"
    run("compress", SPOT, tsc)
    out = tmp_path / "d.usda"
    run("decompress", tsc, out, *STAGE_FLAGS)
    assert_units(out, 0.01, "Y")
    view = tmp_path / "v.usda"
    run("view-decode", tsc, view, "--eye", "0,-3,0.5", "--target", "0,0,0", "--up", "0,0,1",
        "--up-axis", "Y", "--meters-per-unit", "0.0254")
    assert_units(view, 0.0254, "Y")


@pytest.mark.parametrize("verb", ["convert", "simplify", "subdivide", "lod", "tessellate",
                                  "decompress", "view-decode"])
def test_every_writer_has_the_flags(verb):
    text = run(verb, "--help").stdout
    assert "--up-axis <UP_AXIS>" in text and "--meters-per-unit <M>" in text, text


@pytest.mark.parametrize("bad", ["0", "-1", "abc", "inf", "NaN"])
def test_bad_meters_per_unit_is_refused_naming_the_flag(tmp_path, bad):
    out = tmp_path / "x.usda"
    r = run("convert", SPOT, out, f"--meters-per-unit={bad}", check=False)
    assert r.returncode == 2 and "--meters-per-unit" in r.stderr, r.stderr
    r = run("tessellate", CRANK, out, "--tolerance", "0.1mm", f"--meters-per-unit={bad}",
            check=False)
    assert r.returncode == 2 and "--meters-per-unit" in r.stderr, r.stderr
    r = run("convert", SPOT, out, "--up-axis", "X", check=False)
    assert r.returncode == 2 and "--up-axis" in r.stderr, r.stderr
    assert list(tmp_path.iterdir()) == []


# --- the ops, over the socket ----------------------------------------------------------------

STAGE = {"up_axis": "Y", "meters_per_unit": 0.01}


def test_ops_tessellate(daemon, tmp_path):
    doc = json.loads(BOTTLE_JSON.read_text())
    with tessd.Client(daemon.socket, timeout=120) as c:
        # The README's build123d snippet: a document in mm, written as a stage.
        out = tmp_path / "bottle.usda"
        r, _ = c.call("tessellate", {"brep": doc, "tolerance": "0.1mm", "output": str(out)})
        assert r["units"] == "mm" and r["meters_per_unit"] == 0.001
        assert_units(out, 0.001, "Z")
        # OpenCASCADE BREP text in inches.
        r, _ = c.call("tessellate", {"input": str(CRANK), "units": "in", "tolerance": "0.01in",
                                     "output": str(out)})
        assert_units(out, 0.0254, "Z")
        # The request's own stage options win.
        c.call("tessellate", {"brep": doc, "tolerance": "0.1mm", "output": str(out), **STAGE})
        assert_units(out, 0.01, "Y")


def test_ops_mesh_writers(daemon, tmp_path):
    with tessd.Client(daemon.socket, timeout=120) as c:
        out = tmp_path / "convert.usda"
        c.call("mesh.convert", {"input": str(SPOT), "output": str(out), **STAGE})
        assert_units(out, 0.01, "Y")

        out, boxes = tmp_path / "simplify.usda", tmp_path / "cells.usda"
        c.call("simplify", {"input": str(SPOT), "output": str(out), "method": "grid", "cells": 16,
                            "partition_output": str(boxes), **STAGE})
        assert_units(out, 0.01, "Y")
        assert_units(boxes, 0.01, "Y")

        for usd in ("refined", "cage"):
            out = tmp_path / f"subdivide_{usd}.usda"
            c.call("subdivide", {"input": str(SPOT_CAGE), "output": str(out), "usd": usd,
                                 **STAGE})
            assert_units(out, 0.01, "Y")

        out = tmp_path / "lod.usda"
        r, _ = c.call("lod", {"input": str(SPOT), "levels": ["50%", "20%"], "output": str(out),
                              "per_level": str(tmp_path / "levels"), "per_level_format": "usda",
                              **STAGE})
        assert_units(out, 0.01, "Y")
        assert len(r["per_level_files"]) == 3
        for f in r["per_level_files"]:
            assert_units(Path(f), 0.01, "Y")

        tsc = tmp_path / "spot.tsc"
        c.call("codec.compress", {"input": str(SPOT), "output": str(tsc)})
        out = tmp_path / "decompress.usda"
        c.call("codec.decompress", {"input": str(tsc), "output": str(out), **STAGE})
        assert_units(out, 0.01, "Y")
        out = tmp_path / "view.usda"
        c.call("codec.view", {"input": str(tsc), "output": str(out), "eye": [0, -3, 0.5],
                              "target": [0, 0, 0], "up": [0, 0, 1], **STAGE})
        assert_units(out, 0.01, "Y")


@pytest.mark.parametrize("op, params", [
    ("mesh.convert", {"input": str(SPOT)}),
    ("simplify", {"input": str(SPOT), "method": "grid", "cells": 8}),
    ("subdivide", {"input": str(SPOT_CAGE)}),
    ("lod", {"input": str(SPOT), "levels": ["50%"]}),
    ("tessellate", {"input": str(CRANK), "tolerance": "0.1mm"}),
])
def test_ops_refuse_bad_stage_options(daemon, tmp_path, op, params):
    out = tmp_path / "x.usda"
    with tessd.Client(daemon.socket, timeout=120) as c:
        for bad, name in [({"meters_per_unit": 0}, "`meters_per_unit`"),
                          ({"meters_per_unit": -0.001}, "`meters_per_unit`"),
                          ({"meters_per_unit": "0.001"}, "`meters_per_unit`"),
                          ({"up_axis": "X"}, "`up_axis`")]:
            with pytest.raises(TessdError) as info:
                c.call(op, {**params, "output": str(out), **bad})
            assert info.value.code == "invalid_request" and name in info.value.message, (
                op, bad, info.value)
    assert list(tmp_path.iterdir()) == []
