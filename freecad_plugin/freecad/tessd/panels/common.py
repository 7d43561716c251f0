"""What the task panels share: the selection they act on, length fields with units or %,
a path field, and :class:`TaskPanel`, FreeCAD's TaskPanel protocol over a ``jobs.Job``.

A panel builds its fields, reads them as the keyword arguments of its ``api`` function
(``arguments()``), and OK runs ``api.prepare_<op>(objects, **arguments)`` as a ``jobs.Job``:
the panel stays open, its fields disabled, while the job runs (progress and Cancel in the
status bar); when the job is done the panel closes (and the Report view's log has the
equivalent ``api`` line for a macro), when it failed or was cancelled the panel stays for
another try. Cancel (the panel's) cancels a running job and closes the panel; so does FreeCAD
closing the dialog in any other way.
"""

import os
import re

import FreeCAD
import FreeCADGui
import Part

from .. import api, jobs, shapes
from ..qt import QtCore, QtGui, QtWidgets

#: Units a length field offers, as the daemon reads them (docs/protocol.md: mm, cm, m, in;
#: "%" is a percentage of the bounding-box diagonal or largest side, as each field says).
LENGTH_UNITS = ("mm", "cm", "m", "in")

ICONS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                     "resources", "icons")


def icon_path(name):
    """The SVG of ``name`` (e.g. ``"simplify"``) in resources/icons."""
    return os.path.join(ICONS, name + ".svg")


# -- the selection ----------------------------------------------------------------------------

def selected(parts=True, meshes=True):
    """The selected objects a command can act on, in selection order, each once: Part objects
    (``parts``), Mesh objects (``meshes``), and containers (App::Part, groups) holding some,
    which the API takes for their visible contents (``shapes.resolve``)."""
    out = []
    for obj in FreeCADGui.Selection.getSelection():
        if obj in out:
            continue
        if shapes.is_container(obj):
            try:
                inside = shapes.resolve([obj])
            except ValueError:  # nothing usable inside
                continue
            if any((parts and shapes.is_part(o)) or (meshes and shapes.is_mesh(o))
                   for o in inside):
                out.append(obj)
        elif (parts and shapes.is_part(obj)) or (meshes and shapes.is_mesh(obj)):
            out.append(obj)
    return out


def _facets(obj):
    """The facets of a Mesh object (or of the mesh a link points to)."""
    getter = getattr(obj, "getLinkedObject", None)
    target = (getter(True) if getter is not None else None) or obj
    return target.Mesh.CountFacets


def triangle_count(objects):
    """The facets of the meshes among ``objects`` (containers resolved), and whether any
    Part object is among them (its tessellation is not known before it is made)."""
    count, has_parts = 0, False
    for obj in shapes.resolve(objects):
        if shapes.is_mesh(obj):
            count += _facets(obj)
        else:
            has_parts = True
    return count, has_parts


def describe(obj):
    """What the object list says about ``obj``."""
    if shapes.is_container(obj):
        return "%d objects inside" % len(shapes.resolve([obj]))
    if shapes.is_mesh(obj):
        return "mesh, %d triangles" % _facets(obj)
    return "part, %d faces" % len(Part.getShape(obj).Faces)


class ObjectList(QtWidgets.QListWidget):
    """The objects a panel acts on, with their icons and what they are; read-only."""

    def __init__(self, objects, parent=None):
        super().__init__(parent)
        self.setObjectName("tessdObjects")
        self.setSelectionMode(QtWidgets.QAbstractItemView.NoSelection)
        for obj in objects:
            item = QtWidgets.QListWidgetItem("%s  (%s)" % (obj.Label, describe(obj)))
            try:
                item.setIcon(obj.ViewObject.Icon)
            except Exception:  # no view provider (freecadcmd) or no icon
                pass
            self.addItem(item)
        rows = max(1, min(len(objects), 4))
        self.setMaximumHeight(self.sizeHintForRow(0) * rows + 2 * self.frameWidth() + 4)


# -- fields -----------------------------------------------------------------------------------

_LENGTH = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(mm|cm|m|in|%)?\s*$")


def parse_length(text, default_unit="mm"):
    """``"0.1mm"`` → ``(0.1, "mm")``, ``"0.5 %"`` → ``(0.5, "%")``, ``"2"`` → ``(2.0,
    default_unit)``; ValueError for anything else."""
    m = _LENGTH.match(str(text))
    if not m:
        raise ValueError("not a length with units (mm, cm, m, in) or a percentage: %r" % text)
    return float(m.group(1)), m.group(2) or default_unit


