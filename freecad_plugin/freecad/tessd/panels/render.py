"""Render precise image…: size, camera (the active 3D view's or a standard view), crack
filling, over ``api.render``. "Render" draws the picture into a temporary PNG in the background
and shows it in the panel; OK saves that picture to the chosen file (or renders straight to it
when the settings changed since, or nothing was rendered yet). The document is not changed.
"""

import os
import shutil
import tempfile

import FreeCADGui

from .. import api, jobs
from ..qt import QtCore, QtGui, QtWidgets
from . import common

VIEWS = (("Active 3D view", "active"), ("Isometric", "iso"), ("Front", "front"),
         ("Back", "back"), ("Left", "left"), ("Right", "right"), ("Top", "top"),
         ("Bottom", "bottom"))

CRACKS = (("Fill in object space (ray casting)", "object"),
          ("Fill in image space", "image"),
          ("No filling", "none"))

#: Width of the picture shown in the panel, in pixels (the task view's usual width).
PREVIEW_WIDTH = 320


def active_view_available():
    """Whether the active document shows a 3D view to take the camera from."""
    gui_doc = FreeCADGui.ActiveDocument
    view = getattr(gui_doc, "ActiveView", None) if gui_doc is not None else None
    return view is not None and hasattr(view, "getCamera")


class RenderPanel(common.TaskPanel):
    title = "Render precise image"
    icon = "render"
    op = "render"

    def __init__(self, objects):
        super().__init__(objects)
        self._rendered = None  # (arguments without the path, temporary PNG) once rendered
        self.saved = None  # the PNG written, once OK saved it
        self._temp_dir = None
        form = QtWidgets.QFormLayout(self.body)

        size = QtWidgets.QWidget()
        row = QtWidgets.QHBoxLayout(size)
        row.setContentsMargins(0, 0, 0, 0)
        self.width = QtWidgets.QSpinBox()
        self.width.setObjectName("width")
        self.height = QtWidgets.QSpinBox()
        self.height.setObjectName("height")
        for spin, value in ((self.width, 1280), (self.height, 720)):
            spin.setRange(16, 8192)
            spin.setValue(value)
            spin.setSuffix(" px")
        row.addWidget(self.width)
        row.addWidget(QtWidgets.QLabel("\u00d7"))
        row.addWidget(self.height)
        form.addRow("Size:", size)

        self.view = common.combo(VIEWS)
        self.view.setObjectName("view")
        if not active_view_available():
            self.view.removeItem(self.view.findData("active"))
        form.addRow("Camera:", self.view)
        self.cracks = common.combo(CRACKS, "object")
        self.cracks.setObjectName("cracks")
        self.cracks.setToolTip("How the gaps between separately tessellated faces are filled "
                               "(paper 001)")
        form.addRow("Cracks:", self.cracks)
        self.path = common.PathField(common.default_path(objects, ".png"), "PNG images (*.png)",
                                     "Save the picture as")
        self.path.setObjectName("path")
        form.addRow("File:", self.path)

        self.render_button = QtWidgets.QPushButton("Render")
        self.render_button.setObjectName("render_button")
        self.render_button.setToolTip("Render into the panel; OK then saves the picture")
        self.render_button.clicked.connect(self.render_preview)
        form.addRow(self.render_button)
        self.picture = QtWidgets.QLabel("(press Render to see the picture here)")
        self.picture.setObjectName("picture")
        self.picture.setAlignment(QtCore.Qt.AlignCenter)
        self.picture.setMinimumHeight(120)
        self.picture.setFrameShape(QtWidgets.QFrame.StyledPanel)
        form.addRow(self.picture)

    def arguments(self, path=None):
        args = {"path": path or self.path.text(), "size": (self.width.value(),
                                                           self.height.value()),
                "view": self.view.currentData(), "cracks": self.cracks.currentData()}
        if not args["path"]:
            raise ValueError("choose the PNG file to save")
        return args

    def _settings(self):
        args = self.arguments(path="-")
        del args["path"]
        return args

    # -- Render: into the panel ---------------------------------------------------------------

    def render_preview(self):
        """Renders the current settings into a temporary PNG and shows it (background job)."""
        if self.job is not None and not self.job.done:
            return
        if self._temp_dir is None:
            self._temp_dir = tempfile.mkdtemp(prefix="tessd-render-")
        path = os.path.join(self._temp_dir, "render.png")
        settings = self._settings()
        try:
            task = api.prepare_render(self.objects, path=path, **settings)
        except (ValueError, api.TessdError) as e:
            jobs.show_error("tessd: " + self.title, jobs.describe_error(e))
            return
        self.set_busy(True)
        self.state.setText("Rendering...")
        self.job = jobs.Job(task, on_finished=lambda job: self._preview_done(job, settings))
        self.job.start()

    def _preview_done(self, job, settings):
        if self._closed:
            return
        self.set_busy(False)
        if job.state != jobs.DONE:
            self.state.setText("Cancelled." if job.state == jobs.CANCELLED
                               else "Failed: %s" % job.error)
            return
        self._rendered = (settings, job.result)
        self.show_picture(job.result)
        self.state.setText("Rendered in %.1f s; OK saves it to the file." % job.seconds)

    def show_picture(self, path):
        pixmap = QtGui.QPixmap(path)
        self.picture.setPixmap(pixmap.scaledToWidth(min(PREVIEW_WIDTH, pixmap.width()),
                                                    QtCore.Qt.SmoothTransformation))

    # -- OK: save ---------------------------------------------------------------------------

    def accept(self):
        if self.job is not None and not self.job.done:
            return False
        try:
            settings = self._settings()
            target = self.arguments()["path"]
        except ValueError as e:
            jobs.show_error("tessd: " + self.title, str(e))
            return False
        if self._rendered is not None and self._rendered[0] == settings:
            try:
                folder = os.path.dirname(os.path.abspath(target))
                os.makedirs(folder, exist_ok=True)
                shutil.copyfile(self._rendered[1], target)
            except OSError as e:
                jobs.show_error("tessd: " + self.title, "could not save %s: %s" % (target, e))
                return False
            self.saved = target
            self._closing()
            return True
        return super().accept()  # nothing rendered with these settings: render to the file

    def finished(self, job):
        self.saved = job.result

    def closed(self):
        if self._temp_dir is not None:
            shutil.rmtree(self._temp_dir, ignore_errors=True)
            self._temp_dir = None
