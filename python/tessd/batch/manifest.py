"""The batch manifest: which inputs become which assets, with which operations.

A manifest is one of

- a **folder**: every mesh (``.ply .obj .off .stl``) and CAD file (``.step .stp .iges .igs
  .brep .brp``) under it, recursively, hidden entries and the output folder left out, with the
  default operations of its kind (below);
- a **CSV** file with a header row naming at least ``input`` (and optionally ``operations``,
  ``name``, ``host``); ``operations`` is a ``;``-separated list of ``op`` or ``op=ARG`` (quote the field
  when ARG holds commas: ``bunny.ply,"lod=50%,20%,5%; thumbnail"``);
- a **JSON** file: a list of rows (or ``{"assets": [...]}``), each ``{"input": ..., "name": ...,
  "operations": ...}`` where ``operations`` is the CSV string, or a list whose items are such
  strings or objects ``{"op": "lod", "levels": ["50%", "20%"], "method": "complexity"}``.

Relative inputs resolve against the manifest's folder (every worker must see an input, and
OUTDIR, at the same path: shared storage). ``host`` (optional) names the worker host (or worker
address) where the input lives, e.g. on a node's local disk: the task is scheduled there when
that worker is up, elsewhere otherwise (Dask ``workers=[host], allow_other_workers=True``). An empty ``operations`` means the
defaults: meshes get ``lod=50%,20%,5%; thumbnail``, CAD parts ``tessellate=0.1%; thumbnail``
(0.1 % of the part's bounding-box diagonal: the tessellate op's relative tolerance).

Operations, their short ``ARG`` and the keys a JSON object may give:

============  ===============================  ==============================================
op            ARG                              JSON keys (defaults)
============  ===============================  ==============================================
lod           levels ``50%,20%,5%``            levels, method (complexity), lod_schema
                                               (variants), representative, weighting,
                                               triangulate, preserve_boundaries
tessellate    tolerance ``0.1%`` / ``0.05mm``  tolerance (0.1%), angle, units (BREP text: mm)
convert       —                                (the mesh as a USD stage)
thumbnail     size ``512x512``                 size (512x512), view (iso), shading (lit), edges
turntable     frames ``24``                    frames (24), size (256x256), view (iso),
                                               shading (lit)
============  ===============================  ==============================================

``lod`` of a CAD part simplifies its tessellation (``tessellate`` is added with the default
tolerance when the row does not ask for it); an asset whose operations write no geometry gets
``convert`` (mesh) or ``tessellate`` (CAD) added, so every asset stage has a mesh. STEP and IGES
parts get an ``export`` step first (OCP, in the worker: ``tessd.brep``). Nothing here imports
dask: the manifest can be read and checked anywhere.
"""

from __future__ import annotations

import csv
import json
import os
import re
from dataclasses import dataclass, field
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

MESH_EXTS = (".ply", ".obj", ".off", ".stl")
#: Read by the daemon directly; only taken when a CSV/JSON row names one (a folder scan leaves
#: ``.usda`` files out: an asset library's own stages are ``.usda``).
MESH_EXTS_EXPLICIT = MESH_EXTS + (".usda",)
CAD_EXPORT_EXTS = (".step", ".stp", ".iges", ".igs")  # need OCP (tessd.brep) in the worker
CAD_DAEMON_EXTS = (".brep", ".brp")  # OpenCASCADE BREP text: the daemon reads it itself
CAD_EXTS = CAD_EXPORT_EXTS + CAD_DAEMON_EXTS
CAD_EXTS_EXPLICIT = CAD_EXTS + (".json",)  # a tessd-brep document

#: The operations a manifest may ask for, in the order an asset runs them.
OPERATIONS = ("tessellate", "lod", "convert", "thumbnail", "turntable")
#: Steps the batch adds itself: the STEP/IGES export before, the asset stage after.
EXPORT, ASSET = "export", "asset"
GEOMETRY_OPS = ("lod", "tessellate", "convert")

DEFAULT_LEVELS = ("50%", "20%", "5%")
DEFAULT_TOLERANCE = "0.1%"

#: Per op: the short argument's key, and the defaults (also the keys a JSON object may give,
#: with those in _OPTIONAL).
_DEFAULTS: Dict[str, Dict[str, Any]] = {
    "lod": {"levels": list(DEFAULT_LEVELS), "method": "complexity", "lod_schema": "variants"},
    "tessellate": {"tolerance": DEFAULT_TOLERANCE},
    "convert": {},
    "thumbnail": {"size": "512x512", "view": "iso", "shading": "lit"},
    "turntable": {"frames": 24, "size": "256x256", "view": "iso", "shading": "lit"},
}
_SHORT = {"lod": "levels", "tessellate": "tolerance", "thumbnail": "size", "turntable": "frames"}
_OPTIONAL = {
    "lod": ("representative", "weighting", "triangulate", "preserve_boundaries"),
    "tessellate": ("angle", "units"),
    "convert": (),
    "thumbnail": ("edges",),
    "turntable": ("edges",),
}


