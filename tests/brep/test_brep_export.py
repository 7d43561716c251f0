"""The B-Rep exporter (python/tessd/brep) on real OCP: every STEP / IGES / .brep file of the shared
data and OCP-built parts (tests/brep/ocp_parts.py), checked against the format's rules and
against OCP's own evaluation of the shapes (brep_checks.py). Runs under OCP 7.9 (.venv-cad:
cadquery 2.8) and OCP 8.0 (.venv-b123d: build123d 0.13) alike (scripts/test.sh): nothing here
needs cadquery or build123d, except `test_cad_library_input`, which exports the shapes of
whichever of the two the venv has."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

import locate
from brep_checks import TIMINGS, Evaluator, check_document, compare_with_ocp, ocp_maps
from ocp_parts import PARTS, box, cylinder

from tessd.brep import export_shape
from tessd.brep import ocp as brep_ocp

REPO = Path(__file__).resolve().parents[2]
BREP_DIR = locate.shared_data() / "brep"
FILES = sorted(p.name for p in BREP_DIR.glob("*") if p.suffix.lower() in
               (".step", ".stp", ".iges", ".igs", ".brep", ".brp")) if BREP_DIR.is_dir() else []


def exported(shape, **kw):
    """(the document of `shape`, the shape its face and edge ids number: the input, or the sewn
    faces where the exporter sewed; see tessd.brep.ocp.prepare)."""
    prepared = brep_ocp.prepare(shape, sew=kw.pop("sew", None), sew_tolerance=kw.pop("sew_tolerance", None))
    return brep_ocp.export_prepared(prepared, **kw), prepared.shape


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
    doc, shape = exported(shape, source=name)
    t2 = time.perf_counter()
    stats = _check(doc, shape, name)
    TIMINGS.append((name, len(doc["faces"]), len(doc["edges"]), 1000 * (t1 - t0), 1000 * (t2 - t1), stats))
    print(f"{name}: {len(doc['faces'])} faces, read {1000 * (t1 - t0):.0f} ms, export {1000 * (t2 - t1):.0f} ms, {stats}")


# ------------------------------------------------------------------------------------------
# OCP-built parts (ocp_parts.PARTS)


@pytest.mark.parametrize("name", sorted(PARTS))
def test_built_part(name):
    shape = PARTS[name]()
    t0 = time.perf_counter()
    doc = export_shape(shape, source=name)
    t1 = time.perf_counter()
    assert "sewing" not in doc or name == "offset_face", doc.get("sewing")  # closed: not sewn
    stats = _check(doc, shape, name)
    TIMINGS.append((f"ocp:{name}", len(doc["faces"]), len(doc["edges"]), 0.0, 1000 * (t1 - t0), stats))
    types = sorted({f["surface"]["type"] for f in doc["faces"]})
    print(f"{name}: {len(doc['faces'])} faces {types}, export {1000 * (t1 - t0):.0f} ms, {stats}")


def test_parts_cover_the_cases():
    """The built parts reach what they are there for."""
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
    shape = PARTS["mirrored"]()
    stats = compare_with_ocp(export_shape(shape), shape, Evaluator())
    assert stats["mirrored_faces"] > 0


def test_seam_and_reversed_faces():
    """A cylinder's lateral face: the seam edge appears twice in the loop, each time with its
    own pcurve (u = 0 and u = 2π); a solid's faces include reversed ones."""
    doc = export_shape(cylinder(4, 10, (0, 0, -5)), source="cyl")
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
    shape = box(1, 2, 3)
    doc = export_shape(shape)
    assert any(f["reversed"] for f in doc["faces"]) and not all(f["reversed"] for f in doc["faces"])
    fmap, _ = ocp_maps(shape)
    from OCP.TopAbs import TopAbs_REVERSED

    for f in doc["faces"]:
        assert f["reversed"] == (fmap.FindKey(f["id"]).Orientation() == TopAbs_REVERSED)


def test_units_and_compound_input():
    screw = BREP_DIR / "screw.step"
    assert screw.exists(), f"shared data missing: {screw}"
    mm = brep_ocp.export_topods(brep_ocp.read_file(str(screw), units="mm"), units="mm")
    m = brep_ocp.export_topods(brep_ocp.read_file(str(screw), units="m"), units="m")
    assert m["units"] == "m"
    for fa, fb in zip(mm["faces"], m["faces"]):
        if fa["surface"]["type"] in ("plane", "cylinder"):
            assert all(math.isclose(a, 1000 * b, rel_tol=1e-9, abs_tol=1e-9)
                       for a, b in zip(fa["surface"]["origin"], fb["surface"]["origin"]))
    # A compound of three separate boxes: every face, and (closed solids) not sewn.
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    comp, b = TopoDS_Compound(), BRep_Builder()
    b.MakeCompound(comp)
    for x in (-10, 0, 10):
        b.Add(comp, box(2, 2, 2).Moved(_translation(x, 0, 0)))
    doc = export_shape(comp)
    assert len(doc["faces"]) == 18 and "sewing" not in doc
    with pytest.raises(ValueError):
        export_shape(comp, units="furlong")
    with pytest.raises(ValueError):
        export_shape(comp, sew=True, sew_tolerance=-1.0)


def _translation(x, y, z):
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.TopLoc import TopLoc_Location

    t = gp_Trsf()
    t.SetTranslation(gp_Vec(x, y, z))
    return TopLoc_Location(t)


def test_cad_library_input():
    """The shapes of the CAD library this venv has, as users pass them: cadquery's `Workplane`
    (several solids: one compound) and `Shape` under OCP 7.9 (.venv-cad), build123d's `Part`
    and `Compound` under OCP 8.0 (.venv-b123d). One of the two must be there."""
    try:
        import cadquery as cq
    except ImportError:
        cq = None
    if cq is not None:
        wp = cq.Workplane("XY").rarray(10, 1, 3, 1).box(2, 2, 2)
        assert len(export_shape(wp)["faces"]) == 18
        solid = cq.Workplane("XY").box(40, 30, 10).faces(">Z").workplane().hole(10).val()
        doc = export_shape(solid, source="cq")
        _check(doc, solid.wrapped, "cq")
        assert len(doc["faces"]) == 7
        return
    import build123d as bd  # the build123d venv (no cadquery there)

    part = bd.Box(40, 30, 10) - bd.Cylinder(radius=5, height=10)
    doc = export_shape(part, source="b123d")
    _check(doc, part.wrapped, "b123d")
    assert len(doc["faces"]) == 7
    boxes = bd.Compound([bd.Pos(x, 0, 0) * bd.Box(2, 2, 2) for x in (-10, 0, 10)])
    assert len(export_shape(boxes)["faces"]) == 18


@pytest.mark.parametrize("name", ["screw.step", "hammer.iges", "bottle.brep"])
def test_cli_writes_valid_json(tmp_path, name):
    path = BREP_DIR / name
    assert path.exists(), f"shared data missing: {path}"
    out = tmp_path / "out.json"
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    r = subprocess.run([sys.executable, "-m", "tessd.brep", "export", str(path), str(out)],
                       env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    doc = json.loads(out.read_text(), parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))
    assert doc["format"] == "tessd-brep" and doc["version"] == 1 and doc["source"] == name
    shape = brep_ocp.read_file(str(path))
    assert len(doc["faces"]) == ocp_maps(shape)[0].Extent()
    # the summary line says what sewing did (hammer.iges: unsewn IGES surfaces, sewn)
    assert ("sewn at" in r.stderr) == (name == "hammer.iges"), r.stderr
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
