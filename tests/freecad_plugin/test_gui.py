"""The tessd workbench in the real FreeCAD GUI, offscreen: the workbench activates, every
command is registered with its icon, each task panel opens, takes values, runs its job off
the GUI thread and leaves the expected objects and exactly one undo step; Cancel of a long job
leaves the document as it was; a daemon error shows a critical message box with the daemon's
words; the Simplify panel's live preview gives the counts the result has.

    bash tests/freecad_plugin/run.sh     # console tests, then these; in essence:
    QT_QPA_PLATFORM=offscreen freecad -P tests/freecad_plugin -P tests -t test_gui

run.sh prepares a throw-away HOME: the workbench linked into its Mod folder
(freecad_plugin/install.py --link), FreeCAD's start-up workbench set to Part (the Start page is a
QtWebEngine view, which aborts offscreen), and TESSD_BIN. The GUI's Python ignores PYTHONPATH,
hence -P. FreeCAD's test runner exits 1 when a test fails or errors; nothing here is skipped:
a missing FreeCAD module, daemon or GUI is an error.

Documents are opened hidden (no 3D view): offscreen Qt has no OpenGL context, and Coin crashes
when a 3D view without one is destroyed (at document close or exit), which would turn a pass
into a crash. For the same reason the tree's "sync view" is turned off while the tests run (it
opens a 3D view for a selected object of a hidden document). So the Render panel is tested
with the standard views; its "Active 3D view" choice needs a 3D view, so it is checked under
Xvfb only (by hand; the console tests check the conversion of a view's camera).
"""

import os
import shutil
import struct
import tempfile
import time
import unittest

import FreeCAD
import FreeCADGui
import Mesh
import Part
from workbench_parts import filleted_box_with_holes

#: Longest a job of these small parts may take on two CPU cores (the slowest, a render of a
#: part on lavapipe, takes a few seconds; the margin is for a loaded CI machine).
JOB_TIMEOUT = 180
#: The long job Cancel interrupts: six 50 mm spheres to 0.5 µm, about 4.8 M triangles, 15 s of
#: daemon work on two cores (eight took 19.8 s), where every other job here takes a second or two.
LONG_TOLERANCE = "0.0005mm"
LONG_SPHERES = 6
#: How soon a cancelled job must have ended (the daemon stops at its next checkpoint; the task
#: gives it 2 s to confirm, task.CANCEL_WAIT_S): well under the long job's 15 s.
CANCEL_WITHIN_S = 5.0

COMMANDS = {
    "Tessd_Tessellate": ("Tessellate precisely\u2026", "tessellate.svg"),
    "Tessd_Simplify": ("Simplify\u2026", "simplify.svg"),
    "Tessd_GenerateLods": ("Generate LODs\u2026", "lods.svg"),
    "Tessd_ExportUsd": ("Export USD\u2026", "export_usd.svg"),
    "Tessd_Render": ("Render precise image\u2026", "render.svg"),
}

PARAM_PATH = "User parameter:BaseApp/Preferences/Mod/tessd"
TREE_PARAM_PATH = "User parameter:BaseApp/Preferences/TreeView"
_saved_params = {}
_work = None


def setUpModule():
    global _work
    if not FreeCAD.GuiUp:
        raise RuntimeError("test_gui needs FreeCAD's GUI: run it with `freecad -t test_gui`, "
                           "not freecadcmd")
    if not os.environ.get("TESSD_BIN"):
        raise RuntimeError("set TESSD_BIN to the tessd binary (target/release/tessd)")
    _check_no_3d_view()
    _work = tempfile.mkdtemp(prefix="tessd-gui-test-")
    os.chmod(_work, 0o700)
    p = FreeCAD.ParamGet(PARAM_PATH)
    for key in ("Socket", "BinaryPath"):
        _saved_params[key] = p.GetString(key, "")
    # No 3D view may open (see the module's notes): the tree would open one for a selected
    # object of a hidden document to show it in ("sync view").
    tree = FreeCAD.ParamGet(TREE_PARAM_PATH)
    _saved_params["SyncView"] = tree.GetBool("SyncView", True)
    tree.SetBool("SyncView", False)
    # A daemon of this test run only, stopped at the end (daemon_link.release_all).
    p.SetString("Socket", os.path.join(_work, "tessd.sock"))
    p.SetString("BinaryPath", "")
    FreeCADGui.activateWorkbench("TessdWorkbench")


