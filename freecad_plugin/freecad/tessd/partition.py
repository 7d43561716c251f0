"""The partition of a simplification as wire boxes ("show partition", paper 004 section 6).

`simplify` with `partition` returns the non-empty cells as `cells_min` / `cells_max` ([C, 3]);
each becomes the 12 edges of its box (edges of no length, in a cell flat along an axis, are
left out), all in one compound for a Part::Feature `<Label>_partition`: lines only, so FreeCAD
draws it as a wire cage over the result. Part shapes only: safe on a worker thread.
"""

from typing import Any

import FreeCAD
import numpy as np
import Part


def boxes(cells_min: Any, cells_max: Any) -> Any:
    """A compound of the cells' box edges (a null-free, possibly empty compound)."""
    lo = np.asarray(cells_min, dtype=np.float64).reshape(-1, 3)
    hi = np.asarray(cells_max, dtype=np.float64).reshape(-1, 3)
    V = FreeCAD.Vector
    edges = []
    for (x0, y0, z0), (x1, y1, z1) in zip(lo.tolist(), hi.tolist()):
        bottom = [V(x0, y0, z0), V(x1, y0, z0), V(x1, y1, z0), V(x0, y1, z0)]
        top = [V(p.x, p.y, z1) for p in bottom]
        pairs = [(ring[k], ring[(k + 1) % 4]) for ring in (bottom, top) for k in range(4)]
        pairs += list(zip(bottom, top))
        edges.extend(Part.makeLine(a, b) for a, b in pairs if (b - a).Length > 0.0)
    return Part.makeCompound(edges)


__all__ = ["boxes"]
