"""Exporter and daemon together: every shared STEP / IGES / .brep part and the OCP-built parts,
exported by python/tessd/brep on real OCP, are accepted by the daemon's `brep.load` (the Rust
validator of core/brep, an independent reader of the same format), with its table-1 counts
equal to what was sent; a broken document is refused naming the element."""

from __future__ import annotations

import copy
from collections import Counter

import pytest

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
