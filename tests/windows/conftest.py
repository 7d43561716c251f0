"""Checks of what tessd ships for Windows, made on Linux from the cross build (issue 37):
the windows-x64 Blender extension zip and the win_amd64 wheel.

They need the cross-built daemon, named by ``TESSD_WINDOWS_EXE`` (the path of
``<target dir>/x86_64-pc-windows-gnu/release/tessd.exe``, as
``cargo build --release --target x86_64-pc-windows-gnu -p tessd`` leaves it). Without it every
test here fails (never skips): the main pytest run leaves this folder out, and the Windows step
of scripts/test.sh runs it after its Windows build.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def windows_exe() -> Path:
    """The cross-built tessd.exe (``$TESSD_WINDOWS_EXE``); fails when unset or missing."""
    value = os.environ.get("TESSD_WINDOWS_EXE")
    if not value:
        pytest.fail("TESSD_WINDOWS_EXE is not set: point it at the cross-built tessd.exe "
                    "(<target dir>/x86_64-pc-windows-gnu/release/tessd.exe)")
    path = Path(value).resolve()
    if not path.is_file():
        pytest.fail("TESSD_WINDOWS_EXE=%s is not a file (cargo build --release --target "
                    "x86_64-pc-windows-gnu -p tessd)" % value)
    return path
