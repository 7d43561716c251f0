"""The FreeCAD workbench's screenshots in freecad_plugin/README.md, taken from FreeCAD's own
main window (0.20, Debian's freecad-python3) with the workbench's real commands.

    python3 docs/screenshots/freecad/make_screenshots.py [--out docs/screenshots/freecad]

Links the workbench into the Mod folder of a throw-away HOME (freecad_plugin/install.py
--link), starts FreeCAD on a virtual X server (xvfb-run, Mesa's software OpenGL: Qt's offscreen
platform has no OpenGL, so FreeCAD's 3D view would stay empty there) with this same file as its
script, and the script, inside FreeCAD:

- workbench.png: the tessd workbench, its menu dropped down, OCCT's CrankArm (shared/data/brep)
  beside its mesh from Tessellate precisely… at 0.05 mm (shown as Flat Lines);
- simplify_partition.png: the Simplify… panel (paper 004's dialog) with a quality goal of
  2 % of the largest side and "Show partition", its live preview filled in, over the result
  of that simplification of the CrankArm's 0.02 mm mesh and its partition (the cells, red
  wire boxes).

The daemon is $TESSD_BIN (default target/release/tessd) on a private socket; the shared data
come from $TESSD_SHARED_DATA (default ../shared/data). Needs xvfb-run (apt-get install xvfb).
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import traceback

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))))
#: Set by the launcher for the copy of this script FreeCAD runs: where the PNGs go.
OUT_ENV = "TESSD_FREECAD_SCREENSHOTS_OUT"
#: FreeCAD's user settings for the run: start on the Part workbench, not on the Start page
#: (a QtWebEngine view, which run as root will not start without its no-sandbox flag).
USER_CFG = """<?xml version="1.0" encoding="UTF-8" standalone="no" ?>
<FCParameters>
  <FCParamGroup Name="Root">
    <FCParamGroup Name="BaseApp">
      <FCParamGroup Name="Preferences">
        <FCParamGroup Name="General">
          <FCText Name="AutoloadModule">PartWorkbench</FCText>
        </FCParamGroup>
      </FCParamGroup>
    </FCParamGroup>
  </FCParamGroup>
