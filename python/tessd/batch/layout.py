"""The output folder: where each file goes, atomic writes, and the records that make re-runs
idempotent.

::

    OUTDIR/
      library.usda                      the root stage: one reference per asset
      summary.csv, summary.json         per asset and step: status, counts, error, seconds, worker
      assets/<name>/
        <name>.usda                     the asset's stage (defaultPrim, kind component, assetInfo)
        <name>_lod.usda                 lod: the LOD chain (variant set LOD, LOD0 = the input)
        <name>_tess.usda                tessellate: the CAD part's mesh (a GeomSubset per face)
        <name>_mesh.usda                convert: the mesh as a stage (when no lod is asked)
        <name>_brep.json                export: a STEP/IGES part as a tessd-brep document
        <name>_thumb.png                thumbnail (render, iso view)
        turntable/<name>_000.png ...    turntable frames
        .batch/<step>.json              the record of each completed step
        .staging/<attempt>/             the daemon's outputs of the running attempt (transient)

**Atomicity.** Every file reaches its final name by ``os.replace`` of a complete temporary file
written in the same folder, its data fsynced before the rename and the folder after (the
daemon's outputs too: it writes ``.<file>.tmp-<pid>-<n>`` and renames into the staging folder;
the worker fsyncs them, moves them to their final name and fsyncs the folder before recording
the step; records are the exception, below). So a worker or daemon that dies mid-write leaves at most a temporary file, never a
partial file under a final name; temporary files (``.<file>.tmp-<pid>-<suffix>``, the daemon's
pattern) are removed at the next run (each asset's folder when its task starts, OUTDIR's top
level when the batch starts).

**Staging.** The daemon writes each output into a folder of its own attempt,
``assets/<name>/.staging/<pid>-<token>/``, and the worker moves it to its final name (same file
system: ``os.replace``) once the request succeeded. A worker killed mid-request leaves its
request running in the (shared, detached) daemon until the daemon notices the closed
connection and cancels it, removing the files it wrote *by name*; were both attempts writing
the same final names, that cleanup could delete the resubmitted attempt's fresh files. With a
folder per attempt the old request can only touch its own. A task removes ``.staging`` when it
starts (a dead attempt's leftovers) and when it ends.

**Records.** A step is complete when its record ``.batch/<step>.json`` exists, names the same
parameters and the same input (size and modification time), and every file it lists exists with
the size it lists. The record is written last (atomically), after the step's files are durable (their data
fsynced before the rename, their folder after): so a record never outlives its files, while
the record itself needs no fsync (lost or emptied by a power cut, it only makes the step run
again). A complete step is skipped on a re-run and nothing is rewritten.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import shutil
from typing import Any, Dict, Iterable, List, Mapping, Optional

ASSETS = "assets"
LIBRARY = "library.usda"
SUMMARY_CSV = "summary.csv"
SUMMARY_JSON = "summary.json"
RECORDS = ".batch"
STAGING = ".staging"

#: A temporary file of an atomic write: ``.<final name>.tmp-<pid>-<suffix>`` (ours and the
#: daemon's, core/mesh/src/io/atomic.rs).
TEMP_RE = re.compile(r"^\..+\.tmp-\d+-[0-9A-Za-z]+$")


# ---------------------------------------------------------------------------------------------
# Paths


def asset_dir(outdir: str, name: str) -> str:
    return os.path.join(outdir, ASSETS, name)


def asset_stage(outdir: str, name: str) -> str:
    return os.path.join(asset_dir(outdir, name), name + ".usda")


def step_file(outdir: str, name: str, step: str) -> str:
    """The (first) output file of ``step`` for asset ``name``."""
    d = asset_dir(outdir, name)
    return {
        "lod": os.path.join(d, name + "_lod.usda"),
        "tessellate": os.path.join(d, name + "_tess.usda"),
        "convert": os.path.join(d, name + "_mesh.usda"),
        "export": os.path.join(d, name + "_brep.json"),
        "thumbnail": os.path.join(d, name + "_thumb.png"),
        # the daemon writes <stem>_000.png ... for output <stem>.png
        "turntable": os.path.join(d, "turntable", name + ".png"),
        "asset": os.path.join(d, name + ".usda"),
    }[step]


def record_path(outdir: str, name: str, step: str) -> str:
    return os.path.join(asset_dir(outdir, name), RECORDS, step + ".json")


# ---------------------------------------------------------------------------------------------
# Atomic writes


def fsync_dir(path: str) -> None:
    """Makes the folder's entries (a rename) durable; a no-op where folders cannot be opened."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def fsync_file(path: str) -> None:
    """Flushes a file someone else wrote (the daemon) to stable storage."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def temp_name(path: str) -> str:
    """A fresh temporary name beside ``path``, in the pattern :data:`TEMP_RE` matches."""
    d, base = os.path.split(path)
    return os.path.join(d, ".%s.tmp-%d-%s" % (base, os.getpid(), secrets.token_hex(4)))


def atomic_write(path: str, data: bytes, durable: bool = True) -> None:
    """Writes ``data`` to ``path`` atomically: a temporary file in the same folder, fsynced,
    then ``os.replace``d over ``path`` and the folder fsynced. On any failure the temporary
    file is removed and ``path`` is untouched. ``durable=False`` skips both fsyncs (still
    atomic for readers, but a power loss may lose or empty the file: for records, whose loss
    only makes the step run again)."""
    tmp = temp_name(path)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            if durable:
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    if durable:
        fsync_dir(os.path.dirname(path) or ".")


def write_if_changed(path: str, data: bytes) -> bool:
    """Writes ``data`` atomically unless ``path`` already holds exactly it (so a re-run leaves
    the file and its modification time alone). Returns True when it wrote."""
    try:
        with open(path, "rb") as f:
            if f.read() == data:
                return False
    except OSError:
        pass
    atomic_write(path, data)
    return True


def atomic_write_json(path: str, obj: Any, durable: bool = True) -> None:
    atomic_write(path, (json.dumps(obj, indent=1, sort_keys=True, allow_nan=False) + "\n").encode(),
                 durable=durable)


def sweep_temps(folder: str, recursive: bool = False) -> List[str]:
    """Removes the temporary files of interrupted writes in ``folder`` (and below with
    ``recursive``); returns what it removed. Only safe while nothing writes there."""
    removed = []
    walk: Iterable = os.walk(folder) if recursive else [(folder, [], _listdir(folder))]
    for root, _, files in walk:
        for f in files:
            if TEMP_RE.match(f):
                p = os.path.join(root, f)
                try:
                    os.unlink(p)
                    removed.append(p)
                except OSError:
                    pass
    return removed


def _listdir(folder: str) -> List[str]:
    try:
        return [e.name for e in os.scandir(folder) if e.is_file(follow_symlinks=False)]
    except OSError:
        return []


def find_temps(folder: str) -> List[str]:
    """Every temporary file under ``folder``, staging folders included (what a finished run
    leaves none of)."""
    out = []
    for r, dirs, fs in os.walk(folder):
        out += [os.path.join(r, d) for d in dirs if d == STAGING]
        out += [os.path.join(r, f) for f in fs if TEMP_RE.match(f)]
    return out


def staging_dir(asset_folder: str) -> str:
    """A fresh folder for one attempt's daemon outputs: ``<asset>/.staging/<pid>-<token>``."""
    d = os.path.join(asset_folder, STAGING, "%d-%s" % (os.getpid(), secrets.token_hex(4)))
    os.makedirs(d)
    return d


