"""Part inputs to triangle meshes: the B-Rep export and the daemon's `tessellate`, welded.

Every operation that needs a Part object as triangles (Tessellate, and Simplify, Generate LODs
and Export USD on Part objects) goes through :func:`tessellate_part`: the shape goes to the
daemon as OpenCASCADE's own BREP text (`Shape.exportBrepToString()`, a few ms in C++; the
daemon reads it into its exchange document, core/brep/src/occt), is tessellated there (trimmed
faces, shared edges discretised once) and welded (meshes.weld) into a shared-vertex mesh whose
face groups are the B-Rep faces in `shape.Faces` order. A shape holding geometry the daemon's
reader has no exact type for (it answers `unsupported`: offset surfaces, ...) is sent again as
the `tessd-brep` document of tessd.brep.freecad (FreeCAD's Part API walk, ~0.3 ms a face). Positions come back as f64
(absolute), so welding compares exact values and nothing is rounded before FreeCAD's own f32.

The last few tessellations are kept (keyed by the shape, its placement, the tolerance and the
angle): the Simplify dialog's live preview asks for the same part again at every change of a
parameter, and should pay for the tessellation once.
"""

import collections
import threading
from dataclasses import dataclass, field
from typing import Any, Dict, List

import numpy as np
from tessd.brep.freecad import export_shape
from tessd.client import TessdError

from . import meshes
from .params import length
from .shapes import PartInput

#: Tessellations kept for reuse.
CACHE_SIZE = 4
#: Tessellate requests in flight at once while the next parts are exported.
IN_FLIGHT = 2
#: Send shapes as OpenCASCADE BREP text (else always as the Python walk's document).
NATIVE_BREP = True

_cache: "collections.OrderedDict[tuple, Tessellation]" = collections.OrderedDict()
_cache_lock = threading.Lock()


@dataclass
class Tessellation:
    """A Part's watertight mesh: welded positions, triangles, the B-Rep face of each triangle."""

    positions: np.ndarray  # f64 [V, 3]
    triangles: np.ndarray  # int64 [F, 3]
    groups: np.ndarray  # int64 [F]: index of the B-Rep face (0-based, `shape.Faces` order)
    face_count: int  # B-Rep faces (so groups run 0..face_count-1)
    #: The daemon's `tessellate` report (tolerance used, counts, time, warnings).
    result: Dict[str, Any] = field(default_factory=dict)

    def warnings(self, label: str) -> List[str]:
        """What the user should hear about this tessellation."""
        out = ["%s: %s" % (label, w) for w in self.result.get("warnings") or ()]
        empty = self.result.get("empty_faces") or []
        if empty:
            out.append("%s: %d face(s) gave no triangle (face ids %s)"
                       % (label, len(empty), ", ".join(str(i) for i in empty[:10])))
        return out


def tessellate_part(task: Any, client: Any, part: PartInput, tolerance: Any = "0.1mm",
                    angle: float = 0.5, span=(0.0, 1.0)) -> Tessellation:
    """The tessellation of ``part`` at ``tolerance`` (a length with units, a number of mm or a
    percentage of the part's diagonal) and ``angle`` (radians), through ``task``'s client
    (progress on ``span``, cancellable). Daemon errors raise ``TessdError``."""
    return tessellate_parts(task, client, [part], tolerance, angle, span)[0]


def tessellate_parts(task: Any, client: Any, parts: List[PartInput], tolerance: Any = "0.1mm",
                     angle: float = 0.5, span=(0.0, 1.0)) -> List[Tessellation]:
    """:func:`tessellate_part` of every part, pipelined: while the daemon tessellates a part,
    this thread writes the next one's BREP text, up to
    :data:`IN_FLIGHT` requests at once; the results are collected and welded in order. A
    cancel or an error cancels the requests still running."""
    tol = length(tolerance, "tolerance", percent=True)
    n = len(parts)
    lo, hi = span
    out: List[Any] = [None] * n
    pending: "collections.deque[tuple]" = collections.deque()

    def part_span(i: int) -> tuple:
        return (lo + (hi - lo) * i / n, lo + (hi - lo) * (i + 1) / n)

    def submit(i: int, native: bool) -> Any:
        part = parts[i]
        task.report(part_span(i)[0], "%s: exporting the B-Rep" % part.label)
        params = brep_params(part.shape, part.label, native)
        task.check_cancel()
        params.update(tolerance=tol, angle=float(angle), positions="f64")
        return task.submit(client, "tessellate", params, span=part_span(i), label=part.label)

    def finish() -> None:
        i, key, job = pending.popleft()
        try:
            result, arrays = task.wait(job, "tessellate", part_span(i), parts[i].label)
        except TessdError as e:
            if e.code != "unsupported":
                raise
            # geometry the BREP reader has no exact type for: the Part API walk instead
            result, arrays = task.wait(submit(i, native=False), "tessellate", part_span(i),
                                       parts[i].label)
        positions, triangles = meshes.weld(arrays["positions"], meshes.triangles_of(arrays))
        groups = np.asarray(arrays["face_groups"], dtype=np.int64).reshape(-1)
        out[i] = Tessellation(positions, triangles, groups, int(result["faces"]), result)
        if key:
            with _cache_lock:
                _cache[key] = out[i]
                while len(_cache) > CACHE_SIZE:
                    _cache.popitem(last=False)

    try:
        for i, part in enumerate(parts):
            key = part.key + (tol, float(angle)) if part.key else None
            with _cache_lock:
                hit = _cache.get(key) if key else None
                if hit is not None:
                    _cache.move_to_end(key)
            if hit is not None:
                out[i] = hit
                continue
            pending.append((i, key, submit(i, native=NATIVE_BREP)))
            while len(pending) >= IN_FLIGHT:
                finish()
        while pending:
            finish()
    except BaseException:
        for *_, job in pending:
            job.cancel()
        raise
    return out


def brep_text(shape: Any) -> str:
    """The shape as OpenCASCADE's BREP text, the daemon's fastest B-Rep input."""
    return shape.exportBrepToString()


def brep_params(shape: Any, label: str, native: bool = True) -> Dict[str, Any]:
    """The request parameters carrying ``shape`` (FreeCAD's millimetres): its BREP text, or —
    ``native`` false, the fallback where the daemon's reader answered ``unsupported`` — the
    Part API walk's `tessd-brep` document (named ``label``)."""
    if native:
        return {"brep": brep_text(shape), "units": "mm"}
    return {"brep": export_shape(shape, units="mm", source=label)}


def clear_cache() -> None:
    """Forgets the kept tessellations."""
    with _cache_lock:
        _cache.clear()


__all__ = ["Tessellation", "brep_params", "brep_text", "clear_cache", "tessellate_part", "tessellate_parts"]
