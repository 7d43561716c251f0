"""The FreeCAD exporter (python/tessd/brep/freecad.py) on real FreeCAD 0.20: every STEP / IGES /
.brep file of the shared data (read by FreeCAD) and parts built with FreeCAD's Part API, checked
against FreeCAD's own evaluation of the shapes (fc_checks.py); the cases the parts are there
for; topology (shared edges, seams, poles); units; bad input. System Python (conftest.py)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest

import FreeCAD
import Part
from fc_checks import TIMINGS, Evaluator, check_against_freecad, exported, exported_timed, shared_files
from fc_parts import PARTS

from tessd.brep import export_shape
from tessd.brep import freecad as brep_freecad
from tessd.brep.document import ExportError

REPO = Path(__file__).resolve().parents[2]
FILES = shared_files()


def _check(name):
    shape, doc, read_ms, export_ms = exported_timed(name)
    stats = check_against_freecad(doc, shape, Evaluator())
    # plain JSON: no NaN / inf, nothing but dicts, lists, numbers, strings
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc
    TIMINGS.append((name, len(doc["faces"]), len(doc["edges"]), read_ms, export_ms, stats))
    return doc, stats


def test_the_shared_parts_are_there():
    assert len(FILES) >= 10, f"shared B-Rep data missing: {FILES}"


@pytest.mark.parametrize("name", FILES)
def test_shared_file(name):
    doc, stats = _check(name)
    print(f"{name}: {len(doc['faces'])} faces, {stats}")


@pytest.mark.parametrize("name", sorted(PARTS))
def test_freecad_part(name):
    doc, stats = _check(name)
    print(f"{name}: {len(doc['faces'])} faces {sorted({f['surface']['type'] for f in doc['faces']})}, {stats}")


def _types(name):
    return {f["surface"]["type"] for f in exported(name)[1]["faces"]}


def test_parts_cover_the_cases():
    """The built parts reach what they are there for."""
    assert {"plane", "cylinder", "cone"} <= _types("filleted_box")  # fillets, chamfers (cones)
    assert {"cone", "cylinder", "revolution", "plane"} <= _types("revolved_profile")
    assert "bspline" in _types("lofted")
    assert _types("torus") == {"torus"} and _types("sphere") == {"sphere"}
    assert "extrusion" in _types("extruded_spline")
    assert [f["surface"]["type"] for f in exported("offset_face")[1]["faces"]] == ["bspline"]
    # left-handed frames after the mirror: written mirrored, checked exact by check_against_freecad
    shape, doc = exported("mirrored")
    assert check_against_freecad(doc, shape)["mirrored"] > 0
    # holes in the cylinder: its end planes have three (axial) holes each
    _, holes = exported("cylinder_with_holes")
    planes = [f for f in holes["faces"] if f["surface"]["type"] == "plane"]
    assert sorted(len(f["loops"]) for f in planes) == [4, 4]

    # the island: the top (z = 10) has the pocket's outer circle (r 15) as a hole, the island's
    # disc (r 6) is a face of its own at the same height, and the floor (z = 6) is a ring
    _, island = exported("island")

    def horizontal(s):  # |z of x_dir × y_dir| = 1
        return abs(abs(s["x_dir"][0] * s["y_dir"][1] - s["x_dir"][1] * s["y_dir"][0]) - 1) < 1e-9

    def planar_at(z):
        return sorted((f for f in island["faces"] if f["surface"]["type"] == "plane"
                       and horizontal(f["surface"]) and abs(f["surface"]["origin"][2] - z) < 1e-9),
                      key=lambda f: len(f["loops"]))

    top, floor = planar_at(10.0), planar_at(6.0)
    assert [len(f["loops"]) for f in top] == [1, 2], [len(f["loops"]) for f in top]
    assert [len(f["loops"]) for f in floor] == [2]
    hole = top[1]["loops"][1]["edges"]
    assert [t["curve"]["type"] for t in hole] == ["circle"], hole
    ev = Evaluator()
    u, v = ev.curve(hole[0]["curve"], hole[0]["range"][0])
    p = ev.surface(top[1]["surface"], u, v)
    assert math.isclose(math.hypot(p[0], p[1]), 15.0, rel_tol=1e-12)


def test_seams_poles_and_shared_edges():
    """A sphere: the seam edge twice in the loop (at u = 0 and u = 2π), the poles as degenerate
    edges without a curve. A closed solid: every edge with a curve bounds two faces (one id, two
    trims) or is a seam (one face, two trims)."""
    _, sphere = exported("sphere")
    (face,) = sphere["faces"]
    trims = face["loops"][0]["edges"]
    ids = [t["edge"] for t in trims]
    seam = [i for i in set(ids) if ids.count(i) == 2]
    assert len(seam) == 1, ids
    ev = Evaluator()
    us = sorted(ev.curve(t["curve"], t["range"][0])[0] for t in trims if t["edge"] == seam[0])
    assert math.isclose(us[1] - us[0], 2 * math.pi, abs_tol=1e-9), us
    poles = [e for e in sphere["edges"] if e["curve"] is None]
    assert len(poles) == 2 and all(e["faces"] == [face["id"]] for e in poles)

    for name in ("filleted_box", "revolved_profile", "torus", "island", "mirrored"):
        shape, doc = exported(name)
        uses = {}
        for f in doc["faces"]:
            for lp in f["loops"]:
                for t in lp["edges"]:
                    if t["edge"] is not None:
                        uses.setdefault(t["edge"], []).append(f["id"])
        for e in doc["edges"]:
            if e["curve"] is None:
                continue
            assert len(uses[e["id"]]) == 2, (name, e["id"], uses[e["id"]])
            assert sorted(set(uses[e["id"]])) == sorted(e["faces"]), (name, e)
        assert len(doc["edges"]) == len(shape.Edges)  # one id per topological edge


def test_reversed_faces():
    """`reversed` is FreeCAD's face orientation on direct frames (a box: both kinds)."""
    box = Part.makeBox(1, 2, 3)
    doc = export_shape(box)
    assert [f["reversed"] for f in doc["faces"]] == [f.Orientation == "Reversed" for f in box.Faces]
    assert any(f["reversed"] for f in doc["faces"]) and not all(f["reversed"] for f in doc["faces"])


