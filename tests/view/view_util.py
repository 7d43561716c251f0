"""Helpers of the `tessd view` tests: the viewer run on a display with a timeout, a viewer
process whose stdout lines (`view: ...`, one per change of state) are read on a thread and whose
window gets real key events from `xdotool` (XTEST), face-id PNGs as ids."""

from __future__ import annotations

import json
import os
import queue
import re
import subprocess
import threading
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

import locate
from png_decode import read_png

TIMEOUT = 60


def tessd() -> str:
    """The binary; waits a little when the lead is relinking it."""
    for _ in range(40):
        try:
            p = locate.tessd_bin()
            if p.exists():
                return str(p)
        except FileNotFoundError:
            pass
        time.sleep(0.5)
    return str(locate.tessd_bin())


def view_env(display: Optional[str]) -> Dict[str, str]:
    """The environment with DISPLAY = `display` (unset when None) and no Wayland."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    if display:
        env["DISPLAY"] = display
    return env


def run_view(display: Optional[str], args: Sequence[str], script: Optional[list] = None,
             tmp: Optional[Path] = None, timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    """`tessd view ARGS [--script tmp/script.json]` on `display`, waited for with a timeout."""
    cmd = [tessd(), "view", *map(str, args)]
    if script is not None:
        path = Path(tmp) / f"script_{time.monotonic_ns()}.json"
        path.write_text(json.dumps(script))
        cmd += ["--script", str(path)]
    return subprocess.run(cmd, env=view_env(display), capture_output=True, text=True,
                          timeout=timeout)


def checked(r: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    assert r.returncode == 0, f"status {r.returncode}\n{r.stdout}\n{r.stderr}"
    return r


def run_tessd(*args, timeout: float = TIMEOUT) -> subprocess.CompletedProcess:
    r = subprocess.run([tessd(), *map(str, args)], capture_output=True, text=True,
                       timeout=timeout)
    assert r.returncode == 0, f"tessd {' '.join(map(str, args))}: {r.returncode}\n{r.stderr}"
    return r


def face_ids(path: Path) -> np.ndarray:
    """A face-id PNG as ids: R + 256 G + 65536 B (0 background)."""
    a = read_png(path).astype(np.int64)
    return a[..., 0] + 256 * a[..., 1] + 65536 * a[..., 2]


class Viewer:
    """A `tessd view` process without a script: its stdout lines on a queue, keys by xdotool."""

    def __init__(self, display: str, args: Sequence[str], cwd: Optional[Path] = None):
        self.display = display
        self.proc = subprocess.Popen(
            [tessd(), "view", *map(str, args)], env=view_env(display), cwd=cwd,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1)
        self.lines: "queue.Queue[Optional[str]]" = queue.Queue()
        self.seen: List[str] = []
        self.stderr = ""
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=self._read_err, daemon=True).start()
        self.window = ""

    def focus(self):
        """Finds the window by its title and gives it the keyboard focus."""
        self.window = self.xdotool("search", "--sync", "--name", "tessd view").split()[0]
        self.xdotool("windowfocus", "--sync", self.window)

    def _read(self):
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def _read_err(self):
        self.stderr = self.proc.stderr.read()

    def xdotool(self, *args: str, timeout: float = 20) -> str:
        r = subprocess.run(["xdotool", *args], env=view_env(self.display),
                           capture_output=True, text=True, timeout=timeout)
        assert r.returncode == 0, f"xdotool {' '.join(args)}: {r.returncode} {r.stderr}"
        return r.stdout

    def key(self, *names: str):
        """Real key events (XTEST, to the focused window: no --window)."""
        self.xdotool("key", *names)

    def wait_line(self, pattern: str, timeout: float = 20) -> re.Match:
        """The next stdout line matching `pattern` (lines before it are kept in `seen`)."""
        deadline = time.monotonic() + timeout
        rx = re.compile(pattern)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                break
            if line is None:
                self.lines.put(None)
                break
            self.seen.append(line)
            m = rx.search(line)
            if m:
                return m
        raise AssertionError(f"no line matching {pattern!r} in {timeout} s; lines: {self.seen}; "
                             f"status {self.proc.poll()}; stderr: {self.stderr}")

    def close(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait(timeout=10)
