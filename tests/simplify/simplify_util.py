"""Helpers of the simplification tests: the shared meshes and running the tessd CLI."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict, List

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(REPO / "tests"))

import locate  # noqa: E402


def shared_meshes() -> List[Path]:
    """Every mesh of the shared data set (fails when the folder is missing)."""
    folder = locate.shared_data() / "mesh"
    assert folder.is_dir(), f"shared test data not found at {folder} (set TESSD_SHARED_DATA)"
    meshes = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".obj", ".ply", ".off", ".stl"))
    assert meshes, folder
    return meshes


def tessd(*args: Any, check: bool = True, timeout: float = 300) -> subprocess.CompletedProcess:
    """Runs the tessd binary; with `check`, fails the test (showing stderr) on a non-zero exit."""
    run = subprocess.run([str(locate.tessd_bin()), *map(str, args)], capture_output=True, text=True,
                         timeout=timeout)
    if check:
        assert run.returncode == 0, f"tessd {' '.join(map(str, args))}:\n{run.stderr}"
    return run


def tessd_json(*args: Any) -> Dict[str, Any]:
    """Runs a tessd verb with `--json` and returns the parsed result."""
    return json.loads(tessd(*args, "--json").stdout)


def stats(path: Path) -> Dict[str, Any]:
    """`tessd stats --json` of a file (a re-read with tessd's own readers and validation)."""
    return json.loads(tessd("stats", "--json", path).stdout)
