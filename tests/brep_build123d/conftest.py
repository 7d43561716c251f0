"""tests/brep_build123d runs in the build123d venv (.venv-b123d: build123d 0.13 on OCP 8.0,
python/requirements-build123d.txt; scripts/test.sh). The root conftest puts python/ and tests/
on sys.path and provides the `daemon` fixture; this one adds tests/brep, whose OCP checks
(brep_checks.py, tessellation_checks.py) load under OCP 7.9 and 8.0 alike (tests/brep itself
runs in this venv too: scripts/test.sh)."""

from __future__ import annotations

import sys
from pathlib import Path

BREP_TESTS = Path(__file__).resolve().parent.parent / "brep"
if str(BREP_TESTS) not in sys.path:
    sys.path.insert(0, str(BREP_TESTS))
