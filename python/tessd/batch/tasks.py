"""The task a Dask worker runs for one asset: its steps, one after the other, on the worker's
daemon (see cluster.py), each skipped when its record says it is complete (layout.py).

Every step ends in a summary row (``status`` ok / error / skipped). A step that fails because
of its input (a truncated PLY, a STEP file OCP cannot read, a tolerance the daemon refuses, a
daemon-side error of any code) is reported as ``error`` with the message, and the task goes
on with the steps that do not depend on it: the task itself never raises for a bad input, so
Dask never retries one. What Dask retries is the loss of the worker (``allowed_failures``): the
resubmitted task finds the steps the dead worker completed recorded, reports them ``ok`` (same
run) and does the rest. A lost daemon connection (the daemon died) restarts the daemon once and
retries that step once. The daemon writes into this attempt's staging folder and the task
moves each output to its final name (layout.py, Staging): a killed attempt's request, still
running in the daemon until it notices, can never touch the files of the attempt that replaced
it.

Steps and their dependencies: ``export`` (STEP/IGES → ``<name>_brep.json`` through OCP,
``tessd.brep.export_file``) feeds every CAD step; ``lod`` of a CAD part reads the
``tessellate`` stage; the ``asset`` stage needs a geometry step. A step whose dependency failed
is an ``error`` "not run: <dep> failed".
"""

from __future__ import annotations

import json
import os
import socket as _socket
import time
import traceback
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple

import tessd
from tessd.transport import DaemonUnavailable

from . import layout, stages
from .cluster import DaemonConfig, worker_daemon
from .manifest import ASSET, EXPORT, Asset, Op

STATUS_OK, STATUS_ERROR, STATUS_SKIPPED = "ok", "error", "skipped"


class StepError(Exception):
    """A step failed for a reason to report (its message is the summary's ``error``)."""


class _Context:
    def __init__(self, asset: Asset, outdir: str, run_id: str, cfg: DaemonConfig,
                 op_timeout: Optional[float]):
        self.asset = asset
        self.outdir = outdir
        self.run_id = run_id
        self.cfg = cfg
        self.op_timeout = op_timeout
        self.dir = layout.asset_dir(outdir, asset.name)
        self.fingerprint: Optional[Dict[str, int]] = None
        self.staging: Optional[str] = None  # this attempt's folder for the daemon's outputs
        self.done: Dict[str, Dict[str, Any]] = {}  # step -> record, for steps ok / skipped
        self.failed: Dict[str, str] = {}  # step -> error

    # -- the daemon ---------------------------------------------------------------------------

    def call(self, op: str, params: Mapping[str, Any]) -> Dict[str, Any]:
        """``op`` on the worker's daemon; one reconnect (daemon restarted) if it went away."""
        for attempt in (0, 1):
            path = worker_daemon(self.cfg, restart=attempt > 0)
            try:
                with tessd.Client(path, timeout=30.0) as client:
                    result, _ = client.call(op, params, timeout=self.op_timeout)
                return result
            except DaemonUnavailable:
                if attempt:
                    raise
            except TimeoutError as e:
                raise StepError("%s did not finish within %gs (cancelled)" % (op, self.op_timeout)) from e
        raise AssertionError("unreachable")

    # -- paths -------------------------------------------------------------------------------

    def out(self, step: str) -> str:
        """The final path of ``step``'s (first) output."""
        return layout.step_file(self.outdir, self.asset.name, step)

    def staged(self, step: str) -> str:
        """Where the daemon writes ``step``'s output in this attempt (layout.py, Staging)."""
        if self.staging is None:
            self.staging = layout.staging_dir(self.dir)
        return os.path.join(self.staging, os.path.basename(self.out(step)))

    def brep_source(self) -> Dict[str, Any]:
        """How the daemon gets the part: the exported document, or the input itself (.brep
        text and tessd-brep JSON are read by the daemon from the path: node-local, no copy
        through the socket and no 16 MiB JSON limit)."""
        if self.asset.needs_export:
            return {"input": self.out(EXPORT)}
        return {"input": self.asset.input}

    def units(self, op: Op) -> str:
        if self.asset.needs_export:
            return "mm"
        if self.asset.ext == ".json":
            try:
                with open(self.asset.input, encoding="utf-8") as f:
                    return str(json.load(f).get("units", "mm"))
            except (OSError, ValueError, AttributeError):
                return "mm"
        return str(op.params.get("units", "mm"))