def _check_no_3d_view():
    _, _, QtWidgets = qt()
    views = FreeCADGui.getMainWindow().findChildren(QtWidgets.QMdiSubWindow)
    if views:
        raise RuntimeError("a 3D view is open (%d windows): test_gui opens hidden documents "
                           "only, as offscreen Coin crashes closing a 3D view" % len(views))


def tearDownModule():
    from freecad.tessd import daemon_link
    daemon_link.release_all()
    p = FreeCAD.ParamGet(PARAM_PATH)
    FreeCAD.ParamGet(TREE_PARAM_PATH).SetBool("SyncView", _saved_params.pop("SyncView"))
    for key, value in _saved_params.items():
        p.SetString(key, value)
    shutil.rmtree(_work, ignore_errors=True)


# -- helpers -----------------------------------------------------------------------------------

def qt():
    from freecad.tessd.qt import QtCore, QtGui, QtWidgets
    return QtCore, QtGui, QtWidgets


def process_events(seconds=0.0):
    QtCore, _, QtWidgets = qt()
    end = time.monotonic() + seconds
    while True:
        QtWidgets.QApplication.processEvents(QtCore.QEventLoop.AllEvents, 20)
        if time.monotonic() >= end:
            return
        time.sleep(0.01)


def wait_for(condition, timeout, what):
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            raise AssertionError("timed out after %d s waiting for %s" % (timeout, what))
        process_events(0.02)


def task_button(which):
    """The task view's standard button (``"Ok"`` / ``"Cancel"``), as the user clicks it."""
    _, _, QtWidgets = qt()
    kind = getattr(QtWidgets.QDialogButtonBox, which)
    for box in FreeCADGui.getMainWindow().findChildren(QtWidgets.QDialogButtonBox):
        button = box.button(kind)
        if button is not None and box.isVisible() and button.isVisible():
            return button
    raise AssertionError("no %s button in the task view" % which)


def open_panel(command, objects):
    """Selects ``objects``, runs ``command`` as the menu does and returns its panel."""
    from freecad.tessd.panels import common
    FreeCADGui.Selection.clearSelection()
    for obj in objects:
        FreeCADGui.Selection.addSelection(obj)
    before = common.latest_panel()
    FreeCADGui.runCommand(command)
    process_events(0.05)
    panel = common.latest_panel()
    assert panel is not None and panel is not before, "%s opened no panel" % command
    assert FreeCADGui.Control.activeDialog(), "%s: no task dialog shown" % command
    assert panel.form.isVisible(), "%s: the panel's form is not shown" % command
    return panel


def run_ok(panel):
    """Clicks the task view's OK and waits for the job to end; returns the job."""
    task_button("Ok").click()
    process_events(0.05)
    assert panel.job is not None, "OK started no job (state: %s)" % panel.state.text()
    assert panel.job.wait(JOB_TIMEOUT), "the job did not end in %d s" % JOB_TIMEOUT
    process_events(0.1)
    return panel.job


def error_boxes():
    _, _, QtWidgets = qt()
    return [w for w in QtWidgets.QApplication.topLevelWidgets()
            if isinstance(w, QtWidgets.QMessageBox) and w.objectName() == "tessdErrorBox"
            and w.isVisible()]


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", "%s is no PNG" % path
    return struct.unpack(">II", head[16:24])


