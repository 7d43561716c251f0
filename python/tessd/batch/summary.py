"""The batch's summary: ``summary.csv`` (one row per asset and step) and ``summary.json`` (the
same rows, with lists kept as lists, plus the run's totals), both written atomically.

Columns: ``asset, input, kind, step, implied, params, status, faces_out, vertices_out, files,
error, seconds, worker, pid, worker_losses``. ``status`` is ``ok`` (done in this run),
``error`` (with ``error``: the daemon's message, OCP's, or why the step did not run) or
``skipped`` (a complete output of an earlier run was found). ``faces_out`` / ``vertices_out``:
lod: per level, LOD0 first (``;``-joined in the CSV); tessellate: triangles and vertices;
convert: faces and vertices; export: B-Rep faces; thumbnail / turntable: triangles drawn.
``seconds``: the step's time in the worker (a skipped step: the check). ``worker``:
``host/worker-name``; ``worker_losses``: how many workers died running the asset's task (it was
resubmitted that many times). The JSON rows add ``detail``: what else the step reported (the
absolute tessellation tolerance and diagonal, the LOD notes, the image size, ...).
"""

from __future__ import annotations

import csv
import io
import json
import os
from typing import Any, Dict, Iterable, List, Mapping

from . import layout

COLUMNS = ("asset", "input", "kind", "step", "implied", "params", "status", "faces_out",
           "vertices_out", "files", "error", "seconds", "worker", "pid", "worker_losses")


def totals(rows: Iterable[Mapping[str, Any]]) -> Dict[str, Any]:
    """Counts of rows per status, and of assets: ``ok`` (every step ok or skipped), ``error``."""
    rows = list(rows)
    by_status: Dict[str, int] = {"ok": 0, "error": 0, "skipped": 0}
    assets: Dict[str, bool] = {}
    for r in rows:
        by_status[r["status"]] = by_status.get(r["status"], 0) + 1
        assets[r["asset"]] = assets.get(r["asset"], True) and r["status"] != "error"
    return {"steps": by_status, "assets": len(assets),
            "assets_ok": sum(1 for ok in assets.values() if ok),
            "assets_with_errors": sum(1 for ok in assets.values() if not ok)}


def _cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, (list, tuple)):
        return ";".join("" if v is None else str(v) for v in value)
    if isinstance(value, bool):
        return "true" if value else "false"
    return value


def csv_text(rows: Iterable[Mapping[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: _cell(r.get(k)) for k in COLUMNS})
    return buf.getvalue()


def write(outdir: str, rows: List[Mapping[str, Any]], meta: Mapping[str, Any]) -> Dict[str, str]:
    """Writes ``summary.csv`` and ``summary.json`` into ``outdir``; returns their paths."""
    csv_path = os.path.join(outdir, layout.SUMMARY_CSV)
    json_path = os.path.join(outdir, layout.SUMMARY_JSON)
    layout.atomic_write(csv_path, csv_text(rows).encode())
    doc = dict(meta)
    doc["totals"] = totals(rows)
    doc["rows"] = [{k: r.get(k) for k in COLUMNS + ("detail",)} for r in rows]
    layout.atomic_write(json_path, (json.dumps(doc, indent=1, default=str) + "\n").encode())
    return {"csv": csv_path, "json": json_path}


def read(outdir: str) -> Dict[str, Any]:
    """``summary.json`` of ``outdir``."""
    with open(os.path.join(outdir, layout.SUMMARY_JSON), encoding="utf-8") as f:
        return json.load(f)


__all__ = ["COLUMNS", "csv_text", "read", "totals", "write"]
