"""Simplify: vertex clustering (paper 004) of Part and Mesh objects, with the partition shown.

The goal and its parameter go to the daemon's `simplify` as `tessd simplify` sends them
(:func:`simplify_params`): ``method`` "grid" (``cells`` per axis or ``cell_size``), "quality"
(``max_error``: a length or a percentage of the largest side) or "complexity" (``target``: a
vertex count or a percentage); a parameter of another goal, or a missing one, is refused by the
daemon with its own message. Part objects are tessellated first (0.1 mm, watertight). Results
are `<Label>_simplified` Mesh::Features keeping their source's segments (a simplified part
keeps one segment per B-Rep face: each output face keeps its input face's group), and, with
``show_partition``, `<Label>_partition`, the non-empty cells as wire boxes.

The same task without document output is the Simplify dialog's live preview
(:class:`SimplifyPreviewTask`: vertex and face counts and the surface error reached).
"""

from typing import Any, Dict, List, Optional

import numpy as np

from . import meshes, params, partition
from .shapes import MeshInput, PartInput
from .task import Task
from .tessellation import tessellate_part

#: Tolerance Part objects are tessellated to before they are simplified.
PART_TOLERANCE = "0.1mm"


def simplify_params(method: str = "complexity", cells: Any = None, cell_size: Any = None,
                    max_error: Any = None, target: Any = None, representative: str = "quadric",
                    show_partition: bool = False, preserve_boundaries: bool = False,
                    weighting: Optional[str] = None) -> Dict[str, Any]:
    """The daemon's `simplify` params, as `tessd simplify` builds them from its options."""
    out: Dict[str, Any] = {"method": method}
    if representative is not None:
        out["representative"] = representative
    if weighting is not None:
        out["weighting"] = weighting
    if cells is not None:
        out["cells"] = int(cells)
    if cell_size is not None:
        out["cell_size"] = params.simplify_length(cell_size, "cell_size", percent=False)
    if max_error is not None:
        out["max_error"] = params.simplify_length(max_error, "max_error", percent=True)
    if target is not None:
        out["target_vertices"] = params.target(target)
    if preserve_boundaries:
        out["preserve_boundaries"] = True
    if show_partition:
        out["partition"] = True
    return out


def source_mesh(task: Task, client: Any, item: Any, span=(0.0, 1.0)):
    """``(positions, triangles, groups, group_count)`` of an input: a Mesh object's own, a Part
    object's tessellation (at :data:`PART_TOLERANCE`, progress on ``span``)."""
    if isinstance(item, MeshInput):
        return item.positions, item.triangles, item.groups, item.group_count
    t = tessellate_part(task, client, item, PART_TOLERANCE, span=span)
    task.warnings.extend(t.warnings(item.label))
    return t.positions, t.triangles, t.groups, t.face_count


class SimplifyTask(Task):
    """See the module's notes. ``inputs``: PartInputs / MeshInputs in the world frame;
    ``simplify``: the daemon's params (:func:`simplify_params`)."""

    title = "Simplify"

    def __init__(self, inputs: List[Any], simplify: Dict[str, Any], doc: Any = None):
        super().__init__(doc)
        self.inputs = inputs
        self.params = simplify
        #: (label, Mesh.Mesh, partition shape or None) per input, once run.
        self.results: List[tuple] = []
        #: The `<Label>_partition` objects added (show_partition), once applied.
        self.partitions: List[Any] = []

    def _run(self, client: Any) -> None:
        self.results, self.reports = [], []
        n = len(self.inputs)
        for i, item in enumerate(self.inputs):
            lo, hi = i / n, (i + 1) / n
            mid = lo + 0.5 * (hi - lo) if isinstance(item, PartInput) else lo
            positions, triangles, groups, count = source_mesh(self, client, item, (lo, mid))
            result, arrays = self.call(client, "simplify", dict(self.params),
                                       meshes.daemon_arrays(positions, triangles, groups),
                                       span=(mid, hi), label=item.label)
            self.reports.append(result)
            if result.get("note"):
                self.warnings.append("%s: %s" % (item.label, result["note"]))
            self._keep(item, result, arrays, count)

    def _keep(self, item: Any, result: Dict[str, Any], arrays: Dict[str, Any], count: int) -> None:
        out_groups = arrays.get("face_groups")
        mesh = meshes.build_mesh(arrays["positions"], meshes.triangles_of(arrays),
                                 None if out_groups is None else np.asarray(out_groups), count)
        cells = None
        if "cells_min" in arrays:
            cells = partition.boxes(arrays["cells_min"], arrays["cells_max"])
        self.results.append((item.label, mesh, cells))

    def _apply(self, doc: Any) -> List[Any]:
        out, self.partitions = [], []
        for label, mesh, cells in self.results:
            feature = self.new_object(doc, "Mesh::Feature", label + "_simplified")
            feature.Mesh = mesh
            out.append(feature)
            if cells is not None:
                wire = self.new_object(doc, "Part::Feature", label + "_partition")
                wire.Shape = cells
                self.partitions.append(wire)
        return out


class SimplifyPreviewTask(SimplifyTask):
    """The live preview: one object simplified, nothing added to the document; apply()
    returns ``{"vertices", "faces", "surface_error"}`` (the error in mm; None for the grid
    goal) and the daemon's whole report under ``"report"``."""

    title = "Simplify preview"
    changes_document = False

    def _keep(self, item: Any, result: Dict[str, Any], arrays: Dict[str, Any], count: int) -> None:
        pass  # the counts are in the report; the mesh is not wanted

    def _apply(self, doc: Any) -> Dict[str, Any]:
        r = self.reports[0]
        return {"vertices": r.get("output_vertices"), "faces": r.get("output_faces"),
                "surface_error": r.get("surface_error"), "report": r}


__all__ = ["PART_TOLERANCE", "SimplifyPreviewTask", "SimplifyTask", "simplify_params",
           "source_mesh"]
