"""Simplify…: the simplification dialog of paper 004, section 6 (its AutoCAD plug-in, figure 7),
over ``api.simplify``.

The user picks a goal — a regular grid (cells per axis, or a cell size), a quality (the largest
distance the surface may move: a length, or a percentage of the largest side) or a complexity
(a vertex count, or a percentage of the input's) — with its numeric parameter, the cells'
representative (quadric, weighted barycentre, heaviest vertex), whether boundary edges are kept
and whether the partition used is shown in the document afterwards (`<Label>_partition`).

A live preview shows the vertex count and surface error the settings give, for inputs under
:data:`PREVIEW_MAX_TRIANGLES` triangles: each change restarts a short timer
(:data:`PREVIEW_DELAY_MS`), then ``api.prepare_simplify_preview`` runs per object on a worker
thread (``jobs.Job`` without status bar or message box); a newer change cancels the preview
running. The objects are read once: later previews reuse what the first one read.
"""

from .. import jobs
from ..qt import QtCore, QtWidgets
from . import common

#: The issue's limit for the live preview: inputs of fewer triangles than this are previewed
#: (a million-triangle mesh simplifies in about a second on two cores, a preview the user can
#: wait for; larger ones would lag behind the fields).
PREVIEW_MAX_TRIANGLES = 1_000_000
#: Pause after the last change before a preview starts (typing a number is several changes).
PREVIEW_DELAY_MS = 400

GOALS = (("grid", "Regular grid", "A regular grid over the bounding box: each cell's "
          "vertices merge into one"),
         ("quality", "Quality", "Cells split until no vertex moves farther than the maximum "
          "error"),
         ("complexity", "Complexity", "Cells split until the result has the target number "
          "of vertices"))

REPRESENTATIVES = (("Quadric (least surface error)", "quadric"),
                   ("Weighted barycentre", "barycenter"),
                   ("Heaviest vertex", "heaviest"))


class PreviewBatch:
    """The previews of several objects as one task for ``jobs.Job``: ``run`` runs them in
    turn, ``apply`` adds their counts up and keeps the largest error."""

    title = "Simplify preview"

    def __init__(self, tasks):
        self.tasks = tasks

    def run(self, progress=None, cancel=None):
        n = len(self.tasks)
        for i, task in enumerate(self.tasks):
            def part(fraction, message, i=i):
                if progress is not None:
                    progress((i + fraction) / n, message)
            task.run(progress=part, cancel=cancel)

    def apply(self, doc=None):
        results = [task.apply(doc) for task in self.tasks]
        errors = [r["surface_error"] for r in results if r.get("surface_error") is not None]
        reports = [r.get("report") or {} for r in results]
        return {"vertices": sum(r["vertices"] or 0 for r in results),
                "faces": sum(r["faces"] or 0 for r in results),
                "surface_error": max(errors) if errors else None,
                "input_vertices": sum(r.get("input_vertices") or 0 for r in reports),
                "input_faces": sum(r.get("input_faces") or 0 for r in reports),
                "notes": [r["note"] for r in reports if r.get("note")]}