def format_number(x):
    """A short text for ``x``: no trailing zeros, no exponent for everyday values."""
    return ("%.6g" % x) if (x == 0 or 1e-4 <= abs(x) < 1e6) else ("%g" % x)


class LengthField(QtWidgets.QWidget):
    """A positive length with its unit: a spin box and a unit combo (mm, cm, m, in, and "%" of
    ``percent_of`` when given). ``text()`` is what the API takes: ``"0.1mm"``, ``"0.5%"``."""

    changed = QtCore.Signal()

    def __init__(self, value="0.1mm", percent_of=None, units=LENGTH_UNITS, parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.spin = QtWidgets.QDoubleSpinBox()
        self.spin.setDecimals(4)
        self.spin.setRange(0.0001, 1e6)
        self.spin.setSingleStep(0.1)
        self.spin.setKeyboardTracking(False)
        self.spin.setAccelerated(True)
        self.unit = QtWidgets.QComboBox()
        for u in units:
            self.unit.addItem(u, u)
        if percent_of:
            self.unit.addItem("% of " + percent_of, "%")
        layout.addWidget(self.spin, 1)
        layout.addWidget(self.unit)
        self.set_text(value)
        self.spin.valueChanged.connect(lambda *_: self.changed.emit())
        self.unit.currentIndexChanged.connect(lambda *_: self.changed.emit())

    def text(self):
        return format_number(self.spin.value()) + self.unit.currentData()

    def set_text(self, text):
        value, unit = parse_length(text, self.unit.itemData(0))
        index = self.unit.findData(unit)
        if index < 0:
            raise ValueError("this field takes %s, not %r"
                             % (", ".join(self.unit.itemData(i) for i in
                                          range(self.unit.count())), unit))
        self.unit.setCurrentIndex(index)
        self.spin.setValue(value)


class PathField(QtWidgets.QWidget):
    """A file path with a "..." button opening a save dialog for ``file_filter``."""

    changed = QtCore.Signal()

    def __init__(self, path="", file_filter="All files (*)", caption="Save as", parent=None):
        super().__init__(parent)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.edit = QtWidgets.QLineEdit(path)
        self.button = QtWidgets.QToolButton()
        self.button.setText("...")
        self.button.setToolTip(caption)
        layout.addWidget(self.edit, 1)
        layout.addWidget(self.button)
        self._filter = file_filter
        self._caption = caption
        self.button.clicked.connect(self._browse)
        self.edit.textChanged.connect(lambda *_: self.changed.emit())

    def _browse(self):
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, self._caption, self.text(),
                                                        self._filter)
        if path:
            self.edit.setText(path)

    def text(self):
        return self.edit.text().strip()

    def set_text(self, path):
        self.edit.setText(path)


def default_path(objects, suffix):
    """``<document folder or home>/<first object's label><suffix>``."""
    doc = objects[0].Document if objects else FreeCAD.ActiveDocument
    folder = os.path.dirname(doc.FileName) if doc is not None and doc.FileName else \
        os.path.expanduser("~")
    stem = re.sub(r"[^\w.-]+", "_", objects[0].Label) if objects else "tessd"
    return os.path.join(folder, stem + suffix)


def combo(items, current=None):
    """A QComboBox of ``(label, data)`` pairs with ``current`` (a data value) selected."""
    box = QtWidgets.QComboBox()
    for label, data in items:
        box.addItem(label, data)
    if current is not None:
        box.setCurrentIndex(box.findData(current))
    return box


def set_combo(box, data):
    """Selects the item of ``box`` whose data is ``data`` (ValueError when there is none)."""
    index = box.findData(data)
    if index < 0:
        raise ValueError("no choice %r in %s" % (data, box.objectName() or "this list"))
    box.setCurrentIndex(index)


# -- the TaskPanel protocol -------------------------------------------------------------------

def script_line(op, objects, arguments):
    """The console call that does what a panel did, e.g. ``api.simplify([App.getDocument(
    "Doc").getObject("Box")], method='quality', max_error='0.5%')``."""
    refs = ", ".join("App.getDocument(%r).getObject(%r)" % (o.Document.Name, o.Name)
                     for o in objects)
    args = "".join(", %s=%r" % item for item in arguments.items())
    return "api.%s([%s]%s)" % (op, refs, args)