class ManifestError(ValueError):
    """The manifest itself is wrong (unreadable, no ``input`` column, an unknown operation or
    parameter): the batch does not start. Problems of one input (missing, unreadable, an
    operation its kind cannot do) are reported per asset in the summary instead."""


@dataclass(frozen=True)
class Op:
    """One operation of an asset: its name and its complete (defaults filled) parameters."""

    name: str
    params: Mapping[str, Any] = field(default_factory=dict)
    implied: bool = False  # added by the batch, not asked for in the manifest

    def describe(self) -> str:
        """The parameters as a short ``key=value`` text (the summary's ``params``)."""
        parts = []
        for k in sorted(self.params):
            v = self.params[k]
            parts.append("%s=%s" % (k, ",".join(map(str, v)) if isinstance(v, (list, tuple)) else v))
        return " ".join(parts)


@dataclass(frozen=True)
class Asset:
    """One input and what to make of it. ``name`` is unique in the batch and a USD identifier
    (the asset's folder, files and prim are named after it)."""

    name: str
    input: str  # absolute path
    kind: str  # "mesh" | "cad"
    ops: Tuple[Op, ...]
    row: int = 0  # 1-based row of the manifest (0 for a folder scan)
    size: int = 0  # input bytes (0 when missing): scheduling priority
    host: Optional[str] = None  # preferred worker host (data locality), from the manifest

    @property
    def ext(self) -> str:
        return os.path.splitext(self.input)[1].lower()

    @property
    def needs_export(self) -> bool:
        """STEP/IGES: exported to a tessd-brep document through OCP before the daemon sees it."""
        return self.ext in CAD_EXPORT_EXTS

    def op(self, name: str) -> Optional[Op]:
        for op in self.ops:
            if op.name == name:
                return op
        return None


def kind_of(path: str, explicit: bool = True) -> Optional[str]:
    """``"mesh"``, ``"cad"`` or None (not an input the batch knows) from the extension."""
    ext = os.path.splitext(path)[1].lower()
    if ext in (MESH_EXTS_EXPLICIT if explicit else MESH_EXTS):
        return "mesh"
    if ext in (CAD_EXTS_EXPLICIT if explicit else CAD_EXTS):
        return "cad"
    return None


# ---------------------------------------------------------------------------------------------
# Operations


def parse_operations(spec: Any, where: str = "") -> List[Op]:
    """The operations of one row: a ``;``-separated string (``"lod=50%,20%,5%; thumbnail"``),
    a list of such strings or of ``{"op": ..., key: value}`` objects, or None/empty (defaults,
    returned as ``[]``). Raises :class:`ManifestError` naming ``where``."""
    if spec is None:
        return []
    items: List[Any]
    if isinstance(spec, str):
        items = [s for s in (p.strip() for p in spec.split(";")) if s]
    elif isinstance(spec, (list, tuple)):
        items = []
        for item in spec:
            if isinstance(item, str):
                items.extend(s for s in (p.strip() for p in item.split(";")) if s)
            else:
                items.append(item)
    elif isinstance(spec, Mapping):  # {"lod": {...}, "thumbnail": {}}
        items = [dict({"op": k}, **(v if isinstance(v, Mapping) else {_SHORT.get(k, "arg"): v}))
                 for k, v in spec.items()]
    else:
        raise ManifestError("%s: operations must be a string, a list or an object, not %r"
                            % (where, spec))
    ops: List[Op] = []
    for item in items:
        if isinstance(item, str):
            name, sep, arg = item.partition("=")
            name = name.strip().lower()
            given: Dict[str, Any] = {}
            if sep:
                if name not in _SHORT:
                    raise ManifestError("%s: operation %r takes no argument (got %r)"
                                        % (where, name, item))
                given[_SHORT[name]] = arg.strip()
        elif isinstance(item, Mapping):
            given = dict(item)
            name = str(given.pop("op", "")).strip().lower()
        else:
            raise ManifestError("%s: an operation must be a string or an object, not %r" % (where, item))
        if name not in _DEFAULTS:
            raise ManifestError("%s: unknown operation %r (known: %s)"
                                % (where, name, ", ".join(OPERATIONS)))
        if any(op.name == name for op in ops):
            raise ManifestError("%s: operation %r is given twice" % (where, name))
        ops.append(Op(name, _complete(name, given, where)))
    return ops


