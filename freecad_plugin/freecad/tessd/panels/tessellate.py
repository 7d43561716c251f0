"""Tessellate precisely…: a chordal tolerance (a length, or a percentage of each part's
bounding-box diagonal) and an angle, as FreeCAD's own MeshPart "Standard" mesher asks
(surface deviation, angular deflection), run by ``api.tessellate``."""

import math

from ..qt import QtWidgets
from . import common


class TessellatePanel(common.TaskPanel):
    title = "Tessellate precisely"
    icon = "tessellate"
    op = "tessellate"

    def __init__(self, objects):
        super().__init__(objects)
        form = QtWidgets.QFormLayout(self.body)
        self.tolerance = common.LengthField("0.1mm", percent_of="diagonal")
        self.tolerance.setObjectName("tolerance")
        self.tolerance.setToolTip("Every point of the mesh is within this distance of the "
                                  "surface (chordal deviation)")
        form.addRow("Tolerance:", self.tolerance)
        self.angle = QtWidgets.QDoubleSpinBox()
        self.angle.setObjectName("angle")
        self.angle.setRange(1.0, 90.0)
        self.angle.setDecimals(2)
        self.angle.setSuffix(" \u00b0")
        self.angle.setValue(math.degrees(0.5))
        self.angle.setToolTip("The most two neighbouring facets' normals may turn (angular "
                              "deflection)")
        form.addRow("Angle:", self.angle)
        note = QtWidgets.QLabel("One new mesh per part, <Label>_mesh: watertight for a closed "
                                "part, one mesh segment per B-Rep face.")
        note.setWordWrap(True)
        form.addRow(note)

    def arguments(self):
        return {"tolerance": self.tolerance.text(),
                "angle": round(math.radians(self.angle.value()), 6)}