class SimplifyPanel(common.TaskPanel):
    title = "Simplify"
    icon = "simplify"
    op = "simplify"

    def __init__(self, objects):
        super().__init__(objects)
        outer = QtWidgets.QVBoxLayout(self.body)
        outer.setContentsMargins(0, 0, 0, 0)
        outer.addWidget(self._goal_box())
        outer.addWidget(self._options_box())
        outer.addWidget(self._preview_box())

        self.last_preview = None  # what the latest preview gave (apply()'s dict, summed)
        self._preview_job = None
        self._preview_generation = 0
        self._preview_tasks = {}  # object name -> the first preview task (its inputs are reused)
        self._preview_timer = QtCore.QTimer()
        self._preview_timer.setSingleShot(True)
        self._preview_timer.setInterval(PREVIEW_DELAY_MS)
        self._preview_timer.timeout.connect(self._start_preview)
        triangles, has_parts = common.triangle_count(self.objects)
        self._too_big = None
        if triangles >= PREVIEW_MAX_TRIANGLES:
            self._too_big = triangles
        self._has_parts = has_parts
        self.set_goal("complexity")
        for signal in self._change_signals():
            signal.connect(self._changed)
        self._changed()

    # -- the form ---------------------------------------------------------------------------

    def _goal_box(self):
        box = QtWidgets.QGroupBox("Goal")
        layout = QtWidgets.QVBoxLayout(box)
        self.goal_buttons = {}
        row = QtWidgets.QHBoxLayout()
        for key, label, tip in GOALS:
            button = QtWidgets.QRadioButton(label)
            button.setObjectName("goal_" + key)
            button.setToolTip(tip)
            self.goal_buttons[key] = button
            row.addWidget(button)
        layout.addLayout(row)

        self.pages = QtWidgets.QStackedWidget()
        layout.addWidget(self.pages)

        grid = QtWidgets.QWidget()
        g = QtWidgets.QGridLayout(grid)
        g.setContentsMargins(0, 0, 0, 0)
        self.use_cells = QtWidgets.QRadioButton("Cells per axis:")
        self.use_cells.setObjectName("use_cells")
        self.use_cell_size = QtWidgets.QRadioButton("Cell size:")
        self.use_cell_size.setObjectName("use_cell_size")
        self.use_cells.setChecked(True)
        self.cells = QtWidgets.QSpinBox()
        self.cells.setObjectName("cells")
        self.cells.setRange(1, 4096)
        self.cells.setValue(32)
        self.cells.setKeyboardTracking(False)
        self.cell_size = common.LengthField("1mm")
        self.cell_size.setObjectName("cell_size")
        g.addWidget(self.use_cells, 0, 0)
        g.addWidget(self.cells, 0, 1)
        g.addWidget(self.use_cell_size, 1, 0)
        g.addWidget(self.cell_size, 1, 1)

        quality = QtWidgets.QWidget()
        q = QtWidgets.QFormLayout(quality)
        q.setContentsMargins(0, 0, 0, 0)
        self.max_error = common.LengthField("0.5%", percent_of="largest side")
        self.max_error.setObjectName("max_error")
        self.max_error.setToolTip("No vertex moves farther than this")
        q.addRow("Maximum error:", self.max_error)

        complexity = QtWidgets.QWidget()
        c = QtWidgets.QFormLayout(complexity)
        c.setContentsMargins(0, 0, 0, 0)
        target = QtWidgets.QWidget()
        t = QtWidgets.QHBoxLayout(target)
        t.setContentsMargins(0, 0, 0, 0)
        self.target = QtWidgets.QDoubleSpinBox()
        self.target.setObjectName("target")
        self.target.setKeyboardTracking(False)
        self.target_unit = common.combo((("% of the vertices", "%"), ("vertices", "count")),
                                        "%")
        self.target_unit.setObjectName("target_unit")
        t.addWidget(self.target, 1)
        t.addWidget(self.target_unit)
        c.addRow("Target:", target)
        self._target_unit_changed()
        self.target.setValue(20.0)
        self.target_unit.currentIndexChanged.connect(self._target_unit_changed)

        for page in (grid, quality, complexity):
            self.pages.addWidget(page)
        for button in self.goal_buttons.values():
            button.toggled.connect(self._goal_toggled)
        return box

    def _options_box(self):
        box = QtWidgets.QGroupBox("Options")
        form = QtWidgets.QFormLayout(box)
        self.representative = common.combo(REPRESENTATIVES, "quadric")
        self.representative.setObjectName("representative")
        self.representative.setToolTip("The point each cell's vertices merge into")
        form.addRow("Representative:", self.representative)
        self.preserve_boundaries = QtWidgets.QCheckBox("Preserve boundaries")
        self.preserve_boundaries.setObjectName("preserve_boundaries")
        self.preserve_boundaries.setToolTip("Keep open boundary edges where they are")
        form.addRow(self.preserve_boundaries)
        self.show_partition = QtWidgets.QCheckBox("Show partition")
        self.show_partition.setObjectName("show_partition")
        self.show_partition.setToolTip("Add the cells used, as wire boxes "
                                       "(<Label>_partition)")
        form.addRow(self.show_partition)
        return box

    def _preview_box(self):
        box = QtWidgets.QGroupBox("Preview")
        layout = QtWidgets.QVBoxLayout(box)
        self.preview = QtWidgets.QLabel()
        self.preview.setObjectName("preview")
        self.preview.setWordWrap(True)
        self.preview.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        layout.addWidget(self.preview)
        return box

    def _change_signals(self):
        return (self.cells.valueChanged, self.cell_size.changed, self.use_cells.toggled,
                self.max_error.changed, self.target.valueChanged,
                self.target_unit.currentIndexChanged, self.representative.currentIndexChanged,
                self.preserve_boundaries.toggled)

    def _target_unit_changed(self, *_):
        if self.target_unit.currentData() == "%":
            self.target.setDecimals(2)
            self.target.setRange(0.01, 100.0)
            self.target.setSuffix(" %")
        else:
            self.target.setDecimals(0)
            self.target.setRange(3, 1e9)
            self.target.setSuffix("")

    def _goal_toggled(self, checked):
        if checked:
            self.pages.setCurrentIndex([g[0] for g in GOALS].index(self.goal()))
            self._changed()

    # -- values -----------------------------------------------------------------------------

    def goal(self):
        return next((k for k, b in self.goal_buttons.items() if b.isChecked()), "complexity")

    def set_goal(self, goal):
        self.goal_buttons[goal].setChecked(True)
        self.pages.setCurrentIndex([g[0] for g in GOALS].index(goal))

    def arguments(self, preview=False):
        goal = self.goal()
        args = {"method": goal}
        if goal == "grid":
            if self.use_cells.isChecked():
                args["cells"] = self.cells.value()
            else:
                args["cell_size"] = self.cell_size.text()
        elif goal == "quality":
            args["max_error"] = self.max_error.text()
        else:
            value = self.target.value()
            args["target"] = ("%s%%" % common.format_number(value)
                              if self.target_unit.currentData() == "%" else int(round(value)))
        args["representative"] = self.representative.currentData()
        if not preview:
            args["show_partition"] = self.show_partition.isChecked()
        if self.preserve_boundaries.isChecked():
            args["preserve_boundaries"] = True
        return args

    # -- the live preview -------------------------------------------------------------------

    def _changed(self, *_):
        if self._closed:
            return
        if self._too_big is not None:
            self.preview.setText("No live preview: %s triangles, %s or more are computed on OK "
                                 "only." % (_count(self._too_big),
                                            _count(PREVIEW_MAX_TRIANGLES)))
            return
        self._cancel_preview()
        self.preview.setText("Preview: waiting for the settings to settle...")
        self._preview_timer.start()

    def preview_pending(self):
        """Whether a preview is waiting for the settings to settle or running."""
        return self._preview_timer.isActive() or (
            self._preview_job is not None and not self._preview_job.done)

    def _cancel_preview(self):
        self._preview_generation += 1
        if self._preview_job is not None and not self._preview_job.done:
            self._preview_job.cancel()
        self._preview_job = None

    def _preview_task(self, obj, args):
        """The preview of ``obj``: the first one reads the object (GUI thread, as prepare
        does), later ones reuse what it read with the new settings."""
        first = self._preview_tasks.get(obj.Name)
        if first is None:
            from .. import api
            first = api.prepare_simplify_preview(obj, **args)
            self._preview_tasks[obj.Name] = first
            return first
        from ..task_simplify import simplify_params
        p = dict(args)
        return type(first)(first.inputs, simplify_params(
            p.pop("method"), p.pop("cells", None), p.pop("cell_size", None),
            p.pop("max_error", None), p.pop("target", None), p.pop("representative", None),
            False, p.pop("preserve_boundaries", False)), first.doc)

    def _start_preview(self):
        if self._closed or (self.job is not None and not self.job.done):
            return
        try:
            args = self.arguments(preview=True)
            tasks = [self._preview_task(obj, args) for obj in self._preview_objects()]
        except ValueError as e:
            self.preview.setText("Preview: %s" % e)
            return
        self.preview.setText("Preview: computing...")
        generation = self._preview_generation
        self._preview_job = jobs.Job(
            PreviewBatch(tasks), status=False, report_errors=False,
            on_finished=lambda job: self._preview_done(job, generation)).start()

    def _preview_objects(self):
        from .. import shapes
        return shapes.resolve(self.objects)

    def _preview_done(self, job, generation):
        if self._closed or generation != self._preview_generation:
            return  # settings changed since: a newer preview is on its way
        self._preview_job = None
        if job.state == jobs.FAILED:
            self.preview.setText("Preview: %s" % job.error)
            return
        if job.state != jobs.DONE:
            return
        r = job.result
        if r["input_faces"] >= PREVIEW_MAX_TRIANGLES:
            self._too_big = r["input_faces"]  # a part's tessellation turned out that large
        text = "%s vertices, %s triangles (from %s vertices, %s triangles)" % (
            _count(r["vertices"]), _count(r["faces"]), _count(r["input_vertices"]),
            _count(r["input_faces"]))
        if r["surface_error"] is not None:
            text += "; surface error %.3g mm" % r["surface_error"]
        if r["notes"]:
            text += "\n" + "\n".join(r["notes"])
        self.preview.setText(text)
        self.last_preview = r

    def closed(self):
        self._preview_timer.stop()
        self._cancel_preview()

    def set_busy(self, busy):
        super().set_busy(busy)
        if busy:
            self._preview_timer.stop()
            self._cancel_preview()


def _count(n):
    """1234567 → "1 234 567" (thin spaces, readable in any locale)."""
    return "{:,}".format(int(n)).replace(",", "\u2009")