# ---------------------------------------------------------------------------------------------
# The steps: each returns ([(file written, its final path)], counts for the summary); files the
# daemon wrote are staged and moved to their final path by the caller


def _step_export(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    from tessd.brep import export_file  # OCP: only the workers that export import it

    doc = export_file(ctx.asset.input, units=op.params.get("units", "mm"))
    path = ctx.out(EXPORT)
    layout.atomic_write(path, json.dumps(doc, allow_nan=False, separators=(",", ":")).encode())
    return [(path, path)], {"faces_out": len(doc.get("faces", [])), "vertices_out": None,
                    "detail": {"edges": len(doc.get("edges") or []), "sewing": doc.get("sewing")}}


def _step_tessellate(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    if ctx.asset.kind != "cad":
        raise StepError("tessellate needs a CAD input (STEP, IGES, BREP), not a %s file"
                        % ctx.asset.ext)
    units = ctx.units(op)
    params: Dict[str, Any] = dict(ctx.brep_source())
    params.update({"tolerance": op.params["tolerance"], "output": ctx.staged("tessellate"),
                   "name": ctx.asset.name,
                   "meters_per_unit": stages.METERS_PER_UNIT.get(units, 0.001)})
    if "angle" in op.params:
        params["angle"] = op.params["angle"]
    if ctx.asset.ext in (".brep", ".brp"):
        params["units"] = units
    r = ctx.call("tessellate", params)
    return [(ctx.staged("tessellate"), ctx.out("tessellate"))], {
        "faces_out": r.get("triangles"), "vertices_out": r.get("vertices"),
        "detail": {"tolerance": r.get("tolerance"), "diagonal": r.get("diagonal"),
                   "brep_faces": r.get("faces"), "units": r.get("units"),
                   "warnings": r.get("warnings") or []}}


def _step_lod(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    if ctx.asset.kind == "cad":
        source, mpu = ctx.out("tessellate"), stages.METERS_PER_UNIT.get(
            ctx.units(ctx.asset.op("tessellate") or op), 0.001)
    else:
        source, mpu = ctx.asset.input, 1.0
    params = {"input": source, "output": ctx.staged("lod"), "name": ctx.asset.name,
              "meters_per_unit": mpu}
    params.update(op.params)
    r = ctx.call("lod", params)
    levels = r.get("levels") or []
    lod0 = r.get("lod0") or {}
    return [(ctx.staged("lod"), ctx.out("lod"))], {
        # LOD0's faces as the levels count theirs: after the triangulation the goal does
        "faces_out": [r.get("input_faces")] + [lv.get("output_faces") for lv in levels],
        "vertices_out": [r.get("input_vertices")] + [lv.get("output_vertices") for lv in levels],
        "detail": {"lod0_polygons": lod0.get("faces"),
                   "notes": [lv.get("note") for lv in levels if lv.get("note")],
                   "surface_error": [lv.get("surface_error") for lv in levels]}}


def _step_convert(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    if ctx.asset.kind != "mesh":
        raise StepError("convert needs a mesh input, not a %s file" % ctx.asset.ext)
    r = ctx.call("mesh.convert", {"input": ctx.asset.input, "output": ctx.staged("convert"),
                                  "name": ctx.asset.name})
    return [(ctx.staged("convert"), ctx.out("convert"))], {"faces_out": r.get("faces"), "vertices_out": r.get("vertices")}


def _render_source(ctx: _Context) -> Dict[str, Any]:
    return ctx.brep_source() if ctx.asset.kind == "cad" else {"input": ctx.asset.input}


def _step_thumbnail(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    params = dict(_render_source(ctx))
    params.update(op.params)
    params["output"] = ctx.staged("thumbnail")
    r = ctx.call("render", params)
    return [(ctx.staged("thumbnail"), ctx.out("thumbnail"))], {
        "faces_out": r.get("triangles"), "vertices_out": None,
        "detail": {"size": [r.get("width"), r.get("height")], "covered": r.get("covered"),
                   "adapter": (r.get("adapter") or {}).get("name")}}


def _step_turntable(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    final_dir = os.path.dirname(ctx.out("turntable"))
    os.makedirs(final_dir, exist_ok=True)
    layout.sweep_temps(final_dir)
    params = dict(_render_source(ctx))
    params.update({k: v for k, v in op.params.items() if k != "frames"})
    params.update({"turntable": op.params["frames"], "output": ctx.staged("turntable")})
    r = ctx.call("render", params)
    files = [f for f in (r.get("files") or []) if f.endswith(".png")]
    if len(files) != op.params["frames"]:
        raise StepError("render wrote %d turntable frames, expected %d" % (len(files), op.params["frames"]))
    return [(f, os.path.join(final_dir, os.path.basename(f))) for f in files], {"faces_out": r.get("triangles"), "vertices_out": None,
                   "detail": {"frames": r.get("frames"), "size": [r.get("width"), r.get("height")]}}


def _step_asset(ctx: _Context, op: Op) -> Tuple[List[str], Dict[str, Any]]:
    name = ctx.asset.name
    geometry = next((s for s in ("lod", "tessellate", "convert") if s in ctx.done), None)
    if geometry is None:
        raise StepError("not written: no geometry step succeeded")
    mpu = 1.0
    if ctx.asset.kind == "cad":
        mpu = stages.METERS_PER_UNIT.get(ctx.units(ctx.asset.op("tessellate") or op), 0.001)
    thumb = "thumbnail" in ctx.done and os.path.basename(ctx.out("thumbnail"))
    frames = sorted(ctx.done["turntable"]["files"]) if "turntable" in ctx.done else []
    text = stages.asset_stage(name, os.path.basename(ctx.out(geometry)), ctx.asset.input,
                              meters_per_unit=mpu, thumbnail=thumb or None, turntable=frames,
                              kind_label=ctx.asset.ext.lstrip("."))
    path = ctx.out(ASSET)
    layout.write_if_changed(path, text.encode())
    return [(path, path)], {"faces_out": None, "vertices_out": None,
                    "detail": {"geometry": os.path.basename(ctx.out(geometry)),
                               "meters_per_unit": mpu}}


STEPS: Dict[str, Callable[[_Context, Op], Tuple[List[Tuple[str, str]], Dict[str, Any]]]] = {
    EXPORT: _step_export,
    "tessellate": _step_tessellate,
    "lod": _step_lod,
    "convert": _step_convert,
    "thumbnail": _step_thumbnail,
    "turntable": _step_turntable,
    ASSET: _step_asset,
}


def _dependencies(asset: Asset, step: str) -> List[str]:
    deps = []
    if asset.kind == "cad" and asset.needs_export and step not in (EXPORT, ASSET):
        deps.append(EXPORT)
    if asset.kind == "cad" and step == "lod":
        deps.append("tessellate")
    return deps


def _record_params(ctx: _Context, op: Op) -> Dict[str, Any]:
    """What a step's output depends on besides the input: its parameters, and for the asset
    stage the steps it names (a thumbnail added later rewrites it)."""
    params = dict(op.params)
    if op.name == ASSET:
        params = {"steps": sorted(s for s in ctx.done if s != ASSET)}
    return params


# ---------------------------------------------------------------------------------------------
# The task


def _identity() -> Tuple[str, int]:
    try:
        from distributed import get_worker

        w = get_worker()
        return "%s/%s" % (_socket.gethostname(), w.name), os.getpid()
    except (ImportError, ValueError):
        return "%s/local" % _socket.gethostname(), os.getpid()


def process_asset(asset: Asset, outdir: str, run_id: str, cfg: DaemonConfig,
                  op_timeout: Optional[float] = 600.0) -> List[Dict[str, Any]]:
    """Runs every step of ``asset`` into ``outdir``; returns one summary row per step."""
    worker, pid = _identity()
    ctx = _Context(asset, outdir, run_id, cfg, op_timeout)
    rows: List[Dict[str, Any]] = []

    def row(op: Op, status: str, seconds: float, rec: Optional[Mapping[str, Any]] = None,
            error: str = "") -> Dict[str, Any]:
        rec = rec or {}
        return {"asset": asset.name, "input": asset.input, "kind": asset.kind, "step": op.name,
                "implied": op.implied, "params": op.describe(), "status": status,
                "faces_out": rec.get("faces_out"), "vertices_out": rec.get("vertices_out"),
                "files": [os.path.relpath(os.path.join(ctx.dir, f), outdir)
                          for f in sorted(rec.get("files") or {})],
                "error": error, "seconds": round(seconds, 4), "detail": rec.get("detail"),
                "worker": rec.get("worker", worker) if status == STATUS_OK and rec.get("run_id") == run_id
                else worker,
                "pid": rec.get("pid", pid) if status == STATUS_OK and rec.get("run_id") == run_id else pid}

    try:
        os.makedirs(os.path.join(ctx.dir, layout.RECORDS), exist_ok=True)
        layout.sweep_temps(ctx.dir)
        layout.sweep_temps(os.path.join(ctx.dir, layout.RECORDS))
        layout.remove_staging(ctx.dir)  # a dead attempt's (its daemon request is cancelled)
    except OSError as e:
        return [row(op, STATUS_ERROR, 0.0, error="cannot prepare %s: %s" % (ctx.dir, e))
                for op in asset.ops]
    if asset.kind == "unknown":
        return [row(asset.ops[-1], STATUS_ERROR, 0.0,
                    error="%s: not an input tessd.batch knows (meshes: .ply .obj .off .stl .usda; "
                          "CAD: .step .stp .iges .igs .brep .brp .json)" % asset.input)]
    try:
        ctx.fingerprint = layout.input_fingerprint(asset.input)
    except OSError as e:
        return [row(op, STATUS_ERROR, 0.0, error="cannot read the input %s: %s"
                    % (asset.input, e.strerror or e)) for op in asset.ops]

    for op in asset.ops:
        t0 = time.perf_counter()
        missing = [d for d in _dependencies(asset, op.name) if d not in ctx.done]
        if missing:
            ctx.failed[op.name] = "dependency"
            rows.append(row(op, STATUS_ERROR, 0.0, error="not run: %s failed" % ", ".join(missing)))
            continue
        params = _record_params(ctx, op)
        rec_path = layout.record_path(outdir, asset.name, op.name)
        rec = layout.load_record(rec_path)
        if layout.record_complete(rec, params, ctx.fingerprint, ctx.dir):
            assert rec is not None
            ctx.done[op.name] = rec
            same_run = rec.get("run_id") == run_id
            rows.append(row(op, STATUS_OK if same_run else STATUS_SKIPPED,
                            float(rec.get("seconds", 0.0)) if same_run else time.perf_counter() - t0,
                            rec))
            continue
        try:
            produced, counts = STEPS[op.name](ctx, op)
            for staged, final in produced:
                layout.publish(staged, final)  # fsync, rename (the daemon's outputs)
            committed = layout.commit_files(  # fsync the folders of the renames
                [final for _, final in produced], ctx.dir,
                sync_folders=any(staged != final for staged, final in produced))
            seconds = time.perf_counter() - t0
            rec = {"step": op.name, "params": params, "input": ctx.fingerprint,
                   "files": committed, "faces_out": counts.get("faces_out"),
                   "vertices_out": counts.get("vertices_out"), "detail": counts.get("detail"),
                   "run_id": run_id, "seconds": round(seconds, 4), "worker": worker, "pid": pid,
                   "finished": time.time()}
            rec = json.loads(json.dumps(rec, default=str))
            layout.atomic_write_json(rec_path, rec, durable=False)
            ctx.done[op.name] = rec
            rows.append(row(op, STATUS_OK, seconds, rec))
        except Exception as e:  # a bad input, or whatever else: reported, never retried
            ctx.failed[op.name] = _message(e)
            rows.append(row(op, STATUS_ERROR, time.perf_counter() - t0, error=_message(e)))
    layout.remove_staging(ctx.dir)
    return rows


def process_assets(assets: List[Asset], outdir: str, run_id: str, cfg: DaemonConfig,
                   op_timeout: Optional[float] = 600.0) -> List[Dict[str, Any]]:
    """:func:`process_asset` for each of ``assets`` (a chunk: one Dask task), rows in order.
    After a worker loss the whole chunk is resubmitted; its completed steps are skipped."""
    rows: List[Dict[str, Any]] = []
    for asset in assets:
        rows.extend(process_asset(asset, outdir, run_id, cfg, op_timeout))
    return rows


def _message(e: BaseException) -> str:
    if isinstance(e, (StepError, tessd.TessdError)):
        return str(e)
    if isinstance(e, FileNotFoundError):
        return "no such file: %s" % (e.filename or e)
    text = "%s: %s" % (type(e).__name__, e)
    if not isinstance(e, (OSError, ValueError, DaemonUnavailable)):
        # something unexpected: keep where it came from
        text += " (at %s)" % traceback.extract_tb(e.__traceback__)[-1].name if e.__traceback__ else ""
    return text


__all__ = ["STATUS_ERROR", "STATUS_OK", "STATUS_SKIPPED", "STEPS", "StepError", "process_asset",
           "process_assets"]
