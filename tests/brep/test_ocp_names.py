"""Every OCP name the exporter and the shared checks use exists in this venv's OCP (7.9, cadquery;
tests/brep_build123d asks OCP 8.0 the same), as spelled or through tessd.brep.ocp_compat."""

from __future__ import annotations

import pytest

from ocp_names import SHARED, unresolved


@pytest.mark.parametrize("path", SHARED, ids=lambda p: p.name)
def test_ocp_names_resolve(path):
    assert unresolved(path) == []
