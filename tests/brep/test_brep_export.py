"""The B-Rep exporter (python/tessd/brep) on real OCP: every STEP / IGES / .brep file of the shared
data and cadquery-built parts, checked against the format's rules and against OCP's own
evaluation of the shapes (brep_checks.py). Runs in the CAD venv (.venv-cad: cadquery 2.8,
cadquery-ocp 7.9)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

import cadquery as cq
import locate
from brep_checks import TIMINGS, Evaluator, check_document, compare_with_ocp, ocp_maps

from tessd.brep import export_shape
from tessd.brep import ocp as brep_ocp

REPO = Path(__file__).resolve().parents[2]
BREP_DIR = locate.shared_data() / "brep"
FILES = sorted(p.name for p in BREP_DIR.glob("*") if p.suffix.lower() in
               (".step", ".stp", ".iges", ".igs", ".brep", ".brp")) if BREP_DIR.is_dir() else []


def _check(doc, shape, label):
    ev = Evaluator()
    doc_stats = check_document(doc, ev)
    stats = compare_with_ocp(doc, shape, ev)
    # The document must survive JSON (no NaN / inf, plain types only).
    json.loads(json.dumps(doc, allow_nan=False))
    return {**doc_stats, **stats}


def test_the_shared_parts_are_there():
    assert len(FILES) >= 10, f"shared B-Rep data missing in {BREP_DIR}: {FILES}"


@pytest.mark.parametrize("name", FILES)
def test_shared_file(name):
    path = str(BREP_DIR / name)
    t0 = time.perf_counter()
    shape = brep_ocp.read_file(path)
    t1 = time.perf_counter()
    doc = brep_ocp.export_topods(shape, source=name)
    t2 = time.perf_counter()
    stats = _check(doc, shape, name)
    TIMINGS.append((name, len(doc["faces"]), len(doc["edges"]), 1000 * (t1 - t0), 1000 * (t2 - t1), stats))
    print(f"{name}: {len(doc['faces'])} faces, read {1000 * (t1 - t0):.0f} ms, export {1000 * (t2 - t1):.0f} ms, {stats}")


# ------------------------------------------------------------------------------------------
# cadquery-built parts


def _plate_with_holes():
    return (cq.Workplane("XY").box(80, 60, 10).faces(">Z").workplane()
            .rarray(20, 20, 3, 2).hole(6).faces(">Z").workplane().rect(60, 40, forConstruction=True)
            .vertices().cboreHole(4, 7, 3))


def _filleted_box():
    return cq.Workplane("XY").box(30, 20, 10).edges().fillet(3)


def _revolved():
    # a profile with lines and a spline: planes, cones, cylinders, a surface of revolution
    prof = (cq.Workplane("XZ").moveTo(0, 0).lineTo(10, 0).lineTo(12, 5).lineTo(12, 10)
            .spline([(8, 16), (6, 22)], includeCurrent=True).lineTo(0, 22).close())
    return prof.revolve(360, (0, 0, 0), (0, 1, 0))


def _revolved_torus():
    return cq.Workplane("XZ").center(20, 0).circle(4).revolve(270, (-20, 0, 0), (-20, 1, 0))


def _lofted():
    return (cq.Workplane("XY").rect(20, 20).workplane(offset=15).circle(8)
            .workplane(offset=10).ellipse(12, 6).loft(ruled=False))


def _island():
    # the top face has a hole (the ring pocket's outer circle); the island (the boss left in the
    # pocket) is a face of its own in that hole; the pocket's floor is a ring (a face with a hole)
    return (cq.Workplane("XY").box(50, 50, 10).faces(">Z").workplane()
            .circle(15).circle(6).cutBlind(-4))


def _mirrored():
    # mirrored cylinders/cones/spheres: OCP frames turn indirect (left-handed)
    part = (cq.Workplane("XY").box(30, 20, 10).faces(">Z").workplane().hole(8)
            .edges("|Z").fillet(2).faces("<Z").edges().chamfer(1))
    part = part.union(cq.Workplane("XY").sphere(6).translate((0, 0, 8)))
    return part.mirror("YZ")


def _extruded_spline():
    return (cq.Workplane("XY").spline([(0, 0), (10, 5), (20, -3), (30, 4)]).lineTo(30, 20)
            .lineTo(0, 20).close().extrude(8))


def _moved():
    # shapes placed by a TopLoc_Location (not baked into the geometry)
    c = cq.Workplane("XY").cylinder(10, 4).val()
    return c.moved(cq.Location(cq.Vector(5, -3, 7), cq.Vector(1, 1, 0), 33))


def _offset_face():
    # an offset surface (no format type: goes through BRepBuilderAPI_NurbsConvert)
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_OffsetSurface

    lofted = _lofted().val()
    bs = [f for f in lofted.Faces() if f.geomType() == "BSPLINE"][0]
    from OCP.BRep import BRep_Tool

    surf = BRep_Tool.Surface_s(bs.wrapped)
    u0, u1, v0, v1 = bs._uvBounds()
    off = Geom_OffsetSurface(surf, 1.5)
    return BRepBuilderAPI_MakeFace(off, u0, u1, v0, v1, 1e-7).Face()


PARTS = {
    "plate_with_holes": _plate_with_holes,
    "filleted_box": _filleted_box,
    "revolved": _revolved,
    "revolved_torus": _revolved_torus,
    "lofted": _lofted,
    "island": _island,
    "mirrored": _mirrored,
    "extruded_spline": _extruded_spline,
    "moved": _moved,
    "offset_face": _offset_face,
}


@pytest.mark.parametrize("name", sorted(PARTS))
def test_cadquery_part(name):
    part = PARTS[name]()
    shape = brep_ocp.to_topods(part)
    t0 = time.perf_counter()
    doc = export_shape(part, source=name)
    t1 = time.perf_counter()
    stats = _check(doc, shape, name)
    TIMINGS.append((f"cq:{name}", len(doc["faces"]), len(doc["edges"]), 0.0, 1000 * (t1 - t0), stats))
    types = sorted({f["surface"]["type"] for f in doc["faces"]})
    print(f"{name}: {len(doc['faces'])} faces {types}, export {1000 * (t1 - t0):.0f} ms, {stats}")


def test_parts_cover_the_cases():
    """The cadquery parts reach what they are there for."""
    def doc(name):
        return export_shape(PARTS[name](), source=name)

    # the top (z = 5): the plate's face with a hole (the pocket's outer circle, r 15) and the
    # island's disc (r 6) inside that hole; the pocket's floor (z = 1): a ring (r 15 around r 6)
    island = doc("island")

    def planar_at(z):
        return sorted((f for f in island["faces"] if f["surface"]["type"] == "plane"
                       and abs(abs(cross_z(f["surface"])) - 1) < 1e-9
                       and abs(f["surface"]["origin"][2] - z) < 1e-9), key=lambda f: len(f["loops"]))

    def cross_z(s):
        x, y = s["x_dir"], s["y_dir"]
        return x[0] * y[1] - x[1] * y[0]

    top, floor = planar_at(5.0), planar_at(1.0)
    assert [len(f["loops"]) for f in top] == [1, 2], [len(f["loops"]) for f in top]
    assert [len(f["loops"]) for f in floor] == [2]
    assert top[1]["loops"][1]["edges"][0]["curve"]["type"] == "circle"
    types = {f["surface"]["type"] for f in doc("revolved")["faces"]}
    assert {"cone", "cylinder", "revolution"} <= types, types
    assert "torus" in {f["surface"]["type"] for f in doc("revolved_torus")["faces"]}
    assert "bspline" in {f["surface"]["type"] for f in doc("lofted")["faces"]}
    assert "extrusion" in {f["surface"]["type"] for f in doc("extruded_spline")["faces"]}
    filleted = {f["surface"]["type"] for f in doc("filleted_box")["faces"]}
    assert {"plane", "cylinder"} <= filleted, filleted
    assert [f["surface"]["type"] for f in doc("offset_face")["faces"]] == ["bspline"]
    # the mirrored part has indirect OCP frames: exported mirrored, still checked exact above
    mirrored = PARTS["mirrored"]()
    shape = brep_ocp.to_topods(mirrored)
    stats = compare_with_ocp(export_shape(mirrored), shape, Evaluator())
    assert stats["mirrored_faces"] > 0


def test_seam_and_reversed_faces():
    """A cylinder's lateral face: the seam edge appears twice in the loop, each time with its
    own pcurve (u = 0 and u = 2π); a solid's faces include reversed ones."""
    doc = export_shape(cq.Workplane("XY").cylinder(10, 4), source="cyl")
    lateral = [f for f in doc["faces"] if f["surface"]["type"] == "cylinder"]
    assert len(lateral) == 1
    trims = lateral[0]["loops"][0]["edges"]
    ids = [t["edge"] for t in trims]
    seam = [i for i in set(ids) if ids.count(i) == 2]
    assert len(seam) == 1, ids
    us = sorted(Evaluator().curve(t["curve"], t["range"][0])[0] for t in trims if t["edge"] == seam[0])
    assert math.isclose(us[1] - us[0], 2 * math.pi, abs_tol=1e-9), us
    edge = [e for e in doc["edges"] if e["id"] == seam[0]][0]
    assert edge["faces"] == [lateral[0]["id"]]
    box = export_shape(cq.Workplane("XY").box(1, 2, 3))
    assert any(f["reversed"] for f in box["faces"]) and not all(f["reversed"] for f in box["faces"])
    shape = brep_ocp.to_topods(cq.Workplane("XY").box(1, 2, 3))
    fmap, _ = ocp_maps(shape)
    from OCP.TopAbs import TopAbs_REVERSED

    for f in box["faces"]:
        assert f["reversed"] == (fmap.FindKey(f["id"]).Orientation() == TopAbs_REVERSED)


