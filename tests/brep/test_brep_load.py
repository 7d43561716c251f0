"""Exporter and daemon together: every shared STEP / IGES / .brep part and the OCP-built parts,
exported by python/tessd/brep on real OCP, are accepted by the daemon's `brep.load` (the Rust
validator of core/brep, an independent reader of the same format), with its table-1 counts
equal to what was sent; a broken document is refused naming the element."""

from __future__ import annotations

import copy
import os
import tempfile
from collections import Counter

import pytest
from OCP.BRepTools import BRepTools

import tessd
from tessd import TessdError
from tessd.brep import export_shape
from tessd.brep import ocp as brep_ocp

from ocp_parts import PARTS
from test_brep_export import BREP_DIR, FILES


def load(daemon, doc):
    with tessd.Client(daemon.socket, timeout=120) as c:
        return c.call("brep.load", {"brep": doc})[0]


def check_counts(result, doc):
    assert result["faces"] == [f["id"] for f in doc["faces"]]
    stats = result["stats"]
    flat = str(stats)
    for surface, n in Counter(f["surface"]["type"] for f in doc["faces"]).items():
        assert surface in flat, (surface, stats)
    assert sum(len(f["loops"]) for f in doc["faces"]) > 0
    return stats


@pytest.mark.parametrize("name", FILES)
def test_shared_parts_load(daemon, name):
    doc = brep_ocp.export_topods(brep_ocp.read_file(str(BREP_DIR / name)), source=name)
    result = load(daemon, doc)
    print(name, result["stats"])
    check_counts(result, doc)


@pytest.mark.parametrize("name", sorted(PARTS))
def test_built_parts_load(daemon, name):
    doc = export_shape(PARTS[name](), source=name)
    check_counts(load(daemon, doc), doc)


def test_a_broken_document_is_refused(daemon):
    doc = export_shape(PARTS[sorted(PARTS)[0]](), source="broken")
    bad = copy.deepcopy(doc)
    face = next(f for f in bad["faces"] if f["loops"] and len(f["loops"][0]["edges"]) > 2)
    del face["loops"][0]["edges"][1]  # opens the outer loop
    with pytest.raises(TessdError) as e:
        load(daemon, bad)
    assert e.value.code == "invalid_brep"
    assert f"face {face['id']}, loop 0" in e.value.message, e.value.message
    assert load(daemon, doc)["faces"]  # the daemon is still up


def brep_text(shape) -> str:
    """OpenCASCADE's own BREP text of a shape (what FreeCAD's exportBrepToString gives)."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "s.brep")
        assert BRepTools.Write_s(shape, path)
        with open(path) as f:
            return f.read()


def test_brep_text_requests_and_their_errors(daemon):
    """`brep` as OpenCASCADE BREP text, with `units`; the refusals name what is wrong and the
    daemon serves on."""
    name = sorted(PARTS)[0]
    text = brep_text(PARTS[name]())
    with tessd.Client(daemon.socket, timeout=120) as c:
        got = c.call("brep.load", {"brep": text, "units": "cm"})[0]
        assert got["units"] == "cm" and got["faces"][0] == 1
        assert got["faces"] == list(range(1, len(got["faces"]) + 1))
        for params, code, words in [
            ({"brep": "not a shape"}, "invalid_brep", "OpenCASCADE BREP text"),
            ({"brep": text, "units": "furlong"}, "invalid_request", "`units`"),
            ({"brep": export_shape(PARTS[name]()), "units": "mm"}, "invalid_request",
             "BREP text only"),
            ({"brep": text[: len(text) // 2]}, "invalid_brep", "line"),
            ({"brep": 7}, "invalid_request", "a number"),
        ]:
            with pytest.raises(TessdError) as e:
                c.call("brep.load", params)
            assert e.value.code == code, (params.get("units"), e.value)
            assert words in e.value.message, e.value.message
        assert c.call("brep.load", {"brep": text})[0]["faces"] == got["faces"]