_latest = None


def latest_panel():
    """The task panel opened last (scripts and tests reach a command's panel through it)."""
    return _latest


class TaskPanel:
    """FreeCAD's TaskPanel protocol (``form``, ``accept``, ``reject``,
    ``getStandardButtons``) over one ``jobs.Job``. Subclasses set ``title``, ``icon`` and
    ``op`` (the ``api`` function), build their fields in ``self.body`` (a QWidget under the
    object list) and return the function's keyword arguments from ``arguments()`` (ValueError
    for a field to fix); they may override ``prepare()`` and ``finished(job)``."""

    title = "tessd"
    icon = "tessd"
    op = None

    def __init__(self, objects):
        global _latest
        _latest = self
        self.objects = list(objects)
        self.doc = self.objects[0].Document if self.objects else FreeCAD.ActiveDocument
        self.job = None
        self._closed = False
        self.form = QtWidgets.QWidget()
        self.form.setObjectName("tessdPanel")
        self.form.setWindowTitle(self.title)
        self.form.setWindowIcon(QtGui.QIcon(icon_path(self.icon)))
        layout = QtWidgets.QVBoxLayout(self.form)
        layout.addWidget(ObjectList(self.objects))
        self.body = QtWidgets.QWidget()
        layout.addWidget(self.body)
        # However the panel goes (OK, Cancel, FreeCAD closing the dialog with the document),
        # its timers stop and a job still running is cancelled once the form is gone.
        self.form.destroyed.connect(self._form_destroyed)
        self.state = QtWidgets.QLabel("")
        self.state.setObjectName("tessdState")
        self.state.setWordWrap(True)
        layout.addWidget(self.state)
        layout.addStretch(1)

    # -- FreeCAD calls these ----------------------------------------------------------------

    def getStandardButtons(self):
        return int(QtWidgets.QDialogButtonBox.Ok | QtWidgets.QDialogButtonBox.Cancel)

    def accept(self):
        """OK: starts the job and keeps the panel open until it is done (returns False)."""
        if self.job is not None and not self.job.done:
            return False
        try:
            task = self.prepare()
        except (ValueError, api.TessdError) as e:
            self.state.setText("Not started: %s" % jobs.describe_error(e))
            jobs.show_error("tessd: " + self.title, jobs.describe_error(e))
            return False
        self.set_busy(True)
        self.state.setText("Running... (Cancel, here or in the status bar, stops it)")
        self.job = jobs.Job(task, doc=self.doc, on_finished=self._job_finished).start()
        return False

    def reject(self):
        """Cancel: cancels a running job (nothing is applied) and closes the panel."""
        if self.job is not None and not self.job.done:
            self.job.cancel()
        self._closing()
        return True

    # -- for subclasses ---------------------------------------------------------------------

    def arguments(self):
        """The ``api.<op>`` keyword arguments the fields hold (ValueError for a bad field)."""
        raise NotImplementedError

    def prepare(self):
        """The task OK runs: ``api.prepare_<op>(objects, **arguments())``."""
        return getattr(api, "prepare_" + self.op)(self.objects, **self.arguments())

    def finished(self, job):
        """Called when the job is DONE, before the panel closes."""

    def closed(self):
        """Called once when the panel closes (stop timers, previews)."""

    def set_busy(self, busy):
        self.body.setEnabled(not busy)

    # -- internals ----------------------------------------------------------------------------

    def _job_finished(self, job):
        if self._closed:
            return
        self.set_busy(False)
        if job.state == jobs.DONE:
            self.state.setText("Done in %.1f s." % job.seconds)
            try:
                FreeCAD.Console.PrintLog("tessd: from freecad.tessd import api; %s\n"
                                         % script_line(self.op, self.objects, self.arguments()))
            except ValueError:
                pass
            self.finished(job)
            self.close()
        elif job.state == jobs.CANCELLED:
            self.state.setText("Cancelled: the document is unchanged.")
        else:
            self.state.setText("Failed: %s" % job.error)

    def _form_destroyed(self, *_):
        if self.job is not None and not self.job.done:
            self.job.cancel()
        self._closing()

    def _closing(self):
        if not self._closed:
            self._closed = True
            self.closed()

    def close(self):
        """Closes this panel (when it is the one shown)."""
        self._closing()
        if FreeCADGui.Control.activeDialog():
            FreeCADGui.Control.closeDialog()
