"""Render precise image: a PNG of Part objects through the daemon's `render` (paper 001).

Part objects, placed in the world, go to the daemon as one B-Rep (a compound when there are
several) in OpenCASCADE's BREP text — or, where the daemon's reader answers `unsupported`, as
the Part API walk's document — which it renders headless on the GPU (lavapipe without one) with per-frame
tessellation, GPU trimming and crack filling (``cracks``: "object", "image" or "none"); Mesh
objects are rendered as meshes, one face id per object. Parts and meshes cannot share one
picture (the op renders one B-Rep document, or meshes). The camera is a standard view fitted
to the objects ("iso", "front", ...) or, with the GUI up, the active 3D view's (camera.py).
"""

import os
from typing import Any, Dict, List, Optional

import numpy as np
import Part
from tessd.client import TessdError

from . import tessellation
from .shapes import MeshInput, PartInput
from .task import Task


class RenderTask(Task):
    """See the module's notes. ``camera``: the explicit camera (``eye``, ``target``, ``up``,
    ``fov``) or None for ``view``; ``extra``: more `render` params (shading, edges, ...)."""

    title = "Render"
    changes_document = False

    def __init__(self, inputs: List[Any], path: str, size: tuple, view: str = "iso",
                 camera: Optional[Dict[str, Any]] = None, cracks: str = "object",
                 extra: Optional[Dict[str, Any]] = None, doc: Any = None):
        super().__init__(doc)
        kinds = {type(i) for i in inputs}
        if len(kinds) > 1:
            raise ValueError("render draws Part objects (precisely, from their B-Rep) or Mesh "
                             "objects, not both in one picture: %s"
                             % ", ".join("%s (%s)" % (i.label, "mesh" if isinstance(i, MeshInput)
                                                      else "part") for i in inputs))
        self.inputs = inputs
        self.path = os.path.abspath(os.path.expanduser(os.fspath(path)))
        self.params: Dict[str, Any] = {"output": self.path, "size": [int(size[0]), int(size[1])]}
        if camera is not None:
            self.params.update(camera)
        else:
            self.params["view"] = view
        if isinstance(inputs[0], PartInput):
            self.params["cracks"] = cracks
        self.params.update(extra or {})

    def _run(self, client: Any) -> None:
        params = dict(self.params)
        if isinstance(self.inputs[0], PartInput):
            shapes = [p.shape for p in self.inputs]
            shape = shapes[0] if len(shapes) == 1 else Part.makeCompound(shapes)
            label = ", ".join(p.label for p in self.inputs)
            self.report(0.0, "exporting the B-Rep")
            try:
                result, _ = self.call(client, "render",
                                      {**params, **tessellation.brep_params(shape, label)},
                                      span=(0.1, 1.0))
            except TessdError as e:
                if e.code != "unsupported":
                    raise
                # geometry the daemon's BREP reader has no exact type for: the Part API walk
                params.update(tessellation.brep_params(shape, label, native=False))
                result, _ = self.call(client, "render", params, span=(0.1, 1.0))
        else:
            result, _ = self.call(client, "render", params, self._mesh_arrays(),
                                  span=(0.1, 1.0))
        self.reports = [result]
        self.warnings.extend(result.get("warnings") or ())

    def _mesh_arrays(self) -> Dict[str, Any]:
        """The meshes merged, each object its own face id."""
        positions, triangles, groups, base = [], [], [], 0
        for k, m in enumerate(self.inputs):
            positions.append(m.positions)
            triangles.append(m.triangles + base)
            groups.append(np.full(len(m.triangles), k))
            base += len(m.positions)
        return {"positions": np.concatenate(positions).astype(np.float32),
                "face_indices": np.concatenate(triangles).astype(np.uint32),
                "face_groups": np.concatenate(groups).astype(np.uint32)}

    def _apply(self, doc: Any) -> str:
        return self.path


__all__ = ["RenderTask"]
