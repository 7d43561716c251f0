"""What the B-Rep exporters (ocp.py, freecad.py) share, free of any CAD kernel: the document's
frame, the face's loops once the kernel has given its trims (the mirror's loop reversal, the outer
loop's choice, the bounds, the gap bridges) and the bookkeeping of shared edges. Keeping this in
one place is what makes the two exporters write the same document for the same shape.

A trim's curve is the exporter's own 2D curve wrapped in an object with `uv(t)` (its point) and
`json()` (its CURVE2D); `Line2d` is the kernel-free one used for the gap bridges."""

from __future__ import annotations

import math
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

FORMAT = "tessd-brep"
VERSION = 1
UNITS = ("mm", "cm", "m", "in")

TWO_PI = 2.0 * math.pi
# Gaps between consecutive trims above this fraction of the bounds' size get a bridging segment.
GAP_BRIDGE = 1e-8
# Samples per trim taken to make sure `bounds` holds every trim (see face_bounds).
BOUNDS_SAMPLES = 16


class ExportError(ValueError):
    """A shape the exporter cannot write; the message names the face / edge."""


def check_units(units: str) -> None:
    if units not in UNITS:
        raise ValueError(f"units must be one of {UNITS}, not {units!r}")


def new_document(units: str, source: Optional[str], faces: List[Dict[str, Any]],
                 edges: List[Dict[str, Any]], sewing: Optional[Dict[str, Any]] = None) -> Dict[str, Any]:
    """The document around its faces and edges (the fields in the format's order); `sewing`:
    the exporter's report of what sewing did, when it sewed (an optional top-level field)."""
    doc: Dict[str, Any] = {"format": FORMAT, "version": VERSION, "units": units}
    if source is not None:
        doc["source"] = source
    if sewing is not None:
        doc["sewing"] = sewing
    doc["faces"] = faces
    doc["edges"] = edges
    return doc


def edge_json(eid: int, curve: Optional[Dict[str, Any]], first: float, last: float,
              faces: List[int], tolerance: Optional[float] = None,
              vertex_tolerances: Optional[Sequence[float]] = None) -> Dict[str, Any]:
    """An EDGE; `tolerance` (the kernel's edge tolerance) and `vertex_tolerances` (its vertices'
    at range[0] and range[1]) are written when known, in the document's units."""
    e: Dict[str, Any] = {"id": eid, "curve": curve, "range": [first, last], "faces": faces}
    if tolerance is not None:
        e["tolerance"] = float(tolerance)
    if vertex_tolerances is not None:
        e["vertex_tolerances"] = [float(t) for t in vertex_tolerances]
    return e


def note_edge_face(edge_faces: Dict[int, List[int]], eid: Optional[int], fid: int) -> None:
    """Records that face `fid` is bounded by edge `eid` (once, in the order met)."""
    if eid is not None:
        lst = edge_faces.setdefault(eid, [])
        if fid not in lst:
            lst.append(fid)


def same_parameter(c: Callable[[float], Sequence[float]], bs: Callable[[float], Sequence[float]],
                   t0: float, t1: float, bs_range: Tuple[float, float], tol: float = 1e-12) -> bool:
    """Whether the curve `bs` (t → point; its own parameter range `bs_range`) is `c` on [t0, t1]
    point for point at the same parameter (sampled): a converter's B-spline may replace a curve
    in a trim or an edge only then, the trim's t staying the edge's t."""
    lo, hi = bs_range
    if abs(lo - t0) > 1e-12 * (1 + abs(t0)) or abs(hi - t1) > 1e-12 * (1 + abs(t1)):
        return False
    scale = 1.0 + max(abs(x) for x in list(c(t0)) + list(c(t1)))
    for k in range(1, 16):
        t = t0 + (t1 - t0) * k / 16
        if math.dist(c(t), bs(t)) > tol * scale:
            return False
    return True


def knot_span_range(t0: float, t1: float, lo: float, hi: float,
                    periodic: bool) -> Optional[Tuple[float, float]]:
    """[t0, t1] for a B-spline with knot span [lo, hi]: clamped to the span (kernel ranges may
    overshoot it by rounding; the format refuses that), or None for a periodic curve's trim
    running over the span (it needs its non-periodic segment)."""
    if periodic and not (t0 >= lo - 1e-12 * (hi - lo) and t1 <= hi + 1e-12 * (hi - lo)):
        return None
    return max(t0, lo), min(t1, hi)


# --------------------------------------------------------------------------------------------
# trims and loops


class Line2d:
    """A straight (u, v) segment's carrier: `origin + t·dir` (dir unit)."""

    __slots__ = ("origin", "dir")

    def __init__(self, origin: Tuple[float, float], direction: Tuple[float, float]) -> None:
        self.origin, self.dir = origin, direction

    def uv(self, t: float) -> Tuple[float, float]:
        return self.origin[0] + t * self.dir[0], self.origin[1] + t * self.dir[1]

    def json(self) -> Dict[str, Any]:
        return {"type": "line", "origin": list(self.origin), "dir": list(self.dir)}


