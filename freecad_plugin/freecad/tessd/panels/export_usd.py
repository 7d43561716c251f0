"""Export USD…: the stage's path and the tessellation tolerance of Part objects, over
``api.export_usd`` (the document is not changed)."""

from ..qt import QtWidgets
from . import common


class ExportUsdPanel(common.TaskPanel):
    title = "Export USD"
    icon = "export_usd"
    op = "export_usd"

    def __init__(self, objects):
        super().__init__(objects)
        form = QtWidgets.QFormLayout(self.body)
        self.path = common.PathField(common.default_path(objects, ".usda"),
                                     "USD stages (*.usda)", "Export USD")
        self.path.setObjectName("path")
        form.addRow("File:", self.path)
        self.tolerance = common.LengthField("0.1mm", percent_of="diagonal")
        self.tolerance.setObjectName("tolerance")
        self.tolerance.setToolTip("Part objects are tessellated within this distance of "
                                  "their surfaces")
        form.addRow("Tolerance:", self.tolerance)
        note = QtWidgets.QLabel("One stage: the document's tree as Xforms with the "
                                "placements, one GeomSubset per B-Rep face, the view "
                                "colours; millimetres, Z up.")
        note.setWordWrap(True)
        form.addRow(note)

    def arguments(self):
        if not self.path.text():
            raise ValueError("choose the USD file to write")
        return {"path": self.path.text(), "tolerance": self.tolerance.text()}

    def finished(self, job):
        self.state.setText("Wrote %s" % job.result)