</FCParameters>
"""
#: The parts' colour (FreeCAD's default grey reads poorly against the mesh lines).
PART_COLOR = (0.55, 0.68, 0.85)
#: The main window's size in the pictures (the X screen is a little larger).
WINDOW = (1480, 900)


# -- outside FreeCAD: the launcher ----------------------------------------------------------------

def launch(out):
    binary = os.environ.get("TESSD_BIN") or os.path.join(REPO, "target", "release", "tessd")
    if not os.access(binary, os.X_OK):
        sys.exit("no tessd binary at %s (cargo build --release -p tessd, or set TESSD_BIN)"
                 % binary)
    if shutil.which("xvfb-run") is None:
        sys.exit("xvfb-run not found: apt-get install -y xvfb (FreeCAD's 3D view needs an X "
                 "server with OpenGL; Qt's offscreen platform has none)")
    if shutil.which("freecad") is None:
        sys.exit("freecad not found (scripts/setup.sh installs freecad-python3)")
    work = tempfile.mkdtemp(prefix="tessd-freecad-shots-")
    try:
        env = dict(os.environ, HOME=os.path.join(work, "home"), TESSD_BIN=binary,
                   LIBGL_ALWAYS_SOFTWARE="1", **{OUT_ENV: os.path.abspath(out)})
        for key in ("XDG_DATA_HOME", "XDG_CONFIG_HOME", "FREECAD_USER_HOME", "QT_QPA_PLATFORM"):
            env.pop(key, None)
        os.makedirs(env["HOME"])
        subprocess.run([sys.executable, os.path.join(REPO, "freecad_plugin", "install.py"),
                        "--link", "--mod-dir",
                        os.path.join(env["HOME"], ".local", "share", "FreeCAD", "Mod")],
                       check=True, env=env)
        cfg = os.path.join(work, "user.cfg")
        with open(cfg, "w") as f:
            f.write(USER_CFG)
        os.makedirs(out, exist_ok=True)
        screen = "-screen 0 %dx%dx24" % (WINDOW[0] + 120, WINDOW[1] + 100)
        cmd = ["xvfb-run", "-a", "-s", screen, "freecad", "-u", cfg,
               "-P", os.path.join(REPO, "tests", "freecad_plugin"),
               os.path.abspath(__file__)]
        print("running:", " ".join(cmd))
        status = subprocess.run(cmd, env=env, timeout=900).returncode
    finally:
        shutil.rmtree(work, ignore_errors=True)
    for name in ("workbench.png", "simplify_partition.png"):
        path = os.path.join(out, name)
        if not os.path.isfile(path):
            sys.exit("FreeCAD (status %d) wrote no %s" % (status, path))
        print("wrote", path)
    if status != 0:
        sys.exit("FreeCAD ended with status %d" % status)


# -- inside FreeCAD -------------------------------------------------------------------------------

def process_events(seconds):
    from freecad.tessd.qt import QtCore, QtWidgets
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        QtWidgets.QApplication.processEvents(QtCore.QEventLoop.AllEvents, 20)
        time.sleep(0.01)


def click_ok():
    from freecad.tessd.qt import QtWidgets
    import FreeCADGui
    for box in FreeCADGui.getMainWindow().findChildren(QtWidgets.QDialogButtonBox):
        button = box.button(QtWidgets.QDialogButtonBox.Ok)
        if button is not None and button.isVisible():
            button.click()
            return
    raise RuntimeError("no OK button in the task view")


def open_panel(command, objects):
    import FreeCADGui
    from freecad.tessd.panels import common
    FreeCADGui.Selection.clearSelection()
    for obj in objects:
        FreeCADGui.Selection.addSelection(obj)
    FreeCADGui.runCommand(command)
    process_events(0.3)
    return common.latest_panel()


def run_panel(panel):
    click_ok()
    process_events(0.1)
    if not panel.job.wait(600) or panel.job.state != "done":
        raise RuntimeError("%s: %s" % (panel.title, panel.job.error or panel.job.state))
    process_events(0.3)
    return panel.job.result


def arrange_window():
    """The main window at WINDOW, the combo view wide enough for the task panels, no Python
    console or report view (they would take the 3D view's room)."""
    import FreeCADGui
    from freecad.tessd.qt import QtCore, QtWidgets
    mw = FreeCADGui.getMainWindow()
    mw.showNormal()
    mw.resize(*WINDOW)
    mw.move(0, 0)
    for dock in mw.findChildren(QtWidgets.QDockWidget):
        if dock.objectName() in ("Python console", "Report view", "Selection view",
                                 "Property view"):
            dock.hide()
    combo = mw.findChild(QtWidgets.QDockWidget, "Combo View")
    if combo is not None:
        combo.show()
        mw.resizeDocks([combo], [430], QtCore.Qt.Horizontal)
    process_events(0.5)


def combo_tab(name):
    """Shows the combo view's ``name`` tab ("Model" or "Tasks")."""
    import FreeCADGui
    from freecad.tessd.qt import QtWidgets
    for tabs in FreeCADGui.getMainWindow().findChildren(QtWidgets.QTabWidget):
        for i in range(tabs.count()):
            if tabs.tabText(i) == name:
                tabs.setCurrentIndex(i)
                process_events(0.2)
                return


def show_view(doc, view="isometric"):
    import FreeCADGui
    gui_doc = FreeCADGui.getDocument(doc.Name)
    active = gui_doc.activeView()
    getattr(active, "view" + view.capitalize())()
    active.fitAll()
    process_events(0.5)


def grab(path):
    """The main window as the X server shows it (QWidget.grab() would leave the OpenGL 3D
    view out), with any menu dropped down over it."""
    import FreeCADGui
    from freecad.tessd.qt import QtGui
    process_events(0.8)
    mw = FreeCADGui.getMainWindow()
    frame = mw.frameGeometry()
    screen = QtGui.QGuiApplication.primaryScreen()
    picture = screen.grabWindow(0, frame.x(), frame.y(), frame.width(), frame.height())
    if picture.isNull() or not picture.save(path):
        raise RuntimeError("could not write %s" % path)
    print("tessd screenshots: wrote %s" % path, flush=True)


def close_menus():
    from freecad.tessd.qt import QtWidgets
    popup = QtWidgets.QApplication.activePopupWidget()
    while popup is not None:
        popup.close()
        process_events(0.1)
        popup = QtWidgets.QApplication.activePopupWidget()


def drop_menu(title):
    """Opens the menu bar's ``title`` menu (without waiting on it, as a click would)."""
    import FreeCADGui
    mw = FreeCADGui.getMainWindow()
    bar = mw.menuBar()
    for action in bar.actions():
        if action.text().replace("&", "") == title and action.menu() is not None:
            bar.setActiveAction(action)
            process_events(0.5)
            return action.menu()
    raise RuntimeError("no %s menu" % title)


def take_pictures(out):
    import FreeCAD
    import FreeCADGui
    import Part
    from workbench_parts import shared_data

    # A daemon of this run only (the throw-away HOME's socket), stopped at the end.
    FreeCAD.ParamGet("User parameter:BaseApp/Preferences/Mod/tessd").SetString(
        "Socket", os.path.join(os.environ["HOME"], "tessd.sock"))
    # The selected part keeps its colours in the picture (no green selection highlight).
    FreeCAD.ParamGet("User parameter:BaseApp/Preferences/View").SetBool("EnableSelection",
                                                                         False)
    arrange_window()
    FreeCADGui.activateWorkbench("TessdWorkbench")
    shape = Part.Shape()
    shape.read(str(shared_data() / "brep" / "CrankArm.brep"))

    # workbench.png: the part beside its precise tessellation, the Tessellate panel open.
    doc = FreeCAD.newDocument("CrankArm")
    part = doc.addObject("Part::Feature", "CrankArm")
    part.Shape = shape
    doc.recompute()
    panel = open_panel("Tessd_Tessellate", [part])
    panel.tolerance.set_text("0.05mm")
    mesh = run_panel(panel)[0]
    box = shape.BoundBox
    mesh.Placement.Base = FreeCAD.Vector(1.15 * box.XLength, 0, 0)
    part.ViewObject.ShapeColor = PART_COLOR
    style_mesh(mesh)
    doc.recompute()
    show_view(doc)
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(part)
    combo_tab("Model")
    drop_menu("tessd")
    grab(os.path.join(out, "workbench.png"))
    close_menus()
    FreeCADGui.Selection.clearSelection()

    # simplify_partition.png: the Simplify dialog over its result and partition, on the
    # CrankArm's mesh at 0.02 mm (made with the console API, as a macro would).
    from freecad.tessd import api
    doc2 = FreeCAD.newDocument("Simplify")
    part2 = doc2.addObject("Part::Feature", "CrankArm")
    part2.Shape = shape
    doc2.recompute()
    source = api.tessellate(part2, tolerance="0.02mm")[0]
    part2.ViewObject.Visibility = False

    def settings(panel):
        panel.goal_buttons["quality"].click()
        panel.max_error.set_text("2%")
        panel.show_partition.setChecked(True)

    panel = open_panel("Tessd_Simplify", [source])
    settings(panel)
    simplified = run_panel(panel)[0]
    partition = doc2.getObject("CrankArm_mesh_partition")
    source.ViewObject.Visibility = False
    style_mesh(simplified)
    partition.ViewObject.LineColor = (0.85, 0.15, 0.1)
    partition.ViewObject.LineWidth = 1.0
    doc2.recompute()
    show_view(doc2)
    panel = open_panel("Tessd_Simplify", [source])
    settings(panel)
    end = time.monotonic() + 300
    while (panel.last_preview is None or panel.preview_pending()) and time.monotonic() < end:
        process_events(0.1)
    FreeCADGui.Selection.clearSelection()
    grab(os.path.join(out, "simplify_partition.png"))
    FreeCADGui.Control.closeDialog()


def style_mesh(obj):
    """Flat Lines in the part's colour, the edges a darker shade (not black: a precise
    tessellation has many thin triangles, which black lines would turn into a dark mass)."""
    vo = obj.ViewObject
    vo.DisplayMode = "Flat Lines"
    vo.ShapeColor = PART_COLOR
    vo.LineColor = tuple(0.55 * c for c in PART_COLOR)


def inside_freecad(out):
    status = 0
    try:
        take_pictures(out)
    except Exception:
        traceback.print_exc()
        sys.stderr.flush()
        status = 1
    finally:
        try:
            from freecad.tessd import daemon_link
            daemon_link.release_all()
        except Exception:
            traceback.print_exc()
    sys.stdout.flush()
    os._exit(status)  # FreeCAD's own shutdown is not needed for pictures already written


if os.environ.get(OUT_ENV) and "FreeCAD" in sys.modules:
    inside_freecad(os.environ[OUT_ENV])
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=os.path.join(REPO, "docs", "screenshots", "freecad"))
    launch(parser.parse_args().out)
