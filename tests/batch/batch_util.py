"""Helpers of the tessd.batch tests: usd-core in a subprocess, file listings, PNG headers."""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from pathlib import Path
from typing import Dict, Tuple

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent


def pxr_python() -> str:
    """A Python with usd-core: this one if it has pxr, else the tests' .venv."""
    try:
        import pxr  # noqa: F401

        return sys.executable
    except ImportError:
        pass
    venv = REPO / ".venv" / "bin" / "python"
    assert venv.exists(), "no Python with usd-core (pxr): run scripts/setup.sh (.venv)"
    return str(venv)


def usd_check(outdir) -> dict:
    """tests/batch/usd_check.py on ``outdir``, run with usd-core; its JSON."""
    proc = subprocess.run([pxr_python(), str(HERE / "usd_check.py"), str(outdir)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return json.loads(proc.stdout)


def files_with_mtimes(outdir) -> Dict[str, Tuple[int, int]]:
    """Every file under ``outdir`` but the summaries: relative path -> (mtime_ns, size)."""
    out = {}
    for root, _, files in os.walk(outdir):
        for f in files:
            p = os.path.join(root, f)
            rel = os.path.relpath(p, outdir)
            if rel in ("summary.csv", "summary.json"):
                continue
            st = os.stat(p)
            out[rel] = (st.st_mtime_ns, st.st_size)
    return out


def png_size(path) -> Tuple[int, int]:
    """(width, height) from a PNG's IHDR; fails on anything that is not a whole PNG."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    assert data[12:16] == b"IHDR", path
    assert data[-12:-4] == b"\x00\x00\x00\x00IEND", "%s: no IEND chunk at the end (truncated)" % path
    return struct.unpack(">II", data[16:24])
