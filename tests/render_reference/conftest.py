"""tests/render_reference runs in the CAD venv (.venv-cad: cadquery 2.8, OCP 7.9, embreex, trimesh;
scripts/test.sh). The root conftest puts python/ and tests/ on sys.path; this one adds this folder
(reference.py: the reference path and the parts cache), gives the runner of the real
`tessd render` (tests/locate.py: $TESSD_BIN, else target/release/tessd), and prints the figures the
tests collected (reference.FIGURES) at the end, also without -s."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import locate  # noqa: E402
import reference as R  # noqa: E402


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    FIGURES = R.FIGURES
    if not FIGURES:
        return
    tr = terminalreporter
    tr.section("render reference figures (tessd vs OCP BRepMesh 1e-3 + Embree)")
    for name, line in FIGURES:
        tr.write_line(f"{name}: {line}")


class RenderError(AssertionError):
    pass


@dataclass
class Rendered:
    report: Dict[str, Any]
    ids: np.ndarray  # [H, W], −1 background
    seconds: float


@pytest.fixture(scope="session")
def tessd_render(tmp_path_factory):
    """`tessd render DOC OUT.png <camera> --face-ids IDS.png --json [--cracks C] [--raycast]`:
    the JSON report and the decoded face ids. A refusal raises RenderError with tessd's message."""
    binary = str(locate.tessd_bin())
    out = tmp_path_factory.mktemp("renders")
    counter = [0]

    def run(doc_path: Path, camera: R.Camera, cracks: Optional[str] = None,
            raycast: bool = False) -> Rendered:
        counter[0] += 1
        png = out / f"r{counter[0]}.png"
        ids_png = out / f"r{counter[0]}_ids.png"
        cmd = [binary, "render", str(doc_path), str(png), *camera.args(),
               "--face-ids", str(ids_png), "--json"]
        if cracks is not None:
            cmd += ["--cracks", cracks]
        if raycast:
            cmd.append("--raycast")
        t = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        dt = time.perf_counter() - t
        if p.returncode != 0:
            err = "\n".join(l for l in p.stderr.splitlines() if "XDG_RUNTIME_DIR" not in l)
            raise RenderError(f"tessd render failed (rc {p.returncode}): {err.strip()}\n"
                              f"command: {' '.join(cmd)}")
        report = json.loads(p.stdout)
        ids = R.read_face_ids(ids_png)
        assert ids.shape == (camera.height, camera.width), ids.shape
        assert report["pixels"] == camera.width * camera.height
        assert report["covered"] == int((ids >= 0).sum()), "report's `covered` != the face-id PNG's"
        return Rendered(report, ids, dt)

    return run
