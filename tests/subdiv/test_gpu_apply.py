"""The `subdivide` op's GPU apply phase (wgpu compute; lavapipe in CI, so it runs, not skips)
gives the CPU's numbers within 1e-5 relative, with the same topology, and names its adapter."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "daemon"))

import locate  # noqa: E402
import tessd  # noqa: E402



def run(daemon, path, levels, gpu, boundary="edge-only"):
    params = {"input": str(path), "levels": levels, "gpu": gpu, "boundary": boundary}
    with tessd.Client(daemon.socket, timeout=300) as c:
        result, arrays = c.call("subdivide", params)
    return result, arrays


@pytest.mark.parametrize(
    "name,levels,boundary",
    [
        ("spot_control_mesh.obj", 4, "edge-only"),
        ("suzanne.obj", 3, "edge-and-corner"),
        ("quadknot.obj", 2, "edge-only"),
    ],
)
def test_gpu_equals_cpu(daemon, name, levels, boundary):
    path = locate.shared_data() / "mesh" / name
    cpu_result, cpu = run(daemon, path, levels, False, boundary)
    gpu_result, gpu = run(daemon, path, levels, True, boundary)
    assert gpu_result["gpu"], "the GPU result names no adapter"
    assert cpu_result["gpu"] is None
    print("%s level %d on %s: apply %.1f ms (CPU %.1f ms)" % (
        name, levels, gpu_result["gpu"], gpu_result["apply_ms"], cpu_result["apply_ms"]))
    np.testing.assert_array_equal(cpu["face_indices"], gpu["face_indices"])
    np.testing.assert_array_equal(cpu["face_sizes"], gpu["face_sizes"])
    a, b = np.asarray(cpu["positions"]), np.asarray(gpu["positions"])
    assert a.shape == b.shape and a.shape[0] == cpu_result["vertices"]
    scale = float(np.abs(a).max())
    err = float(np.abs(a - b).max())
    assert err <= 1e-5 * scale, "GPU differs from CPU by %g (scale %g)" % (err, scale)
