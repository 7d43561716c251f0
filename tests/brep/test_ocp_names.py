"""Every OCP name the exporter, the tests of tests/brep and the OCP benchmark peer use exists in
this venv's OCP (7.9 in .venv-cad, 8.0 in .venv-b123d: scripts/test.sh runs tests/brep in both),
as spelled or through tessd.brep.ocp_compat."""

from __future__ import annotations

import pytest

from ocp_names import SHARED, unresolved


@pytest.mark.parametrize("path", SHARED, ids=lambda p: p.name)
def test_ocp_names_resolve(path):
    assert unresolved(path) == []
