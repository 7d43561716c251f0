"""Fixtures for the daemon tests: real `tessd serve` processes on real sockets.

The binary is `$TESSD_BIN`, else `target/release/tessd`, else `target/debug/tessd` (relative
to the repository root). Tests that need a daemon are skipped when none is built. Shared mesh
data comes from `$TESSD_SHARED_DATA`, default `<repo>/../shared/data`.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from daemon_util import DaemonProcess, find_tessd_binary, short_tmpdir  # noqa: E402


@pytest.fixture(scope="session")
def tessd_bin() -> str:
    """Path of the tessd binary (skips the test when there is none)."""
    path = find_tessd_binary()
    if path is None:
        pytest.skip("no tessd binary: set TESSD_BIN or run `cargo build -p tessd`")
    return path


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared test-data folder (skips when missing)."""
    path = Path(os.environ.get("TESSD_SHARED_DATA") or (REPO.parent / "shared" / "data"))
    if not (path / "mesh").is_dir():
        pytest.skip("shared test data not found at %s (set TESSD_SHARED_DATA)" % path)
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
    with short_tmpdir() as d:
        proc = DaemonProcess(tessd_bin, os.path.join(d, "t.sock"))
        proc.start()
        try:
            yield proc
            assert proc.alive(), "the daemon died during the tests:\n" + proc.log_tail()
        finally:
            proc.stop()