def test_units_and_workplane_input():
    screw = BREP_DIR / "screw.step"
    if not screw.exists():
        pytest.skip("no shared data")
    mm = brep_ocp.export_topods(brep_ocp.read_file(str(screw), units="mm"), units="mm")
    m = brep_ocp.export_topods(brep_ocp.read_file(str(screw), units="m"), units="m")
    assert m["units"] == "m"
    for fa, fb in zip(mm["faces"], m["faces"]):
        if fa["surface"]["type"] in ("plane", "cylinder"):
            assert all(math.isclose(a, 1000 * b, rel_tol=1e-9, abs_tol=1e-9)
                       for a, b in zip(fa["surface"]["origin"], fb["surface"]["origin"]))
    # A Workplane with several solids: one compound, every face.
    wp = cq.Workplane("XY").rarray(10, 1, 3, 1).box(2, 2, 2)
    assert len(export_shape(wp)["faces"]) == 18
    with pytest.raises(ValueError):
        export_shape(wp, units="furlong")


@pytest.mark.parametrize("name", ["screw.step", "hammer.iges", "bottle.brep"])
def test_cli_writes_valid_json(tmp_path, name):
    path = BREP_DIR / name
    if not path.exists():
        pytest.skip("no shared data")
    out = tmp_path / "out.json"
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    r = subprocess.run([sys.executable, "-m", "tessd.brep", "export", str(path), str(out)],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    doc = json.loads(out.read_text(), parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert doc["format"] == "tessd-brep" and doc["version"] == 1 and doc["source"] == name
    shape = brep_ocp.read_file(str(path))
    assert len(doc["faces"]) == ocp_maps(shape)[0].Extent()
    # `-`: the JSON alone on standard output (OCCT's reader chatter goes to standard error)
    r = subprocess.run([sys.executable, "-m", "tessd.brep", "export", str(path), "-"],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == doc


def test_cli_errors(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    bad = tmp_path / "x.obj"
    bad.write_text("v 0 0 0\n")
    for args in ([str(tmp_path / "missing.step"), str(tmp_path / "o.json")], [str(bad), str(tmp_path / "o.json")]):
        r = subprocess.run([sys.executable, "-m", "tessd.brep", "export", *args],
                           env=env, capture_output=True, text=True, timeout=120)
        assert r.returncode != 0 and "tessd.brep:" in r.stderr, r.stderr
        assert not (tmp_path / "o.json").exists()


def test_import_needs_no_ocp():
    """`import tessd.brep` (and `tessd`) must not import OCP: the main venv has none."""
    code = "import sys, tessd, tessd.brep; assert 'OCP' not in sys.modules, 'OCP imported'"
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