def remove_staging(asset_folder: str) -> None:
    """Removes ``<asset>/.staging`` (every attempt's): at a task's start and end, when no other
    attempt of the asset is alive."""
    shutil.rmtree(os.path.join(asset_folder, STAGING), ignore_errors=True)


def publish(produced: str, final: str) -> None:
    """Moves a staged output (complete: the daemon renamed it into place) to its final name,
    after flushing it to stable storage."""
    if produced != final:
        fsync_file(produced)
        os.replace(produced, final)


# ---------------------------------------------------------------------------------------------
# Records


def input_fingerprint(path: str) -> Dict[str, int]:
    """What identifies the input's version: its size and modification time (ns)."""
    st = os.stat(path)
    return {"size": st.st_size, "mtime_ns": st.st_mtime_ns}


def load_record(path: str) -> Optional[Dict[str, Any]]:
    try:
        with open(path, encoding="utf-8") as f:
            rec = json.load(f)
    except (OSError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None


def _jsonable(obj: Any) -> Any:
    return json.loads(json.dumps(obj, sort_keys=True))


def record_complete(rec: Optional[Mapping[str, Any]], params: Mapping[str, Any],
                    fingerprint: Optional[Mapping[str, Any]], base: str) -> bool:
    """Whether ``rec`` (a step's record) stands for a complete output of these parameters and
    this input: same parameters, same input fingerprint, every listed file present with its
    recorded size."""
    if not rec or rec.get("params") != _jsonable(dict(params)):
        return False
    if fingerprint is not None and rec.get("input") != _jsonable(dict(fingerprint)):
        return False
    files = rec.get("files")
    if not isinstance(files, dict) or not files:
        return False
    for rel, size in files.items():
        try:
            if os.path.getsize(os.path.join(base, rel)) != size:
                return False
        except OSError:
            return False
    return True


def commit_files(paths: Iterable[str], base: str, sync_folders: bool = True) -> Dict[str, int]:
    """Makes the renames of a step's files durable (fsyncs their folders; the files' data were
    fsynced before their rename: :func:`publish`, :func:`atomic_write`) and returns ``{path
    relative to base: size}`` for the record. Raises ``OSError`` if one is missing."""
    out: Dict[str, int] = {}
    folders = set()
    for p in paths:
        out[os.path.relpath(p, base)] = os.path.getsize(p)
        folders.add(os.path.dirname(p))
    if sync_folders:
        for d in sorted(folders):
            fsync_dir(d)
    return out


__all__ = ["ASSETS", "LIBRARY", "RECORDS", "SUMMARY_CSV", "SUMMARY_JSON", "TEMP_RE", "asset_dir",
           "asset_stage", "atomic_write", "atomic_write_json", "commit_files", "find_temps",
           "fsync_dir", "fsync_file", "input_fingerprint", "load_record", "publish", "record_complete",
           "record_path", "remove_staging", "staging_dir", "step_file", "sweep_temps", "temp_name",
           "write_if_changed"]
