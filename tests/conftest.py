"""Shared pytest setup: make `python/` (the tessd package), `tests/` (locate.py) and
`tests/usd` (usd_checks) importable."""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
for p in (REPO / "python", REPO / "tests", REPO / "tests" / "usd"):
    sys.path.insert(0, str(p))
