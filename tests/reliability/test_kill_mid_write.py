"""The daemon SIGKILLed while it writes a large output (issue 18, part 2): the destination holds
the previous file, byte for byte, or nothing when there was none (or, when the kill came after
the rename, the complete new file), never a partial one. The killed writer's temporary file
stays beside it (nothing runs in a SIGKILLed process), and the next write into that folder, by
the next daemon, removes it (tessd_mesh::io::TempOutput sweeps temporary files whose writer's
pid is gone and that nobody holds locked).

Each format is killed at fixed points of its write, the temporary file's size reaching 0 %,
10 %, ... 95 % of the complete output's, and at random moments after the request was sent.
The watcher runs at real-time priority. A fixed point is first tried with the daemon running
(the kill may land inside one large write(2), which the kernel then cuts short); when the
watcher misses the point before the write completes, it is tried again, in turn with the
daemon stepped by SIGSTOP / SIGCONT once its temporary file exists (so that the kill lands at
the state seen) and running. Every kill is followed by a fresh `tessd serve`
on the same socket (the kill leaves the socket file behind, so each restart is also a
stale-socket takeover).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import random
import signal
import time
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import pytest

import tessd
from daemon_util import TEMP_NAME, DaemonProcess, RawConn, tessd_temps
from tessd.frame import encode_frame_bytes

#: Kill points: the temporary file's size as a fraction of the complete output's.
FRACTIONS = (0.0, 0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 0.95)
#: Kills at a random moment after the request was sent.
RANDOM_KILLS = 3


def grid_mesh(n: int) -> Dict[str, np.ndarray]:
    """An n x n grid of quads as mesh arrays (a wavy sheet)."""
    ys, xs = np.mgrid[0:n, 0:n].astype(np.float32)
    positions = np.stack([xs.ravel(), ys.ravel(), np.sin(xs.ravel() * 0.1)], 1).astype(np.float32)
    i = np.arange((n - 1) * (n - 1))
    a = ((i // (n - 1)) * n + i % (n - 1)).astype(np.uint32)
    quads = np.stack([a, a + 1, a + 1 + n, a + n], 1).astype(np.uint32)
    return {"positions": positions, "face_indices": quads}


def usd_request(mesh_dir, dest) -> Tuple[str, Dict[str, Any], Any]:
    """A 16 MB `.usda`: suzanne subdivided 4 times (~126 k quads)."""
    return "subdivide", {"input": str(mesh_dir / "suzanne.obj"), "levels": 4,
                         "output": dest}, None


def ply_request(mesh_dir, dest) -> Tuple[str, Dict[str, Any], Any]:
    """A 14 MB binary `.ply` from a 700 x 700 grid sent as arrays (13.7 MB of payload)."""
    return "mesh.convert", {"output": dest}, grid_mesh(700)


def png_request(mesh_dir, dest) -> Tuple[str, Dict[str, Any], Any]:
    """A 1.5 MB PNG: suzanne rendered at 3072 x 3072."""
    return "render", {"input": str(mesh_dir / "suzanne.obj"), "size": "3072x3072",
                      "output": dest}, None


FORMATS = {"usda": usd_request, "ply": ply_request, "png": png_request}


def digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def read_or_none(path: str) -> Optional[bytes]:
    try:
        with open(path, "rb") as f:
            return f.read()
    except FileNotFoundError:
        return None


def pid_of(temp_name: str) -> int:
    return int(TEMP_NAME.match(temp_name).group(1))


@contextlib.contextmanager
def high_priority():
    """Runs the calling thread under the real-time FIFO policy (Linux: 0 names the calling
    thread; the tests run as root), so that neither other load on the machine nor the daemon's
    threads it wakes can hold the watcher off; at nice -15 where real time is not allowed. The
    watcher's loops are bounded by their deadlines."""
    before_nice = os.getpriority(os.PRIO_PROCESS, 0)
    os.setpriority(os.PRIO_PROCESS, 0, -15)
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
        realtime = True
    except PermissionError:
        realtime = False
    try:
        yield
    finally:
        if realtime:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        os.setpriority(os.PRIO_PROCESS, 0, before_nice)