class GuiCase(unittest.TestCase):
    def setUp(self):
        for box in error_boxes():
            box.close()
        self.doc = FreeCAD.newDocument("TessdGui", hidden=True)
        FreeCAD.setActiveDocument(self.doc.Name)
        self.tmp = tempfile.mkdtemp(dir=_work)

    def tearDown(self):
        _check_no_3d_view()
        if FreeCADGui.Control.activeDialog():
            FreeCADGui.Control.closeDialog()
        process_events(0.05)
        FreeCADGui.Selection.clearSelection()
        FreeCAD.closeDocument(self.doc.Name)
        for box in error_boxes():
            box.close()

    def add_part(self, shape, name):
        obj = self.doc.addObject("Part::Feature", name)
        obj.Shape = shape
        self.doc.recompute()
        return obj

    def add_mesh(self, mesh, name):
        obj = self.doc.addObject("Mesh::Feature", name)
        obj.Mesh = mesh
        self.doc.recompute()
        return obj

    def snapshot(self):
        return sorted(o.Name for o in self.doc.Objects), self.doc.UndoCount

    def assert_one_undo_step(self, before, name):
        self.assertEqual(self.doc.UndoCount, before + 1,
                         "expected exactly one undo step, got %s" % self.doc.UndoNames)
        self.assertEqual(self.doc.UndoNames[0], name)


# -- the workbench and its commands --------------------------------------------------------------

class TestWorkbench(GuiCase):
    def test_workbench_activates(self):
        FreeCADGui.activateWorkbench("TessdWorkbench")
        wb = FreeCADGui.activeWorkbench()
        self.assertEqual(wb.name(), "TessdWorkbench")
        self.assertEqual(wb.MenuText, "tessd")
        self.assertTrue(os.path.isfile(wb.Icon), wb.Icon)
        self.assertIn("tessd", wb.listMenus())
        self.assertIn("tessd", wb.listToolbars())
        self.assertEqual(sorted(wb.getToolbarItems()["tessd"]), sorted(COMMANDS))
        _, _, QtWidgets = qt()
        menus = [a.text().replace("&", "") for a in
                 FreeCADGui.getMainWindow().menuBar().actions()]
        self.assertIn("tessd", menus)

    def test_commands_registered_with_icons(self):
        _, QtGui, _ = qt()
        registered = FreeCADGui.listCommands()
        for name, (menu_text, icon) in COMMANDS.items():
            self.assertIn(name, registered)
            info = FreeCADGui.Command.get(name).getInfo()
            self.assertEqual(info["menuText"], menu_text)
            self.assertTrue(info["toolTip"])
            self.assertEqual(os.path.basename(info["pixmap"]), icon)
            self.assertTrue(os.path.isfile(info["pixmap"]), info["pixmap"])
            pixmap = QtGui.QIcon(info["pixmap"]).pixmap(64, 64)
            self.assertFalse(pixmap.isNull(), "%s: the icon does not load" % name)
            image = pixmap.toImage()
            opaque = sum(1 for x in range(0, 64, 4) for y in range(0, 64, 4)
                         if image.pixelColor(x, y).alpha() > 0)
            self.assertGreater(opaque, 20, "%s: the icon is empty" % name)

    def test_commands_follow_the_selection(self):
        box = self.add_part(Part.makeBox(10, 10, 10), "Box")
        mesh = self.add_mesh(Mesh.createBox(10, 10, 10), "Cube")
        cmd = {name: FreeCADGui.Command.get(name) for name in COMMANDS}
        FreeCADGui.Selection.clearSelection()
        self.assertFalse(any(c.isActive() for c in cmd.values()))
        FreeCADGui.Selection.addSelection(box)
        self.assertTrue(all(c.isActive() for c in cmd.values()))
        FreeCADGui.Selection.clearSelection()
        FreeCADGui.Selection.addSelection(mesh)
        self.assertFalse(cmd["Tessd_Tessellate"].isActive())  # a mesh is tessellated already
        self.assertTrue(cmd["Tessd_Simplify"].isActive())

    def test_preference_page(self):
        from freecad.tessd.preferences_page import PreferencePage
        p = FreeCAD.ParamGet(PARAM_PATH)
        socket = p.GetString("Socket")
        page = PreferencePage()
        page.loadSettings()
        self.assertEqual(page.socket.text(), socket)
        self.assertIn(os.environ["TESSD_BIN"], page.found.text())
        page.binary.setText(os.environ["TESSD_BIN"])
        page.saveSettings()
        try:
            self.assertEqual(p.GetString("BinaryPath"), os.environ["TESSD_BIN"])
        finally:
            p.SetString("BinaryPath", "")


