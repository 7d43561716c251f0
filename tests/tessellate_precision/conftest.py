"""Fixtures for the tessellation precision tests: a real `tessd serve` on a real socket (the
pattern of tests/daemon/conftest.py; the binary is found by tests/locate.py, never skipped)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "tests" / "daemon"))

import locate  # noqa: E402
from daemon_util import DaemonProcess, short_tmpdir  # noqa: E402


@pytest.fixture(scope="session")
def tessd_bin() -> str:
    """Path of the tessd binary."""
    return str(locate.tessd_bin())


@pytest.fixture(scope="module")
def daemon(tessd_bin):
    """One `tessd serve --socket <tmp>/t.sock` for the whole module, stopped at the end."""
    with short_tmpdir() as d:
        proc = DaemonProcess(tessd_bin, os.path.join(d, "t.sock"))
        proc.start()
        try:
            yield proc
            assert proc.alive(), "the daemon died during the tests:\n" + proc.log_tail()
        finally:
            proc.stop()
