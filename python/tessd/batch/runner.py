"""Running a batch: manifest → one Dask task per asset → the library stage and the summary.

    from tessd.batch import run
    result = run("assets/", "out/", workers=4)             # a LocalCluster of 4 processes
    result = run("list.csv", "out/", address="tcp://scheduler:8786")
    result = run("list.csv", "out/", client=dask_client)   # a cluster you already have

Tasks are submitted largest input first (Dask ``priority`` = input bytes), so the long ones do
not end up alone at the tail. A task is retried only when its worker dies (the scheduler's
``allowed_failures``, 3 by default; past it the asset is reported as an error ``worker lost``);
bad inputs are errors in the summary and the batch goes on.
"""

from __future__ import annotations

import os
import sys
import time
import uuid
from typing import Any, Callable, Dict, List, NamedTuple, Optional

from . import layout, manifest as manifest_mod, stages, summary
from .cluster import (DaemonConfig, TessdDaemonPlugin, cluster_key, local_cluster, socket_for,
                      worker_losses)
from .progress import ProgressLine
from .tasks import STATUS_ERROR, process_assets

ProgressCallback = Callable[[int, int, List[Dict[str, Any]]], None]


class BatchError(RuntimeError):
    """The batch could not run at all (the workers cannot start their daemon, ...)."""


class BatchResult(NamedTuple):
    outdir: str
    rows: List[Dict[str, Any]]
    totals: Dict[str, Any]
    seconds: float
    run_id: str
    summary_csv: str
    summary_json: str
    library: str

    @property
    def ok(self) -> bool:
        return self.totals["steps"].get("error", 0) == 0


def run(manifest: str, outdir: str, *, address: Optional[str] = None, workers: int = 2,
        client: Any = None, daemon_scope: str = "node", tessd_bin: Optional[str] = None,
        socket_dir: Optional[str] = None, op_timeout: Optional[float] = 600.0,
        allowed_failures: int = 3, chunk: int = 1, show_progress: bool = True,
        on_progress: Optional[ProgressCallback] = None) -> BatchResult:
    """Runs the batch of ``manifest`` into ``outdir`` and returns its summary.

    The cluster: ``client`` (a ``distributed.Client``) if given, else ``address`` (a running
    scheduler), else a ``LocalCluster`` of ``workers`` processes with one thread each, closed
    at the end. ``daemon_scope``: one tessd daemon per node (``"node"``) or per worker process
    (``"worker"``). ``tessd_bin``: the daemon binary on the workers (default: their
    ``$TESSD_BIN`` or ``PATH``). ``op_timeout``: seconds one daemon request may take.
    ``chunk``: assets per Dask task (1: one task per asset; more when assets are small and
    the cluster large, so that the scheduler's per-task cost stays small, docs/scale-out.md).
    ``on_progress(done, total, rows)`` is called after every task with its rows.
    """
    from distributed import Client, as_completed

    t_start = time.perf_counter()
    outdir = os.path.abspath(outdir)
    assets = manifest_mod.load(manifest, outdir=outdir)
    os.makedirs(os.path.join(outdir, layout.ASSETS), exist_ok=True)
    layout.sweep_temps(outdir)  # the top level's leftovers; each task sweeps its asset folder
    run_id = time.strftime("%Y%m%dT%H%M%S") + "-" + uuid.uuid4().hex[:8]

    cluster = None
    own_client = client is None
    if client is None:
        if address:
            client = Client(address)
        else:
            cluster = local_cluster(workers, allowed_failures=allowed_failures)
            client = Client(cluster)
    try:
        cfg = DaemonConfig(key=cluster_key(client.scheduler.address), scope=daemon_scope,
                           binary=os.path.abspath(tessd_bin) if tessd_bin else None,
                           socket_dir=socket_dir)
        try:
            client.register_plugin(TessdDaemonPlugin(cfg))
        except Exception as e:
            raise BatchError("the workers could not start their tessd daemon: %s: %s"
                             % (type(e).__name__, e)) from e
        rows, losses = _submit_and_collect(client, assets, outdir, run_id, cfg, op_timeout,
                                           max(1, int(chunk)), show_progress, on_progress,
                                           as_completed)
        n_workers = len(client.scheduler_info().get("workers", {}))
    finally:
        if own_client:
            client.close()
        if cluster is not None:
            cluster.close()
            if daemon_scope == "node":  # the workers' teardown stops it; make sure
                _stop_quietly(socket_for(cfg))
            else:
                for name in range(workers):
                    _stop_quietly(socket_for(cfg, name))
    for r in rows:
        r["worker_losses"] = losses.get(r["asset"], 0)

    library = os.path.join(outdir, layout.LIBRARY)
    entries = []
    for a in assets:
        stage_rows = [r for r in rows if r["asset"] == a.name and r["step"] == manifest_mod.ASSET]
        if stage_rows and stage_rows[0]["status"] != STATUS_ERROR:
            mpu = float((stage_rows[0].get("detail") or {}).get("meters_per_unit", 1.0))
            entries.append(stages.LibraryEntry(
                a.name, os.path.relpath(layout.asset_stage(outdir, a.name), outdir), mpu))
    layout.write_if_changed(library, stages.library_stage(entries).encode())

    seconds = time.perf_counter() - t_start
    meta = {"run_id": run_id, "manifest": os.path.abspath(manifest), "outdir": outdir,
            "seconds": round(seconds, 3), "workers": n_workers, "daemon_scope": daemon_scope,
            "chunk": max(1, int(chunk)),
            "library": library, "assets_in_library": len(entries)}
    paths = summary.write(outdir, rows, meta)
    return BatchResult(outdir, rows, summary.totals(rows), seconds, run_id, paths["csv"],
                       paths["json"], library)


