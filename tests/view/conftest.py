"""`tessd view` in real windows: an Xvfb server of the tests' own (24-bit screen, no TCP, found
through `-displayfd`, killed at teardown) and viewers opened on it (killed at teardown)."""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from typing import List

import pytest

from view_util import Viewer


@pytest.fixture(scope="session")
def xvfb():
    """`Xvfb -displayfd`: its DISPLAY (":N"), the server killed at teardown."""
    if not shutil.which("Xvfb"):
        pytest.fail("Xvfb is not installed (scripts/setup.sh installs xvfb, xauth, xdotool)")
    r, w = os.pipe()
    proc = subprocess.Popen(
        ["Xvfb", "-displayfd", str(w), "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
        pass_fds=(w,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(w)
    number = b""
    deadline = time.monotonic() + 20
    with os.fdopen(r, "rb", buffering=0) as f:
        while not number.endswith(b"\n") and time.monotonic() < deadline:
            chunk = f.read(16)
            if not chunk:
                break
            number += chunk
    if not number.strip().isdigit():
        proc.kill()
        proc.wait()
        pytest.fail(f"Xvfb did not say its display number (got {number!r})")
    try:
        yield f":{int(number)}"
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture
def viewer(xvfb):
    """Opens viewers on the test's Xvfb; every one is killed at teardown if still running."""
    opened: List[Viewer] = []

    def open_(args, cwd=None) -> Viewer:
        v = Viewer(xvfb, args, cwd)
        opened.append(v)
        v.focus()
        return v

    yield open_
    for v in opened:
        v.close()
