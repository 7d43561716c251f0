"""Fixtures for the daemon tests: real `tessd serve` processes on real sockets.

The binary and the shared data are found by `tests/locate.py`; a missing binary or data
folder fails the tests (it is never a reason to skip).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import locate  # noqa: E402
from daemon_util import serving, short_tmpdir  # noqa: E402


@pytest.fixture(scope="session")
def tessd_bin() -> str:
    """Path of the tessd binary."""
    return str(locate.tessd_bin())


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared test-data folder (fails when missing)."""
    path = locate.shared_data()
    assert (path / "mesh").is_dir(), f"shared test data not found at {path} (set TESSD_SHARED_DATA)"
    return path


@pytest.fixture
def tmpdir_short():
    """A fresh short temporary folder (AF_UNIX paths are limited to ~107 bytes)."""
    with short_tmpdir() as d:
        yield d


@pytest.fixture(scope="module")
def daemon(tessd_bin):
    """One `tessd serve --socket <tmp>/t.sock` for the whole test module.

    Stopped at the end with the `shutdown` op (then killed if it does not exit); the test
    module fails at teardown if the daemon died during it.
    """
    with serving(tessd_bin) as proc:
        yield proc