def test_units_and_document_objects():
    """FreeCAD's millimetres scaled into other units; a document object exports its shape."""
    screw = "screw.step"
    if screw not in FILES:
        pytest.skip("no shared data")
    shape, mm = exported(screw)
    m = export_shape(shape, units="m", source=screw)
    assert m["units"] == "m" and len(m["faces"]) == len(mm["faces"])
    for fa, fb in zip(mm["faces"], m["faces"]):
        assert fa["surface"]["type"] == fb["surface"]["type"]
        if fa["surface"]["type"] in ("plane", "cylinder"):
            assert all(math.isclose(a, 1000 * b, rel_tol=1e-9, abs_tol=1e-9)
                       for a, b in zip(fa["surface"]["origin"], fb["surface"]["origin"]))
        if fa["surface"]["type"] == "cylinder":
            assert math.isclose(fa["surface"]["radius"], 1000 * fb["surface"]["radius"], rel_tol=1e-12)
    assert check_against_freecad(m, shape.scaled(0.001))["surface"] < 1e-9
    doc = FreeCAD.newDocument("tessd_export_test")
    try:
        box = doc.addObject("Part::Box", "Box")
        doc.recompute()
        out = export_shape(box, source="Box")
        assert len(out["faces"]) == 6 and out["source"] == "Box"
    finally:
        FreeCAD.closeDocument(doc.Name)


def test_bad_input():
    """Clear errors: not a shape, a null shape, a unit, a file."""
    with pytest.raises(TypeError, match="Part.Shape"):
        export_shape(object())
    with pytest.raises(TypeError, match="not a FreeCAD Part.Shape: Circle"):
        export_shape(Part.Circle())  # a FreeCAD object, not a shape
    with pytest.raises(TypeError, match="Part.Shape"):
        brep_freecad.export_shape(42)
    with pytest.raises(ExportError, match="empty shape"):
        export_shape(Part.Shape())
    with pytest.raises(ValueError, match="units"):
        export_shape(Part.makeBox(1, 1, 1), units="furlong")
    with pytest.raises(FileNotFoundError):
        brep_freecad.read_file("/nonexistent/part.step")
    with pytest.raises(ExportError, match="unknown extension"):
        brep_freecad.read_file(__file__)


def test_no_cad_kernel_on_import():
    """`import tessd.brep` imports neither FreeCAD nor OCP; exporting a FreeCAD shape needs no
    OCP (this Python has none)."""
    code = ("import sys, tessd, tessd.brep\n"
            "assert not {'OCP', 'Part', 'FreeCAD'} & set(sys.modules), 'a CAD kernel imported'\n"
            f"sys.path.append({brep_freecad.FREECAD_LIB!r})\n"
            "import FreeCAD, Part\n"
            "doc = tessd.brep.export_shape(Part.makeCylinder(1, 2))\n"
            "assert len(doc['faces']) == 3 and 'OCP' not in sys.modules\n")
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr


def test_chaining_in_uv():
    """Trims whose order does not close in (u, v) (a wire FreeCAD's explorer ordered without
    the face) are chained from the first by their ends; closed loops stay as they are."""
    from tessd.brep.document import Line2d, Trim
    from tessd.brep.freecad import _chained

    corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    square = []
    for i, a in enumerate(corners):
        b = corners[(i + 1) % 4]
        d = (b[0] - a[0], b[1] - a[1])
        square.append(Trim(Line2d(a, d), 0.0, 1.0, i + 1))
    assert _chained(square, math.sqrt(2)) == square
    shuffled = [square[0], square[2], square[1], square[3]]
    assert [t.edge for t in _chained(shuffled, math.sqrt(2))] == [1, 2, 3, 4]