def all_stopped(pid: int) -> bool:
    """Whether every thread of process `pid` is stopped (state T), as SIGSTOP leaves them
    once each has left the kernel."""
    try:
        tids = os.listdir("/proc/%d/task" % pid)
    except OSError:
        return True
    for tid in tids:
        try:
            with open("/proc/%d/task/%s/stat" % (pid, tid)) as f:
                state = f.read().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue  # the thread ended meanwhile
        if state not in ("T", "t", "Z", "X"):
            return False
    return True


def stop(pid: int) -> None:
    """SIGSTOPs process `pid` and waits until every thread has stopped."""
    os.kill(pid, signal.SIGSTOP)
    deadline = time.monotonic() + 10
    while not all_stopped(pid):
        assert time.monotonic() < deadline, "the daemon does not stop"


def kill_at_size(pid: int, dest: str, full_size: int, target: int, older: List[str],
                 step: bool, timeout: float = 30.0) -> Tuple[Optional[int], bool]:
    """Watches the folder of `dest` until process `pid`'s temporary file holds `target` bytes
    or more, then SIGKILLs it. Returns (the size it was killed at, whether older temporary
    files were there when the write began); the size is None when the write completed first
    (`dest` got the complete output's `full_size` bytes between two looks; the process is
    left running).

    The folder is watched in a busy loop at a high priority. Without `step`, the temporary
    file's size is then watched while the daemon runs, and the SIGKILL lands wherever the
    daemon is, even inside one large write(2) (the kernel stops the copy at the next page).
    With `step` the daemon is run in short steps once its temporary file exists (SIGCONT,
    then SIGSTOP and a wait until every thread has stopped), its size looked at while it is
    stopped, so that the SIGKILL lands at exactly the state seen.
    """
    deadline = time.monotonic() + timeout
    folder = os.path.dirname(dest)
    temp = None
    swept = False
    with high_priority():
        while temp is None:
            names = [n for n in os.listdir(folder) if TEMP_NAME.match(n)]
            mine = [n for n in names if pid_of(n) == pid]
            if mine:
                if step:
                    stop(pid)
                # This write began: its daemon removed its killed predecessors' temporary
                # files before creating its own.
                leftovers = [n for n in names if pid_of(n) != pid]
                if leftovers:
                    if step:
                        os.kill(pid, signal.SIGCONT)
                    raise AssertionError(f"the new daemon's write did not remove {leftovers}")
                swept = bool(older)
                temp = os.path.join(folder, mine[0])
            else:
                with contextlib.suppress(FileNotFoundError):
                    if os.stat(dest).st_size == full_size:
                        return None, False
                assert time.monotonic() < deadline, "no temporary file appeared"
        while True:
            try:
                size = os.stat(temp).st_size
            except FileNotFoundError:
                if step:
                    os.kill(pid, signal.SIGCONT)
                return None, swept
            if size >= target:
                os.kill(pid, signal.SIGKILL)
                return size, swept
            if step:
                os.kill(pid, signal.SIGCONT)
                stop(pid)