# -- the panels --------------------------------------------------------------------------------

class TestPanels(GuiCase):
    def test_tessellate(self):
        part = self.add_part(filleted_box_with_holes(), "Plate")
        faces = len(part.Shape.Faces)
        undo = self.doc.UndoCount
        panel = open_panel("Tessd_Tessellate", [part])
        panel.tolerance.set_text("0.02mm")
        panel.angle.setValue(20.0)
        self.assertEqual(panel.arguments()["tolerance"], "0.02mm")
        job = run_ok(panel)
        self.assertEqual(job.state, "done", job.error)
        self.assertFalse(FreeCADGui.Control.activeDialog(), "the panel stayed open")
        mesh = self.doc.getObject("Plate_mesh")
        self.assertIsNotNone(mesh, [o.Name for o in self.doc.Objects])
        self.assertEqual(mesh.Label, "Plate_mesh")
        self.assertEqual(mesh.Mesh.countSegments(), faces)
        self.assertTrue(mesh.Mesh.isSolid())
        self.assertAlmostEqual(mesh.Mesh.Area / part.Shape.Area, 1.0, delta=0.005)
        self.assert_one_undo_step(undo, "Tessellate")
        self.doc.undo()
        self.assertIsNone(self.doc.getObject("Plate_mesh"))

    def test_simplify_live_preview_and_partition(self):
        part = self.add_part(Part.makeSphere(20), "Ball")
        mesh = self.add_mesh(Mesh.createSphere(20, 120), "Sphere")
        undo = self.doc.UndoCount
        panel = open_panel("Tessd_Simplify", [mesh])
        # The preview of the defaults (complexity, 20 % of the vertices) comes by itself.
        wait_for(lambda: panel.last_preview is not None and not panel.preview_pending(),
                 JOB_TIMEOUT, "the first preview")
        first = panel.last_preview
        self.assertEqual(first["input_faces"], mesh.Mesh.CountFacets)
        self.assertAlmostEqual(first["vertices"] / mesh.Mesh.CountPoints, 0.2, delta=0.03)
        self.assertIn("vertices", panel.preview.text())
        # Changes in quick succession (typing) make one preview, of the last value.
        from freecad.tessd import jobs
        previews = []
        hook = lambda job: previews.append(job) if job.title == "Simplify preview" else None
        jobs.FINISHED_HOOKS.append(hook)
        try:
            for percent in (30, 35, 40, 45, 50):
                panel.target.setValue(percent)
                process_events(0.02)
            wait_for(lambda: not panel.preview_pending(), JOB_TIMEOUT,
                     "the preview after typing")
            process_events(0.6)
        finally:
            jobs.FINISHED_HOOKS.remove(hook)
        self.assertEqual([p.state for p in previews], ["done"])
        self.assertAlmostEqual(panel.last_preview["vertices"] / mesh.Mesh.CountPoints, 0.5,
                               delta=0.05)
        # Quality goal, 1 % of the largest side, partition shown.
        panel.goal_buttons["quality"].click()
        self.assertEqual(panel.pages.currentIndex(), 1)
        panel.max_error.set_text("1%")
        panel.representative.setCurrentIndex(panel.representative.findData("barycenter"))
        panel.show_partition.setChecked(True)
        self.assertTrue(panel.preview_pending())
        wait_for(lambda: not panel.preview_pending(), JOB_TIMEOUT,
                 "the preview of the quality goal")
        preview = panel.last_preview
        self.assertIsNot(preview, previews[0].result)
        self.assertIn("surface error", panel.preview.text())
        self.assertLessEqual(preview["surface_error"], 0.01 * 40 * 1.0001)
        self.assertEqual(panel.arguments(), {
            "method": "quality", "max_error": "1%", "representative": "barycenter",
            "show_partition": True})
        job = run_ok(panel)
        self.assertEqual(job.state, "done", job.error)
        simplified = self.doc.getObject("Sphere_simplified")
        partition = self.doc.getObject("Sphere_partition")
        self.assertIsNotNone(simplified)
        self.assertIsNotNone(partition)
        self.assertGreater(len(partition.Shape.Edges), 12)
        # The preview gave what the result has.
        self.assertEqual(simplified.Mesh.CountPoints, preview["vertices"])
        self.assertEqual(simplified.Mesh.CountFacets, preview["faces"])
        self.assert_one_undo_step(undo, "Simplify")
        self.assertIsNotNone(part)

    def test_simplify_grid_of_a_part(self):
        part = self.add_part(filleted_box_with_holes(), "Plate")
        undo = self.doc.UndoCount
        panel = open_panel("Tessd_Simplify", [part])
        panel.goal_buttons["grid"].click()
        panel.cells.setValue(8)
        panel.preserve_boundaries.setChecked(True)
        self.assertEqual(panel.arguments(), {"method": "grid", "cells": 8,
                                             "representative": "quadric",
                                             "show_partition": False,
                                             "preserve_boundaries": True})
        job = run_ok(panel)
        self.assertEqual(job.state, "done", job.error)
        result = self.doc.getObject("Plate_simplified")
        self.assertIsNotNone(result)
        self.assertGreater(result.Mesh.CountFacets, 0)
        self.assertIsNone(self.doc.getObject("Plate_partition"))
        self.assert_one_undo_step(undo, "Simplify")

    def test_generate_lods(self):
        mesh = self.add_mesh(Mesh.createSphere(10, 60), "Sphere")
        usd = os.path.join(self.tmp, "sphere_lods.usda")
        undo = self.doc.UndoCount
        panel = open_panel("Tessd_GenerateLods", [mesh])
        panel.levels.setText("50%, 10%")
        panel.write_usd.setChecked(True)
        panel.usd_path.set_text(usd)
        job = run_ok(panel)
        self.assertEqual(job.state, "done", job.error)
        group = self.doc.getObject("Sphere_LODs")
        self.assertIsNotNone(group)
        labels = [o.Label for o in group.Group]
        self.assertEqual(labels, ["Sphere_LOD0", "Sphere_LOD1", "Sphere_LOD2"])
        counts = [o.Mesh.CountPoints for o in group.Group]
        self.assertEqual(counts, sorted(counts, reverse=True))
        self.assertTrue(os.path.isfile(usd))
        with open(usd) as f:
            self.assertIn("LOD", f.read())
        self.assert_one_undo_step(undo, "Generate LODs")

    def test_export_usd(self):
        part = self.add_part(filleted_box_with_holes(), "Plate")
        path = os.path.join(self.tmp, "plate.usda")
        before = self.snapshot()
        panel = open_panel("Tessd_ExportUsd", [part])
        panel.path.set_text(path)
        panel.tolerance.set_text("0.05mm")
        job = run_ok(panel)
        self.assertEqual(job.state, "done", job.error)
        self.assertEqual(job.result, path)
        with open(path) as f:
            text = f.read()
        self.assertTrue(text.startswith("#usda 1.0"))
        self.assertEqual(text.count("GeomSubset"), len(part.Shape.Faces))
        self.assertEqual(self.snapshot(), before, "exporting changed the document")

    def test_render_shows_then_saves(self):
        _, QtGui, _ = qt()
        part = self.add_part(filleted_box_with_holes(), "Plate")
        path = os.path.join(self.tmp, "plate.png")
        before = self.snapshot()
        panel = open_panel("Tessd_Render", [part])
        self.assertEqual(panel.view.findData("active"), -1,
                         "a hidden document has no 3D view to take the camera from")
        panel.width.setValue(320)
        panel.height.setValue(180)
        panel.view.setCurrentIndex(panel.view.findData("front"))
        panel.path.set_text(path)
        panel.render_button.click()
        self.assertIsNotNone(panel.job)
        self.assertTrue(panel.job.wait(JOB_TIMEOUT))
        process_events(0.1)
        self.assertEqual(panel.job.state, "done", panel.job.error)
        pixmap = panel.picture.pixmap()
        self.assertTrue(pixmap is not None and not pixmap.isNull(), "no picture in the panel")
        self.assertEqual((pixmap.width(), pixmap.height()), (320, 180))
        self.assertFalse(os.path.exists(path), "Render saved before OK")
        self.assertTrue(FreeCADGui.Control.activeDialog())
        task_button("Ok").click()
        process_events(0.1)
        self.assertFalse(FreeCADGui.Control.activeDialog(), "OK did not close the panel")
        self.assertEqual(png_size(path), (320, 180))
        image = QtGui.QImage(path)
        corner = image.pixel(0, 0)
        covered = sum(1 for x in range(0, 320, 8) for y in range(0, 180, 8)
                      if image.pixel(x, y) != corner)
        self.assertGreater(covered, 40, "the picture shows nothing")
        self.assertEqual(self.snapshot(), before, "rendering changed the document")


