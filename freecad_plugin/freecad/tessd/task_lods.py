"""Generate LODs: a chain of levels of detail per object, in a group, and as a USD stage.

The daemon's `lod` simplifies every level from the input in one request (shared preparation;
each level's bound holds against the input): `levels` are the goals of LOD1, LOD2, ... as the
CLI's `--levels` ("50%,20%,5%": complexity goals, vertex percentages). Each object gets an
App::DocumentObjectGroup `<Label>_LODs` holding Mesh::Features `<Label>_LOD0` (the input: a
Part object's 0.1 mm tessellation, or a copy of the mesh) to `<Label>_LOD<n>`, all but LOD0
hidden so that one level shows at a time, each keeping its source's segments. With
``usd_path`` the daemon also writes the chain as a USD stage (a `LOD` variant set, or the
UsdLod schema), in millimetres and Z up as FreeCAD models; with several objects each gets its
own stage beside that path, `<stem>_<Label>.usda`.
"""

import os
import re
from typing import Any, Dict, List, Optional

import numpy as np

from . import meshes
from .shapes import PartInput
from .task import Task
from .task_simplify import source_mesh


def stage_paths(usd_path: Optional[str], labels: List[str]) -> List[Optional[str]]:
    """The stage of each object: ``usd_path`` for one object, `<stem>_<Label><ext>` beside it
    for several (absolute paths: the daemon's working folder is not FreeCAD's)."""
    if not usd_path:
        return [None] * len(labels)
    path = os.path.abspath(os.path.expanduser(os.fspath(usd_path)))
    if len(labels) == 1:
        return [path]
    stem, ext = os.path.splitext(path)
    return ["%s_%s%s" % (stem, re.sub(r"[^A-Za-z0-9_.-]+", "_", label), ext) for label in labels]


class LodsTask(Task):
    """See the module's notes. ``lod``: extra params of the daemon's `lod` (method,
    representative, lod_schema, ...)."""

    title = "Generate LODs"

    def __init__(self, inputs: List[Any], levels: Any, usd_path: Optional[str] = None,
                 lod: Optional[Dict[str, Any]] = None, doc: Any = None):
        super().__init__(doc)
        self.inputs = inputs
        self.levels = levels
        self.paths = stage_paths(usd_path, [i.label for i in inputs])
        self.lod = dict(lod or {})
        #: (label, [Mesh.Mesh per level, LOD0 first], stage path or None) per input, once run.
        self.chains: List[tuple] = []

    def _run(self, client: Any) -> None:
        self.chains, self.reports = [], []
        n = len(self.inputs)
        for i, (item, path) in enumerate(zip(self.inputs, self.paths)):
            lo, hi = i / n, (i + 1) / n
            mid = lo + 0.5 * (hi - lo) if isinstance(item, PartInput) else lo
            positions, triangles, groups, count = source_mesh(self, client, item, (lo, mid))
            p = dict(self.lod, levels=self.levels)
            if path:
                p.update(output=path, return_arrays=True, name=item.label, meters_per_unit=0.001,
                         up_axis="Z")
                if groups is not None:  # the stage's GeomSubsets, named as export_usd names them
                    stem = "face" if isinstance(item, PartInput) else "segment"
                    p["group_names"] = ["%s%d" % (stem, g + 1) for g in range(count)] + ["unsegmented"]
            result, arrays = self.call(client, "lod", p,
                                       meshes.daemon_arrays(positions, triangles, groups),
                                       span=(mid, hi), label=item.label)
            self.reports.append(result)
            chain = [meshes.build_mesh(positions, triangles, groups, count)]
            for level in range(1, len(result["levels"]) + 1):
                prefix = "lod%d." % level
                g = arrays.get(prefix + "face_groups")
                chain.append(meshes.build_mesh(arrays[prefix + "positions"],
                                               meshes.triangles_of(arrays, prefix),
                                               None if g is None else np.asarray(g), count))
                note = result["levels"][level - 1].get("note")
                if note:
                    self.warnings.append("%s LOD%d: %s" % (item.label, level, note))
            self.chains.append((item.label, chain, result.get("output")))

    def _apply(self, doc: Any) -> List[Any]:
        groups = []
        for label, chain, stage in self.chains:
            group = self.new_object(doc, "App::DocumentObjectGroup", label + "_LODs")
            if stage:
                group.addProperty("App::PropertyFile", "UsdStage", "tessd",
                                  "The USD stage of this LOD chain")
                group.UsdStage = stage
            for level, mesh in enumerate(chain):
                feature = self.new_object(doc, "Mesh::Feature", "%s_LOD%d" % (label, level))
                feature.Mesh = mesh
                feature.Visibility = level == 0
                group.addObject(feature)
            groups.append(group)
        return groups


__all__ = ["LodsTask", "stage_paths"]
