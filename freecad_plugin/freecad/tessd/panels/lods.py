"""Generate LODs…: the levels (vertex percentages or counts, as ``tessd lod --levels``) and,
optionally, a USD stage holding the chain as a ``LOD`` variant set, over
``api.generate_lods``."""

import re

from ..qt import QtWidgets
from . import common

_LEVELS = re.compile(r"^\s*\d+(\.\d+)?\s*%?\s*(,\s*\d+(\.\d+)?\s*%?\s*)*$")


class LodsPanel(common.TaskPanel):
    title = "Generate LODs"
    icon = "lods"
    op = "generate_lods"

    def __init__(self, objects):
        super().__init__(objects)
        form = QtWidgets.QFormLayout(self.body)
        self.levels = QtWidgets.QLineEdit("50%,20%,5%")
        self.levels.setObjectName("levels")
        self.levels.setToolTip("One level per goal after LOD0 (the object itself): vertex "
                               "percentages of LOD0 (\"50%\") or vertex counts (\"2000\"), "
                               "comma-separated")
        form.addRow("Levels:", self.levels)
        self.write_usd = QtWidgets.QCheckBox("Write a USD stage")
        self.write_usd.setObjectName("write_usd")
        self.usd_path = common.PathField(common.default_path(objects, "_lods.usda"),
                                         "USD stages (*.usda *.usd)", "USD stage of the LODs")
        self.usd_path.setObjectName("usd_path")
        self.usd_path.setEnabled(False)
        self.write_usd.toggled.connect(self.usd_path.setEnabled)
        form.addRow(self.write_usd)
        form.addRow("USD file:", self.usd_path)
        note = QtWidgets.QLabel("A group <Label>_LODs per object, holding <Label>_LOD0 to "
                                "<Label>_LOD<n>; the stage has a LOD variant set (several "
                                "objects: one <file>_<Label>.usda each).")
        note.setWordWrap(True)
        form.addRow(note)

    def arguments(self):
        levels = self.levels.text().strip()
        if not _LEVELS.match(levels):
            raise ValueError("levels must be comma-separated vertex percentages or counts, "
                             "such as 50%%,20%%,5%%; got %r" % levels)
        args = {"levels": levels.replace(" ", "")}
        if self.write_usd.isChecked():
            if not self.usd_path.text():
                raise ValueError("choose the USD file, or untick \"Write a USD stage\"")
            args["usd_path"] = self.usd_path.text()
        return args