class Trim:
    __slots__ = ("curve", "t0", "t1", "edge")

    def __init__(self, curve: Any, t0: float, t1: float, edge: Optional[int]) -> None:
        self.curve, self.t0, self.t1, self.edge = curve, t0, t1, edge

    def json(self) -> Dict[str, Any]:
        return {"curve": self.curve.json(), "range": [self.t0, self.t1], "edge": self.edge}


def signed_area(loop: List[Trim], samples: int = 16) -> float:
    pts = []
    for tr in loop:
        for k in range(samples):
            pts.append(tr.curve.uv(tr.t0 + (tr.t1 - tr.t0) * k / samples))
    return 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(pts, pts[1:] + pts[:1]))


def bridge_gaps(loop: List[Trim], size: float) -> List[Trim]:
    """The loop with a straight (u, v) segment (no edge) across every gap between consecutive
    trims above `GAP_BRIDGE` × the bounds' size. Real data has such gaps (pcurves that meet only
    within the vertex tolerance: up to ~1e-5 of the bounds in the shared data), and the format
    wants loops closed within 1e-7 of the bounds."""
    if size <= 0:
        return loop
    out: List[Trim] = []
    for i, tr in enumerate(loop):
        out.append(tr)
        nxt = loop[(i + 1) % len(loop)]
        a, b = tr.curve.uv(tr.t1), nxt.curve.uv(nxt.t0)
        du, dv = b[0] - a[0], b[1] - a[1]
        gap = math.sqrt(du * du + dv * dv)
        if gap > GAP_BRIDGE * size:
            out.append(Trim(Line2d((a[0], a[1]), (du / gap, dv / gap)), 0.0, gap, None))
    return out


def face_bounds(uv_bounds: Sequence[float], mirror: bool, loops: List[List[Trim]],
                where: str) -> List[float]:
    """The kernel's UVBounds (u → 2π - u where mirrored), widened (if at all) to hold sampled
    points of every exported trim (a straight trim's two ends: exact, and most trims of a CAD
    part are straight)."""
    u0, u1, v0, v1 = uv_bounds
    if mirror:
        u0, u1 = TWO_PI - u1, TWO_PI - u0
    for loop in loops:
        for tr in loop:
            n = 1 if tr.curve.json().get("type") == "line" else BOUNDS_SAMPLES
            for k in range(n + 1):
                u, v = tr.curve.uv(tr.t0 + (tr.t1 - tr.t0) * k / n)
                u0, u1, v0, v1 = min(u0, u), max(u1, u), min(v0, v), max(v1, v)
    b = [u0, u1, v0, v1]
    if not all(math.isfinite(x) for x in b):
        raise ExportError(f"{where}: unbounded parameter range {b} (a face without trims on an "
                          "infinite surface)")
    return b


def outer_first(wires: List[Any], is_outer: Callable[[Any], bool]) -> List[Any]:
    """The face's wires, the kernel's outer wire first, the others in their order."""
    out: List[Any] = []
    for w in wires:
        if is_outer(w):
            out.insert(0, w)
        else:
            out.append(w)
    return out


def face_json(fid: int, reversed_: bool, mirror: bool, surface: Dict[str, Any],
              wire_trims: List[List[Trim]], uv_bounds: Sequence[float], where: str) -> Dict[str, Any]:
    """The FACE from the trims of each wire (the outer wire first, each in the forward face's
    order, the pcurves already mirrored where `mirror`): empty wires dropped, mirrored loops
    walked the other way, the outer loop checked, bounds and gap bridges added."""
    loops: List[List[Trim]] = []
    for trims in wire_trims:
        if not trims:
            continue
        if mirror:  # the mirror turned the loop around: walk it the other way
            trims = [Trim(t.curve, t.t1, t.t0, t.edge) for t in reversed(trims)]
        loops.append(trims)
    # The kernels' outer wire is a guess (OCP's OuterWire compares bounding boxes); where that
    # picks a hole (its box as large as the outer loop's), the signed areas decide: the outer
    # loop is the counter-clockwise one.
    if len(loops) > 1 and signed_area(loops[0]) < 0:
        ccw = [i for i, lp in enumerate(loops) if signed_area(lp) > 0]
        if len(ccw) == 1:
            loops.insert(0, loops.pop(ccw[0]))
    bounds = face_bounds(uv_bounds, mirror, loops, where)
    size = math.hypot(bounds[1] - bounds[0], bounds[3] - bounds[2])
    loops = [bridge_gaps(loop, size) for loop in loops]
    return {
        "id": fid,
        "reversed": reversed_ != mirror,
        "surface": surface,
        "bounds": bounds,
        "loops": [{"edges": [t.json() for t in loop]} for loop in loops],
    }
