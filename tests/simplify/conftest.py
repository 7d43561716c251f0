"""Fixtures for the simplification tests: a real daemon (helpers are in simplify_util.py).

The binary and the shared data are found by `tests/locate.py`; a missing binary or data
folder fails the tests (it is never a reason to skip).
"""

from __future__ import annotations

import sys
from pathlib import Path


REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(REPO / "tests" / "daemon"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import locate  # noqa: E402