# -- long jobs, cancel, errors -----------------------------------------------------------------

class TestJobs(GuiCase):
    def test_cancel_of_a_long_job_leaves_the_document(self):
        _, _, QtWidgets = qt()
        balls = [Part.makeSphere(50, FreeCAD.Vector(120 * i, 0, 0)) for i in range(LONG_SPHERES)]
        part = self.add_part(Part.makeCompound(balls), "Ball")
        before = self.snapshot()
        panel = open_panel("Tessd_Tessellate", [part])
        panel.tolerance.set_text(LONG_TOLERANCE)
        task_button("Ok").click()
        job = panel.job
        self.assertIsNotNone(job)
        # The status bar shows the job with a Cancel button; the GUI keeps answering.
        bar = FreeCADGui.getMainWindow().statusBar()
        cancel = bar.findChild(QtWidgets.QPushButton, "tessdCancel")
        self.assertIsNotNone(cancel, "no Cancel button in the status bar")
        self.assertTrue(cancel.isVisible())
        wait_for(lambda: job._progress[0] is not None, 30, "the job's first progress")
        started = time.monotonic()
        cancel.click()
        self.assertTrue(job.wait(30), "the cancelled job did not end")
        self.assertLess(time.monotonic() - started, CANCEL_WITHIN_S,
                        "the job went on after Cancel (was the daemon job cancelled?)")
        process_events(0.1)
        self.assertEqual(job.state, "cancelled")
        self.assertEqual(job.run_outcome, "cancelled", "run() finished instead of stopping")
        self.assertEqual(self.snapshot(), before, "a cancelled job changed the document")
        self.assertIsNone(bar.findChild(QtWidgets.QPushButton, "tessdCancel"))
        self.assertTrue(FreeCADGui.Control.activeDialog(), "the panel closed on a cancel")
        self.assertIn("Cancelled", panel.state.text())
        # The panel runs again after a cancel.
        panel.tolerance.set_text("0.1mm")
        job = run_ok(panel)
        self.assertEqual(job.state, "done", job.error)
        self.assertIsNotNone(self.doc.getObject("Ball_mesh"))

    def test_closing_the_panel_cancels_its_job(self):
        balls = [Part.makeSphere(50, FreeCAD.Vector(120 * i, 0, 0)) for i in range(LONG_SPHERES)]
        part = self.add_part(Part.makeCompound(balls), "Ball")
        before = self.snapshot()
        panel = open_panel("Tessd_Tessellate", [part])
        panel.tolerance.set_text(LONG_TOLERANCE)
        task_button("Ok").click()
        job = panel.job
        wait_for(lambda: job._progress[0] is not None, 30, "the job's first progress")
        task_button("Cancel").click()
        process_events(0.05)
        self.assertFalse(FreeCADGui.Control.activeDialog(), "Cancel did not close the panel")
        self.assertTrue(job.wait(CANCEL_WITHIN_S), "the job went on after the panel closed")
        self.assertEqual(job.state, "cancelled")
        process_events(0.1)
        self.assertEqual(self.snapshot(), before, "a cancelled job changed the document")

    def test_gui_answers_while_a_job_runs(self):
        part = self.add_part(Part.makeSphere(50), "Ball")
        panel = open_panel("Tessd_Tessellate", [part])
        panel.tolerance.set_text("0.002mm")
        task_button("Ok").click()
        job = panel.job
        ticks = []
        QtCore, _, _ = qt()
        timer = QtCore.QTimer()
        timer.timeout.connect(lambda: ticks.append(time.monotonic()))
        timer.start(20)
        self.assertTrue(job.wait(JOB_TIMEOUT))
        timer.stop()
        self.assertEqual(job.state, "done", job.error)
        gaps = [b - a for a, b in zip(ticks, ticks[1:])]
        self.assertGreater(len(ticks), 10)
        # apply() (building the mesh) runs on the GUI thread; the daemon's work does not.
        self.assertLess(sorted(gaps)[int(0.9 * len(gaps))], 0.25, "the GUI froze while waiting")

    def test_daemon_error_shows_a_message_box(self):
        mesh = self.add_mesh(Mesh.createSphere(10, 30), "Sphere")
        before = self.snapshot()
        panel = open_panel("Tessd_GenerateLods", [mesh])
        panel.levels.setText("0%")  # well formed, refused by the daemon
        job = run_ok(panel)
        self.assertEqual(job.state, "failed")
        self.assertTrue(job.error)
        boxes = error_boxes()
        self.assertEqual(len(boxes), 1, "expected one error box")
        _, _, QtWidgets = qt()
        self.assertEqual(boxes[0].icon(), QtWidgets.QMessageBox.Critical)
        self.assertIn(job.error, boxes[0].text())
        self.assertIn(job.exception.message, boxes[0].text())  # the daemon's own words
        boxes[0].close()
        self.assertEqual(self.snapshot(), before)
        self.assertTrue(FreeCADGui.Control.activeDialog(), "the panel closed on an error")
        self.assertIn("Failed", panel.state.text())

    def test_bad_field_is_reported_before_any_job(self):
        mesh = self.add_mesh(Mesh.createSphere(10, 30), "Sphere")
        panel = open_panel("Tessd_GenerateLods", [mesh])
        panel.levels.setText("half")
        task_button("Ok").click()
        process_events(0.05)
        self.assertIsNone(panel.job)
        boxes = error_boxes()
        self.assertEqual(len(boxes), 1)
        self.assertIn("levels", boxes[0].text())
        boxes[0].close()

    def test_no_live_preview_over_a_million_triangles(self):
        big = self.add_mesh(Mesh.createSphere(10, 720), "Big")
        self.assertGreaterEqual(big.Mesh.CountFacets, 1_000_000)
        panel = open_panel("Tessd_Simplify", [big])
        process_events(1.0)
        self.assertFalse(panel.preview_pending())
        self.assertIsNone(panel.last_preview)
        self.assertIn("No live preview", panel.preview.text())
        task_button("Cancel").click()
        process_events(0.05)
        self.assertFalse(FreeCADGui.Control.activeDialog())
