"""Shared pytest setup: make `python/` (the tessd package), `tests/` (locate.py), `tests/daemon`
(daemon_util) and `tests/usd` (usd_checks) importable; the module-scoped `daemon` fixture that
the simplification, subdivision, render and tessellation-precision tests share (tests/daemon
has its own), and the shared test data (never skipped: a missing folder fails)."""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
for p in (REPO / "python", REPO / "tests", REPO / "tests" / "daemon", REPO / "tests" / "usd"):
    sys.path.insert(0, str(p))


import pytest  # noqa: E402

import locate  # noqa: E402
from daemon_util import serving  # noqa: E402


@pytest.fixture(scope="session")
def shared_data():
    """The shared test-data folder (fails when missing)."""
    path = locate.shared_data()
    assert (path / "mesh").is_dir(), f"shared test data not found at {path} (set TESSD_SHARED_DATA)"
    return path


@pytest.fixture(scope="module")
def daemon():
    """One `tessd serve --socket <tmp>/t.sock` for the whole module, checked alive at the end."""
    with serving(str(locate.tessd_bin())) as proc:
        yield proc
