"""Real Blender (the PyPI `bpy` module, pinned in python/requirements-test.txt) with the
tessd extension installed from its built zip, as Blender installs it
(`extensions.package_install_files` into a local repository), and a real daemon.

BLENDER_USER_RESOURCES points at a temporary folder before `bpy` is first imported (this
folder sorts before the other test folders, so its conftest runs first), so the tests never
touch the user's Blender configuration.
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

_USER_RESOURCES = tempfile.mkdtemp(prefix="tessd-blender-user-")
os.environ.setdefault("BLENDER_USER_RESOURCES", _USER_RESOURCES)
atexit.register(shutil.rmtree, _USER_RESOURCES, True)

from addon_env import REPO, install_addon, uninstall_addon  # noqa: E402


@pytest.fixture(scope="session")
def addon_zip(tmp_path_factory):
    """The extension built by `python blender_addon/build.py` for this platform, bundling
    target/release/tessd (validated by Blender's tool): (zip path, build log)."""
    out = tmp_path_factory.mktemp("dist")
    proc = subprocess.run([sys.executable, str(REPO / "blender_addon" / "build.py"), "--out", str(out)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.returncode == 0, proc.stdout
    zips = list(out.glob("tessd-*.zip"))
    assert len(zips) == 1, proc.stdout
    return zips[0], proc.stdout


@pytest.fixture(scope="module")
def addon(addon_zip, daemon, tmp_path_factory):
    """The installed add-on, talking to the module's daemon (no auto-start)."""
    mod = install_addon(addon_zip[0], tmp_path_factory.mktemp("repo"), daemon.socket)
    try:
        yield mod
    finally:
        uninstall_addon()