@pytest.mark.parametrize("ext", sorted(FORMATS))
def test_sigkill_mid_write_leaves_previous_file_or_nothing(ext, tessd_bin, mesh_dir,
                                                          tmpdir_short):
    rng = random.Random(18)
    out_dir = os.path.join(tmpdir_short, "out")
    os.mkdir(out_dir)
    dest = os.path.join(out_dir, "asset." + ext)
    sock = os.path.join(tmpdir_short, "k.sock")
    op, params, arrays = FORMATS[ext](mesh_dir, dest)

    daemon = DaemonProcess(tessd_bin, sock).start()
    try:
        # The complete output, and how long the request takes.
        t0 = time.monotonic()
        with tessd.Client(sock, timeout=60) as c:
            c.call(op, params, arrays)
        full_time = time.monotonic() - t0
        full = read_or_none(dest)
        assert full is not None and len(full) > 1 << 20, "the output is too small to kill mid-write"
        full_digest = digest(full)
        os.unlink(dest)
        frame = encode_frame_bytes({"id": 1, "op": op, "params": params}, arrays)

        plan: List[Optional[float]] = list(FRACTIONS) + [None] * RANDOM_KILLS
        outcomes: List[str] = []
        mid_write = 0      # fixed kill points that left a partial temporary file
        swept_checks = 0   # writes that began with a killed predecessor's temporary file there
        missed = 0         # writes that completed between two looks (that point is tried again)
        missed_here = 0
        k = 0
        while k < len(plan):
            fraction = plan[k]
            previous: Optional[bytes] = None
            if k % 2 == 0:
                previous = b"previous version %d\n" % k + os.urandom(4096)
                with open(dest, "wb") as f:
                    f.write(previous)
            elif os.path.exists(dest):
                os.unlink(dest)
            older = tessd_temps(out_dir)  # left by the daemons killed before

            # A plain socket (no reader thread in this process: the watcher must not wait for
            # Python's GIL while the daemon writes).
            client = RawConn(sock, timeout=60)
            client.send(frame)
            pid = daemon.pid
            if fraction is not None:
                # Tries at a point kill the running daemon and the stepped one in turn.
                seen, swept = kill_at_size(pid, dest, len(full), int(fraction * len(full)), older,
                                           step=missed_here % 2 == 1)
                swept_checks += swept
                if seen is None:
                    assert client.final(1)["type"] == "ok"
                    client.close()
                    assert digest(read_or_none(dest)) == full_digest
                    missed += 1
                    missed_here += 1
                    assert missed_here <= 8, f"the {fraction:.0%} point was never caught mid-write"
                    continue
                missed_here = 0
            else:
                time.sleep(rng.uniform(0.0, 1.2 * full_time))
                os.kill(pid, signal.SIGKILL)
            daemon.proc.wait(10)
            client.close()

            after = read_or_none(dest)
            left = [n for n in tessd_temps(out_dir) if pid_of(n) == pid]
            if after is None:
                assert previous is None, f"kill {k}: the previous file was removed"
                state = "nothing"
            elif previous is not None and after == previous:
                state = "previous"
            else:
                assert digest(after) == full_digest, (
                    f"kill {k}: {dest} holds {len(after)} bytes that are neither the previous "
                    f"file nor the complete output ({len(full)} bytes)")
                state = "complete"
            sizes = [os.path.getsize(os.path.join(out_dir, n)) for n in left]
            assert all(s <= len(full) for s in sizes), sizes
            if left and fraction is not None:
                mid_write += 1
            label = "random" if fraction is None else f"{fraction:.0%}"
            outcomes.append(f"{label}:{state}" + (f"+temp({sizes[0]})" if left else ""))
            daemon = DaemonProcess(tessd_bin, sock).start()
            k += 1

        # The next complete write replaces whatever is there and leaves no temporary file.
        with tessd.Client(sock, timeout=60) as c:
            c.call(op, params, arrays)
        assert digest(read_or_none(dest)) == full_digest
        assert sorted(os.listdir(out_dir)) == ["asset." + ext], sorted(os.listdir(out_dir))
        # The fixed kill points landed while the temporary file was being written (the last
        # one may land just after the rename on a loaded machine).
        assert mid_write >= len(FRACTIONS) - 1, outcomes
        assert swept_checks >= len(FRACTIONS) - 2, (swept_checks, outcomes)
        print(f"\n{ext}: {len(plan)} kills, {mid_write} of them at fixed points mid-write "
              f"(output {len(full)} bytes; {missed} points passed between two looks, tried "
              f"again): 0 partial files; a killed writer's temporary file removed by the next "
              f"write {swept_checks} times, none left at the end; {outcomes}")
    finally:
        daemon.stop()
