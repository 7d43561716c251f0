"""A full disk (issue 18, part 2): outputs written onto a real, small tmpfs (mounted by the
test; it runs as root) fail with a clear `io` error naming the destination, and leave nothing
behind: no partial output, no temporary file, and the space they took is free again.
"""

from __future__ import annotations

import os
import subprocess

import numpy as np
import pytest

import tessd
from daemon_util import DaemonProcess, read_obj

#: Bytes left free on the tmpfs: every output below needs more.
FREE = 16 << 10


def grid(n: int):
    ys, xs = np.mgrid[0:n, 0:n].astype(np.float32)
    positions = np.stack([xs.ravel(), ys.ravel(), np.zeros(n * n, np.float32)], 1)
    i = np.arange((n - 1) * (n - 1))
    a = ((i // (n - 1)) * n + i % (n - 1)).astype(np.uint32)
    return {"positions": positions.astype(np.float32),
            "face_indices": np.stack([a, a + 1, a + 1 + n, a + n], 1).astype(np.uint32)}


#: (name, op, params, arrays) for each kind of output; `{out}` is the destination.
OUTPUTS = [
    ("ply", "mesh.convert", {}, grid(100)),                       # ~280 KB
    ("obj", "simplify", {"input": "bun_zipper.ply", "method": "grid", "cells": 40}, None),
    ("usda", "subdivide", {"input": "suzanne.obj", "levels": 2}, None),  # ~500 KB
    ("png", "render", {"input": "suzanne.obj", "size": "1024x1024"}, None),  # ~230 KB
    ("tsc", "codec.compress", {"input": "bun_zipper.ply"}, None),  # ~110 KB
]


@pytest.fixture
def small_disk(tmpdir_short):
    """A 1 MiB tmpfs, filled but for FREE bytes by `filler.bin`; unmounted afterwards."""
    mnt = os.path.join(tmpdir_short, "disk")
    os.mkdir(mnt)
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m,mode=0755", "tmpfs", mnt],
                   check=True, capture_output=True)
    try:
        st = os.statvfs(mnt)
        with open(os.path.join(mnt, "filler.bin"), "wb") as f:
            f.write(b"\xff" * (st.f_bavail * st.f_frsize - FREE))
        yield mnt
    finally:
        subprocess.run(["umount", mnt], check=True, capture_output=True)


def free_bytes(path: str) -> int:
    st = os.statvfs(path)
    return st.f_bavail * st.f_frsize


def test_full_disk_gives_an_io_error_naming_the_file_and_leaves_nothing(
        tessd_bin, mesh_dir, tmpdir_short, small_disk):
    free = free_bytes(small_disk)
    assert free <= FREE, free
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "d.sock")).start()
    try:
        with tessd.Client(d.socket, timeout=60) as c:
            for ext, op, params, arrays in OUTPUTS:
                dest = os.path.join(small_disk, "out." + ext)
                params = dict(params, output=dest)
                if "input" in params:
                    params["input"] = str(mesh_dir / params["input"])
                with pytest.raises(tessd.TessdError) as info:
                    c.call(op, params, arrays)
                e = info.value
                assert e.code == "io", (ext, e.code, e.message)
                assert dest in e.message and "No space left on device" in e.message, (
                    ext, e.message)
                assert sorted(os.listdir(small_disk)) == ["filler.bin"], (ext, os.listdir(small_disk))
                assert free_bytes(small_disk) == free, ext
                print(f"\n{ext}: {e.code}: {e.message}")
            # The daemon serves on, and a file that fits is written there.
            assert c.ping("full") == "full"
            tiny = {"positions": np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32),
                    "face_indices": np.array([[0, 1, 2]], np.uint32)}
            dest = os.path.join(small_disk, "tiny.obj")
            c.call("mesh.convert", {"output": dest}, tiny)
            assert read_obj(dest)[1] == [[0, 1, 2]]
            assert sorted(os.listdir(small_disk)) == ["filler.bin", "tiny.obj"]
    finally:
        d.stop()