def _complete(name: str, given: Mapping[str, Any], where: str) -> Dict[str, Any]:
    allowed = set(_DEFAULTS[name]) | set(_OPTIONAL[name])
    unknown = sorted(set(given) - allowed)
    if unknown:
        raise ManifestError("%s: %s has no parameter %s (it takes %s)"
                            % (where, name, ", ".join(map(repr, unknown)), ", ".join(sorted(allowed)) or "none"))
    params = dict(_DEFAULTS[name])
    params.update({k: v for k, v in given.items() if v is not None and v != ""})
    if name == "lod":
        levels = params["levels"]
        if isinstance(levels, str):
            levels = [s.strip() for s in levels.split(",") if s.strip()]
        elif isinstance(levels, (int, float)):
            levels = [levels]
        if not isinstance(levels, (list, tuple)) or not levels:
            raise ManifestError("%s: lod levels must be a list such as 50%%,20%%,5%%, got %r"
                                % (where, params["levels"]))
        params["levels"] = list(levels)
    if name == "turntable":
        try:
            frames = int(str(params["frames"]).strip())
        except ValueError:
            raise ManifestError("%s: turntable frames must be an integer, got %r"
                                % (where, params["frames"])) from None
        if not 1 <= frames <= 3600:
            raise ManifestError("%s: turntable frames must be 1 to 3600, got %d" % (where, frames))
        params["frames"] = frames
    if name in ("thumbnail", "turntable") and isinstance(params["size"], str):
        params["size"] = params["size"].strip()
    return params


def default_operations(kind: str) -> List[Op]:
    """What a folder's (or an empty ``operations``) input gets."""
    if kind == "mesh":
        return [Op("lod", _complete("lod", {}, "")), Op("thumbnail", _complete("thumbnail", {}, ""))]
    return [Op("tessellate", _complete("tessellate", {}, "")),
            Op("thumbnail", _complete("thumbnail", {}, ""))]


def plan(kind: str, input_path: str, ops: Sequence[Op]) -> Tuple[Op, ...]:
    """The steps an asset runs, in order: the export (STEP/IGES), the asked operations in the
    order of :data:`OPERATIONS`, an implied geometry op when none writes a mesh, and the lod's
    tessellate for a CAD part."""
    asked = {op.name: op for op in (ops or default_operations(kind))}
    if kind == "cad" and "lod" in asked and "tessellate" not in asked:
        asked["tessellate"] = Op("tessellate", _complete("tessellate", {}, ""), implied=True)
    if not any(name in asked for name in GEOMETRY_OPS):
        name = "convert" if kind == "mesh" else "tessellate"
        asked[name] = Op(name, _complete(name, {}, ""), implied=True)
    steps: List[Op] = []
    if kind == "cad" and os.path.splitext(input_path)[1].lower() in CAD_EXPORT_EXTS:
        steps.append(Op(EXPORT, {"units": "mm"}, implied=True))
    steps.extend(asked[name] for name in OPERATIONS if name in asked)
    steps.append(Op(ASSET, {}, implied=True))
    return tuple(steps)


# ---------------------------------------------------------------------------------------------
# Names

_IDENT_BAD = re.compile(r"[^A-Za-z0-9_]")


def identifier(text: str) -> str:
    """``text`` as a USD prim name (``[A-Za-z_][A-Za-z0-9_]*``): other characters become
    ``_``, a leading digit gets a ``_`` before it."""
    name = _IDENT_BAD.sub("_", text) or "asset"
    if name[0].isdigit():
        name = "_" + name
    return name


def unique_names(rows: Sequence[Tuple[Optional[str], str]]) -> List[str]:
    """One unique identifier per ``(name, input)`` row, in order: the given name or the input's
    stem; a later clash gets the extension appended (``bunny_ply``), then ``_2``, ``_3``..."""
    taken: Dict[str, int] = {}
    out: List[str] = []
    for given, path in rows:
        stem, ext = os.path.splitext(os.path.basename(path))
        base = identifier(given if given else stem)
        name = base
        if name.lower() in taken and not given and ext:
            name = identifier(base + "_" + ext.lstrip("."))
        n = 2
        while name.lower() in taken:  # case-insensitive: folders on macOS / Windows shares
            name = "%s_%d" % (base, n)
            n += 1
        taken[name.lower()] = 1
        out.append(name)
    return out


# ---------------------------------------------------------------------------------------------
# Reading


