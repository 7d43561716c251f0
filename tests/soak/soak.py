"""Soak test: one real daemon, CLIENTS clients issuing a random mix of every operation, with
valid and invalid inputs, random cancels and dropped connections, for SECONDS.

Pass criteria (issue 18, printed as one JSON line and as the exit status):
  * 0 failures: every reply is the expected one (a result for a valid request, the expected
    error code for an invalid one, `cancelled` or a result for a cancelled one), and the daemon
    never dies or drops a well-behaved connection;
  * the daemon's resident set at the end, once idle, is within 10 % of its resident set after
    the warm-up, once idle;
  * its thread count and open file descriptors at the end, once idle, equal those after the
    warm-up (no leaked connection or job threads, no leaked files);
  * no temporary file is left in the output folder (outputs are written beside their
    destination and renamed: a `.tmp` sibling left behind would be a leak).

    python tests/soak/soak.py [--seconds 600] [--clients 32] [--warmup 20] [--seed 1]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import re
import sys
import threading
import time
import traceback
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(REPO / "tests" / "daemon"))

import locate  # noqa: E402
import tessd  # noqa: E402
from daemon_util import DaemonProcess, short_tmpdir  # noqa: E402
from tessd import TessdError  # noqa: E402


def proc_status(pid: int) -> dict:
    """VmRSS (KiB), threads and open descriptors of a process, from /proc."""
    status = Path(f"/proc/{pid}/status").read_text()
    rss = next(int(line.split()[1]) for line in status.splitlines() if line.startswith("VmRSS:"))
    return {
        "rss_kib": rss,
        "threads": len(os.listdir(f"/proc/{pid}/task")),
        "fds": len(os.listdir(f"/proc/{pid}/fd")),
    }


def grid_arrays(n: int, z: float = 0.0) -> dict:
    """An n × n vertex grid as mesh arrays (2 (n − 1)² triangles)."""
    xs, ys = np.meshgrid(np.arange(n, dtype=np.float32), np.arange(n, dtype=np.float32))
    positions = np.stack([xs.ravel(), ys.ravel(), np.full(n * n, z, np.float32)], axis=1)
    i = np.arange(n - 1)
    a = (i[None, :] + n * i[:, None]).ravel().astype(np.uint32)
    faces = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)])
    return tessd.mesh_to_arrays(positions, faces.astype(np.uint32))


class Mix:
    """The requests: (op, params, arrays, expected) with expected "ok" or a set of error codes."""

    def __init__(self, data: Path, out: Path, tsc: Path, bad_tsc: Path):
        self.mesh = data / "mesh"
        self.brep = data / "brep"
        self.out = out
        self.tsc = tsc
        self.bad_tsc = bad_tsc
        nan = grid_arrays(6)
        pos = np.array(nan["positions"], copy=True)
        pos[7, 1] = np.nan
        nan["positions"] = pos
        self.nan = nan
        oob = grid_arrays(6)
        idx = np.array(oob["face_indices"], copy=True)
        idx[5, 2] = 10_000
        oob["face_indices"] = idx
        self.oob = oob

    def out_path(self, rng: random.Random, ext: str) -> str:
        # a few names only: concurrent writers replace each other's files, atomically
        return str(self.out / f"o{rng.randrange(6)}{ext}")

    def pick(self, rng: random.Random):
        spot = str(self.mesh / "spot_triangulated.obj")
        cube = str(Path(self.mesh).parent / "subdiv" / "catmark_cube_level0.obj")
        r = rng.randrange(28)
        if r == 25:
            return "debug.echo", {"n": rng.random()}, grid_arrays(rng.randrange(2, 50)), "ok"
        if r == 26:
            return rng.choice(["session.hold", "session.release"]), {"host": "soak", "pid": os.getpid()}, None, "ok"
        if r == 27:
            return "codec.compress", {"input": spot, "output": self.out_path(rng, ".tsc"), "bits": 99}, None, \
                {"invalid_request"}
        if r == 0:
            return "ping", {"echo": rng.random()}, None, "ok"
        if r == 1:
            return "hello", {}, None, "ok"
        if r == 2:
            return "mesh.stats", {"input": spot}, None, "ok"
        if r == 3:
            return "mesh.stats", None, self.nan, {"invalid_mesh"}
        if r == 4:
            return "mesh.stats", None, self.oob, {"invalid_mesh"}
        if r == 5:
            return "mesh.stats", {"input": str(self.out / "missing.obj")}, None, {"io"}
        if r == 6:
            ext = rng.choice([".ply", ".obj", ".usda", ".stl", ".off"])
            return "mesh.convert", {"input": spot, "output": self.out_path(rng, ext)}, None, "ok"
        if r == 7:
            return "mesh.convert", {"input": spot, "output": str(self.out / "x.xyz")}, None, {"unsupported"}
        if r == 8:
            return "simplify", {"method": "grid", "cells": rng.randrange(4, 40)}, grid_arrays(30), "ok"
        if r == 9:
            return "simplify", {"input": spot, "method": "quality", "max_error": "0.5%",
                                "output": self.out_path(rng, ".ply")}, None, "ok"
        if r == 10:
            return "simplify", {"input": spot, "method": "bogus"}, None, {"invalid_request"}
        if r == 11:
            return "lod", {"input": spot, "levels": "50%,20%", "output": self.out_path(rng, ".usda")}, None, "ok"
        if r == 12:
            return "subdivide", {"input": cube, "levels": rng.randrange(1, 4)}, None, "ok"
        if r == 13:
            return "subdivide", {"input": cube, "levels": 1000}, None, {"invalid_request", "too_large"}
        if r == 14:
            name = rng.choice(["face2.brep", "shell1.brep", "bottle.brep"])
            return "tessellate", {"input": str(self.brep / name), "tolerance": "0.5%"}, None, "ok"
        if r == 15:
            return "tessellate", {"brep": {"format": "tessd-brep", "faces": "nope"}}, None, \
                {"invalid_brep", "invalid_request"}
        if r == 16:
            return "brep.load", {"input": str(self.brep / "missing.json")}, None, {"io"}
        if r == 17:
            uv = np.array([[[0.5, 0.5], [0.1, 0.9]]], dtype=np.float64)
            return "trim.classify", {"input": str(self.brep / "face2.brep"), "faces": [1], "tolerance": 1e-3}, \
                {"uv": uv}, "ok"
        if r == 18:
            return "render", {"input": spot, "size": "64x48", "output": self.out_path(rng, ".png")}, None, "ok"
        if r == 19:
            return "render", {"input": spot, "size": "0x48"}, None, {"invalid_request"}
        if r == 20:
            return "codec.compress", {"input": spot, "output": self.out_path(rng, ".tsc"),
                                      "bits": rng.choice([10, 12])}, None, "ok"
        if r == 21:
            return "codec.decompress", {"input": str(self.tsc), "max_bits": rng.randrange(3, 13)}, None, "ok"
        if r == 22:
            return "codec.view", {"input": str(self.tsc), "eye": [0, 0.5, 3 + 10 * rng.random()],
                                  "target": [0, 0.5, 0], "up": [0, 1, 0], "size": "320x240"}, None, "ok"
        if r == 23:
            return "codec.decompress", {"input": str(self.bad_tsc)}, None, {"invalid_mesh"}
        return "compare", {"a": spot, "b": str(self.mesh / "spot_quadrangulated.obj")}, None, "ok"


class Stats:
    def __init__(self):
        self.lock = threading.Lock()
        self.counts: dict = {}
        self.failures: list = []

    def count(self, key: str):
        with self.lock:
            self.counts[key] = self.counts.get(key, 0) + 1

    def fail(self, what: str):
        with self.lock:
            self.failures.append(what)


def client_loop(socket: str, mix: Mix, seed: int, deadline: float, stats: Stats):
    rng = random.Random(seed)
    client = tessd.Client(socket, timeout=60)
    try:
        while time.time() < deadline:
            op, params, arrays, expected = mix.pick(rng)
            roll = rng.random()
            try:
                if roll < 0.05:
                    # a client that goes away mid-request: the daemon must cancel and serve on
                    client.submit("debug.sleep", {"seconds": 2, "steps": 200})
                    time.sleep(rng.random() * 0.05)
                    client.close()
                    client = tessd.Client(socket, timeout=60)
                    stats.count("dropped connection")
                    continue
                if roll < 0.20:
                    # cancelled at a random moment: a result or `cancelled`, nothing else
                    if rng.random() < 0.3:
                        op, params, arrays, expected = "debug.sleep", {"seconds": 1, "steps": 100}, None, "ok"
                    job = client.submit(op, params, arrays)
                    time.sleep(rng.random() * 0.02)
                    job.cancel()
                    try:
                        job.result(timeout=120)
                        ok = expected == "ok"
                        stats.count(f"{op} ok (cancel came late)" if ok else f"{op} ok?!")
                        if not ok:
                            stats.fail(f"{op} {params}: succeeded, expected {expected}")
                    except TessdError as e:
                        if e.code == "cancelled" or (expected != "ok" and e.code in expected):
                            stats.count(f"{op} {e.code}")
                        else:
                            stats.fail(f"{op} {params}: cancelled job answered {e.code}: {e.message}")
                    continue
                client.call(op, params, arrays, timeout=120)
                if expected == "ok":
                    stats.count(f"{op} ok")
                else:
                    stats.fail(f"{op} {params}: succeeded, expected {sorted(expected)}")
            except TessdError as e:
                if expected != "ok" and e.code in expected:
                    stats.count(f"{op} {e.code}")
                else:
                    stats.fail(f"{op} {params}: {e.code}: {e.message}")
            except Exception as e:  # noqa: BLE001 — every other exception is a failure
                stats.fail(f"{op} {params}: {type(e).__name__}: {e}")
                client.close()
                client = tessd.Client(socket, timeout=60)
    finally:
        client.close()


def run_phase(socket, mix, clients, seconds, seed, stats):
    deadline = time.time() + seconds
    threads = [threading.Thread(target=client_loop, args=(socket, mix, seed * 1000 + i, deadline, stats))
               for i in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


def idle(daemon: DaemonProcess, settle: float = 2.0) -> dict:
    """The daemon's figures once every job has ended (threads stop shortly after replying)."""
    time.sleep(settle)
    best = proc_status(daemon.pid)
    for _ in range(20):
        time.sleep(0.25)
        s = proc_status(daemon.pid)
        if s["threads"] <= best["threads"] and s["fds"] <= best["fds"]:
            best = s
    return best


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=600)
    ap.add_argument("--clients", type=int, default=32)
    ap.add_argument("--warmup", type=float, default=None, help="default: 10 %% of --seconds, at least 10 s")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    warmup = a.warmup if a.warmup is not None else max(10.0, 0.1 * a.seconds)
    data = locate.shared_data()
    binary = str(locate.tessd_bin())
    with short_tmpdir() as d:
        out = Path(d) / "out"
        out.mkdir()
        tsc = Path(d) / "spot.tsc"
        bad = Path(d) / "bad.tsc"
        daemon = DaemonProcess(binary, os.path.join(d, "s.sock"))
        daemon.start()
        try:
            with tessd.Client(daemon.socket) as c:
                c.call("codec.compress", {"input": str(data / "mesh" / "spot_triangulated.obj"),
                                          "output": str(tsc), "min_cell": 1000})
            bad.write_bytes(tsc.read_bytes()[: tsc.stat().st_size // 2])
            mix = Mix(data, out, tsc, bad)
            stats = Stats()
            t0 = time.time()
            run_phase(daemon.socket, mix, a.clients, warmup, a.seed, stats)
            after_warmup = idle(daemon)
            run_phase(daemon.socket, mix, a.clients, a.seconds - warmup, a.seed + 1, stats)
            alive = daemon.alive()
            at_end = idle(daemon) if alive else {}
            wall = time.time() - t0
            # the outputs are o0…o5 with the mix's extensions; anything else was left behind
            temps = sorted(p.name for p in out.iterdir()
                           if not re.fullmatch(r"o\d\.(ply|obj|usda|stl|off|png|tsc)", p.name))
        except Exception:  # noqa: BLE001
            traceback.print_exc()
            print(daemon.log_tail())
            return 2
        finally:
            daemon.stop()
    total = sum(stats.counts.values())
    growth = (at_end["rss_kib"] / after_warmup["rss_kib"] - 1.0) if at_end else None
    report = {
        "seconds": round(wall, 1), "clients": a.clients, "requests": total,
        "requests_per_s": round(total / max(wall, 1e-9), 1), "failures": len(stats.failures),
        "daemon_alive": alive, "after_warmup": after_warmup, "at_end": at_end,
        "rss_growth": None if growth is None else round(growth, 4),
        "leaked_temp_files": temps, "by_outcome": dict(sorted(stats.counts.items())),
    }
    checks = {
        "no failures": not stats.failures,
        "daemon alive": alive,
        "RSS within 10 % of after warm-up": growth is not None and abs(growth) <= 0.10,
        "threads back to after warm-up": bool(at_end) and at_end["threads"] <= after_warmup["threads"],
        "descriptors back to after warm-up": bool(at_end) and at_end["fds"] <= after_warmup["fds"],
        "no temp files left": not temps,
    }
    report["checks"] = checks
    for f in stats.failures[:20]:
        print("FAILURE:", f)
    print(json.dumps(report))
    bad_checks = [k for k, v in checks.items() if not v]
    print("soak:", "passed" if not bad_checks else "FAILED: " + ", ".join(bad_checks),
          f"({total} requests in {wall:.0f} s, {a.clients} clients, RSS {after_warmup['rss_kib']} -> "
          f"{at_end.get('rss_kib')} KiB, threads {after_warmup['threads']} -> {at_end.get('threads')})")
    return 0 if not bad_checks else 1


if __name__ == "__main__":
    sys.exit(main())
