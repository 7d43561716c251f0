"""Single-node throughput of tessd.batch (issue 16, point 4): the number docs/scale-out.md
extrapolates from. Run by bench/batch/run_batch.sh (the CAD venv: dask + OCP).

For 1 and 2 worker processes (a LocalCluster, one thread each, one shared daemon per node):
(a) the LOD chains (50 %, 20 %, 5 %) of the 12 shared meshes, (b) the tessellation (0.1 % of
the bounding-box diagonal) of the 11 shared CAD parts (5 of them STEP/IGES: exported through
OCP in the worker first). Each workload runs once untimed on the fresh cluster (the cold run:
OCP import, first daemon requests), then 3 times, each into a fresh OUTDIR; the table has the
median. A batch's time is ``tessd.batch.run`` on a running cluster: manifest, submission,
tasks, library stage, summary (the cluster's start is listed apart: it is paid once per
cluster, not per batch). Also measured: the scheduler's cost per task (1000 empty tasks on the
2-worker cluster), and per workload the sum of the steps' times in the workers, so the table
shows how much of a batch is the work itself.

    python bench/batch/bench_batch.py [--runs 3] [--out bench/results/batch.md]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(REPO / "bench"))

from report_common import machine  # noqa: E402

from tessd.batch import cluster as batch_cluster  # noqa: E402
from tessd.batch.runner import run  # noqa: E402


def shared_data() -> Path:
    return Path(os.environ.get("TESSD_SHARED_DATA", REPO.parent / "shared" / "data"))


def manifests(folder: Path, repeat: int) -> dict:
    data = shared_data()
    meshes = sorted(p for p in (data / "mesh").iterdir() if p.suffix in (".ply", ".obj", ".off"))
    parts = sorted(p for p in (data / "brep").iterdir()
                   if p.suffix.lower() in (".step", ".stp", ".iges", ".igs", ".brep"))
    out = {}
    for i, (name, files, ops, rep) in enumerate((
            ("LOD chains of the shared meshes", meshes, "lod=50%,20%,5%", repeat),
            ("tessellation of the shared parts", parts, "tessellate=0.1%", repeat),
            # the B-Rep render (trimmed surfaces on lavapipe here): the dearest step per asset
            ("tessellation + 256x256 thumbnail of the shared parts", parts,
             "tessellate=0.1%; thumbnail=256x256", 1))):
        m = folder / ("workload%d.json" % i)
        m.write_text(json.dumps([{"input": str(p), "operations": ops, "name": "%s_r%d" % (p.stem, k)}
                                 for k in range(rep) for p in files]))
        out[name] = (m, rep * len(files), rep * sum(p.stat().st_size for p in files))
    return out


def one_run(manifest: Path, client, scratch: Path) -> tuple:
    out = Path(tempfile.mkdtemp(prefix="run-", dir=scratch))
    t0 = time.perf_counter()
    result = run(str(manifest), str(out), client=client, show_progress=False)
    seconds = time.perf_counter() - t0
    errors = [r for r in result.rows if r["status"] != "ok"]
    assert not errors, errors[:3]
    steps = sum(r["seconds"] for r in result.rows)
    by_step = {}
    for r in result.rows:
        by_step[r["step"]] = by_step.get(r["step"], 0.0) + r["seconds"]
    written = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(out) for f in fs)
    shutil.rmtree(out)
    return seconds, steps, by_step, written


def task_overhead(client, n: int = 1000) -> float:
    """Milliseconds of scheduler + worker round trip per empty task (n tasks, gathered)."""
    def noop(i):
        return i

    client.gather(client.map(noop, range(50), pure=False))  # warm
    t0 = time.perf_counter()
    client.gather(client.map(noop, range(n), pure=False))
    return 1000.0 * (time.perf_counter() - t0) / n


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--repeat", type=int, default=4,
                    help="each input listed this many times (as distinct assets), so a batch "
                         "lasts long enough to time")
    ap.add_argument("--out", default=str(REPO / "bench" / "results" / "batch.md"))
    args = ap.parse_args()
    from distributed import Client

    scratch = Path(tempfile.mkdtemp(prefix="tessd-batch-bench-"))
    rows, startup, overhead = [], {}, None
    try:
        work = manifests(scratch, args.repeat)
        for workers in [int(w) for w in args.workers.split(",")]:
            t0 = time.perf_counter()
            cl = batch_cluster.local_cluster(workers)
            client = Client(cl)
            client.wait_for_workers(workers)
            startup[workers] = time.perf_counter() - t0
            try:
                for name, (m, n_assets, n_bytes) in work.items():
                    cold = one_run(m, client, scratch)[0]
                    runs = [one_run(m, client, scratch) for _ in range(args.runs)]
                    secs = [r[0] for r in runs]
                    med = statistics.median(secs)
                    i_med = secs.index(med)
                    rows.append(dict(workload=name, workers=workers, assets=n_assets,
                                     mbytes=n_bytes / 1e6, median=med, runs=secs, cold=cold,
                                     steps=runs[i_med][1], by_step=runs[i_med][2],
                                     out_mbytes=runs[i_med][3] / 1e6,
                                     per_min=60.0 * n_assets / med))
                    print("%-34s %d worker(s): median %.2fs (%s), cold %.2fs, %.0f assets/min"
                          % (name, workers, med, ", ".join("%.2f" % s for s in secs), cold,
                             60.0 * n_assets / med), file=sys.stderr)
                if workers == 2:
                    overhead = task_overhead(client)
            finally:
                client.close()
                cl.close()
    finally:
        shutil.rmtree(scratch, ignore_errors=True)

    lines = [
        "# tessd.batch single-node throughput",
        "",
        "Machine: %s; %s. Command: `bash bench/batch/run_batch.sh` (bench/batch/bench_batch.py,"
        " the CAD venv: dask %s, distributed %s)." % (machine(), time.strftime("%Y-%m-%d"),
                                                       _version("dask"), _version("distributed")),
        "",
        "A LocalCluster of N worker processes (one thread each) sharing one tessd daemon (scope"
        " `node`). Time: `tessd.batch.run` on the running cluster (manifest, submission, tasks,"
        " `library.usda`, summary), median of %d runs, each into a fresh OUTDIR, after one"
        " untimed cold run (listed); each shared input listed %d times as distinct assets (once"
        " for the thumbnails)."
        " *Steps* is the sum of the steps' own times in the workers"
        " (the daemon request, OCP's export, the fsyncs); *batch − steps/N* is what the"
        " orchestration costs on top." % (args.runs, args.repeat),
        "",
        "| workload | workers | assets | input MB | output MB | median s | runs s | cold s |"
        " steps s | batch − steps/N s | assets/min |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append("| %s | %d | %d | %.1f | %.1f | %.2f | %s | %.2f | %.2f | %.2f | **%.0f** |" % (
            r["workload"], r["workers"], r["assets"], r["mbytes"], r["out_mbytes"], r["median"],
            " / ".join("%.2f" % s for s in r["runs"]), r["cold"], r["steps"],
            r["median"] - r["steps"] / r["workers"], r["per_min"]))
    lines += ["", "Steps' time by step (the median run):", ""]
    for r in rows:
        lines.append("- %s, %d worker(s): %s" % (r["workload"], r["workers"], ", ".join(
            "%s %.2fs" % (k, v) for k, v in sorted(r["by_step"].items(), key=lambda kv: -kv[1]))))
    lines += [""]
    lines.append("Cluster start (LocalCluster + workers registered): %s." % ", ".join(
        "%d worker(s) %.1fs" % (w, s) for w, s in sorted(startup.items())))
    if overhead is not None:
        lines.append("Scheduler round trip per task (1000 empty tasks, 2 workers): %.2f ms." % overhead)
    lines.append("")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


def _version(mod: str) -> str:
    try:
        return __import__(mod).__version__
    except Exception:
        return "?"


if __name__ == "__main__":
    sys.exit(main())