def load(manifest: str, outdir: Optional[str] = None) -> List[Asset]:
    """The assets of ``manifest`` (a folder, ``.csv`` or ``.json``), in manifest order.
    ``outdir`` (the batch's output folder) is left out of a folder scan."""
    manifest = os.path.abspath(manifest)
    if os.path.isdir(manifest):
        rows = _scan_folder(manifest, outdir)
    elif not os.path.isfile(manifest):
        raise ManifestError("%s: no such file or folder" % manifest)
    elif manifest.lower().endswith(".json"):
        rows = _read_json(manifest)
    elif manifest.lower().endswith((".csv", ".tsv", ".txt")):
        rows = _read_csv(manifest)
    else:
        raise ManifestError("%s: a manifest is a folder, a .csv or a .json file" % manifest)
    names = unique_names([(name, path) for _, name, path, _, _ in rows])
    assets = []
    for (row, _, path, ops, host), name in zip(rows, names):
        kind = kind_of(path) or "unknown"
        try:
            size = os.path.getsize(path)
        except OSError:
            size = 0
        steps = plan(kind, path, ops) if kind != "unknown" else (Op(ASSET, {}, implied=True),)
        assets.append(Asset(name=name, input=path, kind=kind, ops=steps, row=row, size=size,
                            host=host))
    return assets


_Row = Tuple[int, Optional[str], str, List[Op], Optional[str]]  # row, name, input, ops, host


def _scan_folder(folder: str, outdir: Optional[str]) -> List[_Row]:
    skip = os.path.realpath(outdir) if outdir else None
    found: List[str] = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".")
                         and os.path.realpath(os.path.join(root, d)) != skip)
        for f in files:
            if not f.startswith(".") and kind_of(f, explicit=False):
                found.append(os.path.join(root, f))
    found.sort(key=lambda p: os.path.relpath(p, folder))
    return [(0, None, p, [], None) for p in found]


def _row(base: str, n: int, data: Mapping[str, Any]) -> _Row:
    where = "row %d" % n
    raw = data.get("input")
    if not isinstance(raw, str) or not raw.strip():
        raise ManifestError("%s: no input" % where)
    path = os.path.expanduser(raw.strip())
    if not os.path.isabs(path):
        path = os.path.join(base, path)
    name = data.get("name")
    name = str(name).strip() if name not in (None, "") else None
    host = data.get("host")
    host = str(host).strip() if host not in (None, "") else None
    return (n, name, os.path.normpath(path), parse_operations(data.get("operations"), where), host)


def _read_csv(path: str) -> List[_Row]:
    base = os.path.dirname(path)
    with open(path, newline="", encoding="utf-8-sig") as f:
        lines = [ln for ln in f if ln.strip() and not ln.lstrip().startswith("#")]
    dialect = "excel-tab" if path.lower().endswith(".tsv") else "excel"
    reader = csv.DictReader(lines, dialect=dialect, skipinitialspace=True)
    if not reader.fieldnames or "input" not in [h.strip().lower() for h in reader.fieldnames]:
        raise ManifestError("%s: the first row must name the columns, `input` and optionally "
                            "`operations`, `name`" % path)
    rows = []
    for n, rec in enumerate(reader, 1):
        rec = {(k or "").strip().lower(): v for k, v in rec.items()}
        rows.append(_row(base, n, rec))
    return rows


def _read_json(path: str) -> List[_Row]:
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        raise ManifestError("%s: %s" % (path, e)) from e
    if isinstance(data, Mapping):
        data = data.get("assets")
    if not isinstance(data, list):
        raise ManifestError("%s: expected a list of rows or {\"assets\": [...]}" % path)
    base = os.path.dirname(path)
    rows = []
    for n, rec in enumerate(data, 1):
        if isinstance(rec, str):
            rec = {"input": rec}
        if not isinstance(rec, Mapping):
            raise ManifestError("row %d: expected an object with `input`, got %r" % (n, rec))
        rows.append(_row(base, n, rec))
    return rows


def to_rows(assets: Iterable[Asset]) -> List[Dict[str, Any]]:
    """The assets as JSON manifest rows (with their complete parameters)."""
    return [{"name": a.name, "input": a.input,
             "operations": [dict({"op": op.name}, **op.params) for op in a.ops
                            if op.name in OPERATIONS and not op.implied]} for a in assets]


__all__ = ["ASSET", "Asset", "EXPORT", "ManifestError", "OPERATIONS", "Op", "default_operations",
           "identifier", "kind_of", "load", "parse_operations", "plan", "to_rows", "unique_names"]
