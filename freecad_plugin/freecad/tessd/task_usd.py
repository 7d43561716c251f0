"""Export USD: one stage of the document's tree, a mesh per part, a GeomSubset per face.

The objects and the containers above them (shapes.document_tree) become the stage's prims under
a root Xform named after the document: App::Parts and groups are Xforms (an App::Part's
Placement as its `xformOp:transform`, a group none), each Part object a Mesh with its own
Placement, tessellated by the daemon in its own frame (so the placements stay in the stage,
not baked into the points) with one GeomSubset `face<i>` per B-Rep face (`shape.Faces[i-1]`),
each Mesh object a Mesh with one GeomSubset per segment (`segment<i>`, and `unsegmented` for
facets in none). `primvars:displayColor` comes from the
view providers when the GUI is up: per face (`uniform`) where faces differ, else `constant`.
Millimetres and Z up, as FreeCAD models (`metersPerUnit = 0.001`, `upAxis = "Z"`).

The daemon writes stages of one mesh only, so the stage is written here (usda.py) from the
tessellations' arrays.
"""

import math
import os
from typing import Any, List, Optional

import numpy as np

from . import usda
from .shapes import MeshInput, Node, PartInput
from .task import Task
from .tessellation import tessellate_part


def usd_matrix(placement: Any) -> Optional[List[List[float]]]:
    """A FreeCAD Placement as USD's row-vector 4x4 matrix (the transpose of FreeCAD's)."""
    if placement is None:
        return None
    a = placement.toMatrix().A
    return [[a[c], a[4 + c], a[8 + c], a[12 + c]] for c in range(4)]


def origin_for(points: np.ndarray, tolerance: float) -> Optional[tuple]:
    """Where to put a part's f32 points relative to, as the daemon's `origin: "auto"` does:
    nothing while the f32 spacing at the part's largest coordinate is below 1 % of the
    tolerance, else the box centre rounded to the largest power of ten not above the box's
    half-extent (docs/protocol.md, "tessellate")."""
    if not len(points) or not tolerance:
        return None
    if np.spacing(np.float32(np.abs(points).max())) < 0.01 * float(tolerance):
        return None
    lo, hi = points.min(axis=0), points.max(axis=0)
    half = float((hi - lo).max()) / 2
    step = 10.0 ** math.floor(math.log10(half)) if half > 0 else 1.0
    return tuple(float(v) for v in np.round((lo + hi) / 2 / step) * step)


def subsets(groups: Optional[np.ndarray], count: int, name: str) -> List[tuple]:
    """``(name<i>, faces)`` for groups 0..count-1 (named from 1, as the daemon's `face<id>`),
    the empty ones left out (a GeomSubset holds at least one face)."""
    if groups is None or not count:
        return []
    order = np.argsort(groups, kind="stable")
    bounds = np.searchsorted(groups[order], np.arange(count + 1))
    return [("%s%d" % (name, g + 1), order[bounds[g]:bounds[g + 1]])
            for g in range(count) if bounds[g + 1] > bounds[g]]


class ExportUsdTask(Task):
    """See the module's notes. ``roots``: shapes.document_tree's nodes."""

    title = "Export USD"
    changes_document = False

    def __init__(self, roots: List[Node], path: str, tolerance: Any = "0.1mm",
                 doc_name: str = "FreeCAD", doc: Any = None):
        super().__init__(doc)
        self.roots = roots
        self.path = os.path.abspath(os.path.expanduser(os.fspath(path)))
        self.tolerance = tolerance
        self.doc_name = doc_name

    def leaves(self) -> List[Node]:
        """The tree's leaves (each object exported), depth first."""
        out: List[Node] = []

        def walk(nodes: List[Node]) -> None:
            for n in nodes:
                if n.leaf is not None:
                    out.append(n)
                walk(n.children)

        walk(self.roots)
        return out

    def _run(self, client: Any) -> None:
        self.reports = []
        leaves = self.leaves()
        prims = {}
        for i, node in enumerate(leaves):
            span = (0.95 * i / len(leaves), 0.95 * (i + 1) / len(leaves))
            prims[id(node)] = self._prim(client, node, span)
        root = usda.Xform(self.doc_name, None, [self._convert(n, prims) for n in self.roots])
        self.check_cancel()
        self.report(0.95, "writing %s" % self.path)
        usda.write_stage(self.path, root, doc="FreeCAD document %s, exported by the tessd "
                         "workbench" % self.doc_name)

    def _prim(self, client: Any, node: Node, span: tuple) -> usda.MeshPrim:
        item = node.leaf
        transform = usd_matrix(node.placement)
        if isinstance(item, PartInput):
            t = tessellate_part(self, client, item, self.tolerance, span=span)
            self.reports.append(t.result)
            self.warnings.extend(t.warnings(item.label))
            color = None
            if item.colors and len(item.colors) == t.face_count:
                color = np.asarray(item.colors, dtype=np.float64)[t.groups]
            return usda.MeshPrim(item.label, t.positions, t.triangles, transform,
                                 origin_for(t.positions, t.result.get("tolerance", 0.0)),
                                 subsets(t.groups, t.face_count, "face"), color, item.name)
        assert isinstance(item, MeshInput)
        parts = subsets(item.groups, item.group_count, "segment")
        if item.groups is not None and np.any(item.groups == item.group_count):
            # facets in no segment: a subset of their own keeps the family a partition
            parts.append(("unsegmented", np.flatnonzero(item.groups == item.group_count)))
        return usda.MeshPrim(item.label, item.positions, item.triangles, transform, None, parts,
                             item.colors[0] if item.colors else None, item.name)

    def _convert(self, node: Node, prims: dict) -> Any:
        if node.leaf is not None:
            return prims[id(node)]
        return usda.Xform(node.label, usd_matrix(node.placement),
                          [self._convert(c, prims) for c in node.children], node.name)

    def _apply(self, doc: Any) -> str:
        return self.path


__all__ = ["ExportUsdTask", "origin_for", "subsets", "usd_matrix"]