def chunks(assets: List[manifest_mod.Asset], size: int) -> List[List[manifest_mod.Asset]]:
    """The assets in tasks of ``size``: grouped by host (locality), largest inputs first."""
    if size <= 1:
        return [[a] for a in assets]
    ordered = sorted(assets, key=lambda a: (a.host or "", -a.size))
    return [ordered[i:i + size] for i in range(0, len(ordered), size)]


def _submit_and_collect(client: Any, assets: List[manifest_mod.Asset], outdir: str, run_id: str,
                        cfg: DaemonConfig, op_timeout: Optional[float], chunk: int,
                        show_progress: bool, on_progress: Optional[ProgressCallback],
                        as_completed: Any):
    futures = {}
    for i, group in enumerate(chunks(assets, chunk)):
        label = group[0].name if len(group) == 1 else "%s-and-%d-more" % (group[0].name, len(group) - 1)
        key = "tessd-batch-%s-%05d-%s" % (run_id, i, label)
        host = group[0].host
        where = dict(workers=[host], allow_other_workers=True) if host else {}
        f = client.submit(process_assets, group, outdir, run_id, cfg, op_timeout, key=key,
                          pure=False, priority=sum(a.size for a in group), retries=0, **where)
        futures[f] = group
    bar = ProgressLine(len(assets)) if show_progress else None
    if bar:
        bar.update(0, force=True)
    rows_by_asset: Dict[str, List[Dict[str, Any]]] = {}
    done = errors = 0
    for f in as_completed(list(futures)):
        group = futures[f]
        if f.status == "finished":
            task_rows = f.result()
        else:  # the task itself failed: its worker died allowed_failures + 1 times, or a bug
            exc = f.exception()
            name = type(exc).__name__
            msg = ("worker lost: %s" % exc) if name == "KilledWorker" else "%s: %s" % (name, exc)
            task_rows = [_lost_row(a, op, msg) for a in group for op in a.ops]
        for a in group:
            asset_rows = [r for r in task_rows if r["asset"] == a.name]
            rows_by_asset[a.name] = asset_rows
            errors += any(r["status"] == STATUS_ERROR for r in asset_rows)
        done += len(group)
        if bar:
            bar.update(done, errors)
        if on_progress:
            on_progress(done, len(assets), task_rows)
    try:
        by_key = worker_losses(client, [f.key for f in futures])
    except Exception:
        by_key = {}
    losses = {a.name: by_key.get(f.key, 0) for f, group in futures.items() for a in group}
    rows = [r for a in assets for r in rows_by_asset.get(a.name, [])]
    return rows, losses


def _lost_row(a: manifest_mod.Asset, op: manifest_mod.Op, msg: str) -> Dict[str, Any]:
    return {"asset": a.name, "input": a.input, "kind": a.kind, "step": op.name,
            "implied": op.implied, "params": op.describe(), "status": STATUS_ERROR,
            "faces_out": None, "vertices_out": None, "files": [], "error": msg, "seconds": 0.0,
            "worker": "", "pid": None, "detail": None}


def _stop_quietly(path: str) -> None:
    from tessd.daemon import stop_daemon

    try:
        stop_daemon(path, timeout=10.0)
    except Exception as e:  # pragma: no cover - best effort
        print("tessd.batch: could not stop the daemon on %s: %s" % (path, e), file=sys.stderr)


__all__ = ["BatchError", "BatchResult", "run"]
