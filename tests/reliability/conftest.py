"""Fixtures for the fault-injection and access tests: real `tessd serve` processes killed,
starved and probed from outside; a second system user; a small tmpfs.

Everything here runs as root in CI (a fresh machine): the second user is created when missing,
the tmpfs is mounted and unmounted by the test. Nothing is mocked and nothing is skipped: a
missing tool (`useradd`, `mount`) fails the test that needs it.
"""

from __future__ import annotations

import os
import pwd
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "daemon"))
sys.path.insert(0, str(HERE.parent.parent / "python"))

import locate  # noqa: E402
from daemon_util import short_tmpdir  # noqa: E402

#: The second system user of the access tests.
OTHER_USER = "tessd-other"


@pytest.fixture(scope="session")
def tessd_bin() -> str:
    """Path of the tessd binary."""
    path = locate.tessd_bin()
    assert path.is_file(), f"no tessd binary at {path}"
    return str(path)


@pytest.fixture(scope="session")
def mesh_dir() -> Path:
    """The shared test meshes (fails when missing)."""
    path = locate.shared_data() / "mesh"
    assert (path / "suzanne.obj").is_file(), f"shared test data not found at {path}"
    return path


@pytest.fixture
def tmpdir_short():
    """A fresh short temporary folder (AF_UNIX paths are limited to ~107 bytes)."""
    with short_tmpdir() as d:
        yield d


@pytest.fixture(scope="session")
def other_user() -> pwd.struct_passwd:
    """A second system user: `tessd-other`, created with `useradd --system` when missing (and
    removed again at the end of the session). The tests run as root, as CI does."""
    assert os.geteuid() == 0, "the access tests create a second user: run them as root"
    try:
        yield pwd.getpwnam(OTHER_USER)
        return
    except KeyError:
        pass
    useradd = shutil.which("useradd") or "/usr/sbin/useradd"
    subprocess.run([useradd, "--system", "--no-create-home", "--shell", "/usr/sbin/nologin",
                    OTHER_USER], check=True, capture_output=True)
    try:
        yield pwd.getpwnam(OTHER_USER)
    finally:
        userdel = shutil.which("userdel") or "/usr/sbin/userdel"
        subprocess.run([userdel, OTHER_USER], capture_output=True)


@pytest.fixture(scope="session")
def public_bin(tessd_bin):
    """A copy of the tessd binary that any user may run (the build folder may sit under a
    private home), in a world-readable temporary folder."""
    d = tempfile.mkdtemp(prefix="tsd-bin-", dir="/tmp")
    os.chmod(d, 0o755)
    path = os.path.join(d, "tessd")
    shutil.copy(tessd_bin, path)
    os.chmod(path, 0o755)
    yield path
    shutil.rmtree(d, ignore_errors=True)
