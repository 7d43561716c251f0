"""FreeCAD's GUI imports this module at start-up (namespaced workbench layout, FreeCAD 0.19+:
``<Mod>/tessd/freecad/tessd/init_gui.py``): it registers the workbench and its preference
page, nothing else. The commands are registered when the workbench is first activated
(``Initialize``), so FreeCAD starts as fast with the workbench installed as without it.
"""

import os

import FreeCADGui

ICON = os.path.join(os.path.dirname(os.path.abspath(__file__)), "resources", "icons",
                    "tessd.svg")


class TessdWorkbench(FreeCADGui.Workbench):
    """tessd: precise tessellation, simplification, LODs, USD and renders of parts."""

    MenuText = "tessd"
    ToolTip = ("Precise tessellation, vertex-clustering simplification, levels of detail, USD "
               "export and precise renders of parts and meshes, by the tessd daemon")
    Icon = ICON

    def Initialize(self):
        from . import commands
        self.appendToolbar("tessd", commands.NAMES)
        self.appendMenu("tessd", commands.NAMES)

    def Activated(self):
        pass

    def Deactivated(self):
        pass

    def ContextMenu(self, recipient):
        from . import commands
        if recipient == "Tree" and FreeCADGui.Selection.getSelection():
            self.appendContextMenu("tessd", commands.NAMES)

    def GetClassName(self):
        return "Gui::PythonWorkbench"


def _add_preference_page():
    from .preferences_page import PreferencePage
    FreeCADGui.addPreferencePage(PreferencePage, "tessd")


FreeCADGui.addWorkbench(TessdWorkbench())
_add_preference_page()
