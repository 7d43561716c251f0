"""Tessellate precisely: one watertight Mesh::Feature per Part object, a segment per face.

Each Part object's shape, placed in the world, is tessellated by the daemon (tessellation.py)
and becomes `<Label>_mesh`, a Mesh::Feature whose segment i holds the triangles of the shape's
face i (`shape.Faces[i]`, FreeCAD's Face<i+1>): a renderer or a simulation can still tell the
faces apart, and a closed part's mesh is closed (every edge shared by two triangles).
"""

from typing import Any, List

from . import meshes
from .shapes import PartInput
from .task import Task
from .tessellation import tessellate_parts


class TessellateTask(Task):
    """See the module's notes; ``inputs`` are PartInputs in the world frame."""

    title = "Tessellate"

    def __init__(self, inputs: List[PartInput], tolerance: Any = "0.1mm", angle: float = 0.5,
                 doc: Any = None):
        super().__init__(doc)
        self.inputs = inputs
        self.tolerance = tolerance
        self.angle = angle
        #: (label, Mesh.Mesh) per input, once run.
        self.meshes: List[tuple] = []

    def _run(self, client: Any) -> None:
        self.meshes, self.reports = [], []
        done = tessellate_parts(self, client, self.inputs, self.tolerance, self.angle)
        for part, t in zip(self.inputs, done):
            self.reports.append(t.result)
            self.warnings.extend(t.warnings(part.label))
            mesh = meshes.build_mesh(t.positions, t.triangles, t.groups, t.face_count)
            self.meshes.append((part.label, mesh))

    def _apply(self, doc: Any) -> List[Any]:
        out = []
        for label, mesh in self.meshes:
            feature = self.new_object(doc, "Mesh::Feature", label + "_mesh")
            feature.Mesh = mesh
            out.append(feature)
        return out


__all__ = ["TessellateTask"]
