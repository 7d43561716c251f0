"""A headless machine (ssh, cron, CI, render nodes: no `XDG_RUNTIME_DIR`, no display): a
successful GPU command prints no line starting with `error` (issue 32, point 5). The noise came
from Mesa's device-selection layer (an implicit Vulkan layer of mesa-vulkan-drivers), which saw
wgpu enable `VK_KHR_wayland_surface` and tried to reach a Wayland compositor; tessd's instance
now leaves the window-system extensions out (core/gpu/src/context.rs)."""

from __future__ import annotations

import os
import subprocess

import numpy as np
from locate import tessd_bin
from png_decode import read_png


def headless_env():
    """This environment without a session: no XDG_RUNTIME_DIR, no Wayland or X display."""
    drop = {"XDG_RUNTIME_DIR", "WAYLAND_DISPLAY", "WAYLAND_SOCKET", "DISPLAY"}
    return {k: v for k, v in os.environ.items() if k not in drop}


def error_lines(text):
    return [line for line in text.splitlines() if line.lower().startswith("error")]


def test_render_without_a_session_prints_no_error(tmp_path, shared_data):
    png = tmp_path / "spot.png"
    run = subprocess.run([str(tessd_bin()), "render", str(shared_data / "mesh/spot_triangulated.obj"),
                          str(png), "--size", "320x240"],
                         capture_output=True, text=True, timeout=300, env=headless_env())
    assert run.returncode == 0, run.stderr
    assert error_lines(run.stderr) == [] and error_lines(run.stdout) == [], run.stderr
    rgba = read_png(png)
    assert rgba.shape == (240, 320, 4)
    assert int(np.any(rgba[..., :3] != (224, 224, 224), axis=-1).sum()) > 2000


def test_gpu_subdivision_without_a_session_prints_no_error(tmp_path, shared_data):
    out = tmp_path / "smooth.obj"
    run = subprocess.run([str(tessd_bin()), "subdivide", str(shared_data / "mesh/spot_control_mesh.obj"),
                          str(out), "--levels", "2", "--gpu"],
                         capture_output=True, text=True, timeout=300, env=headless_env())
    assert run.returncode == 0, run.stderr
    assert error_lines(run.stderr) == [] and error_lines(run.stdout) == [], run.stderr
    faces = sum(1 for line in out.read_text().splitlines() if line.startswith("f "))
    assert faces == 732 * 4  # Catmull-Clark level 2: a quad per cage corner, then four each
