"""The workbench's five commands (menu "tessd" and its toolbar).

Each is active when a document is open, the selection holds objects it can act on and no
other task panel is shown; it opens its task panel (``panels/``) on the selected objects.
The panel does the work through the console API (``api.prepare_<name>``), so what a command
does a macro does with ``freecad.tessd.api.<name>(...)`` (the panel prints that line in the
Report view when it finished).
"""

import FreeCAD
import FreeCADGui

from .panels import common


class PanelCommand:
    """A command that opens ``panel`` (a ``common.TaskPanel`` class, imported lazily from
    ``panels.<module>``) on the selected objects: ``parts`` / ``meshes`` say which kinds."""

    def __init__(self, module, panel, icon, menu, tooltip, parts=True, meshes=True):
        self.module = module
        self.panel = panel
        self.icon = icon
        self.menu = menu
        self.tooltip = tooltip
        self.parts = parts
        self.meshes = meshes

    def GetResources(self):
        return {"Pixmap": common.icon_path(self.icon), "MenuText": self.menu,
                "ToolTip": self.tooltip}

    def IsActive(self):
        if FreeCAD.ActiveDocument is None or FreeCADGui.Control.activeDialog():
            return False
        return bool(common.selected(self.parts, self.meshes))

    def Activated(self):
        import importlib
        objects = common.selected(self.parts, self.meshes)
        if not objects:
            return
        module = importlib.import_module("freecad.tessd.panels." + self.module)
        FreeCADGui.Control.showDialog(getattr(module, self.panel)(objects))


#: Command name → command, in menu order.
COMMANDS = {
    "Tessd_Tessellate": PanelCommand(
        "tessellate", "TessellatePanel", "tessellate", "Tessellate precisely\u2026",
        "Mesh the selected Part objects with tessd: watertight, within a chordal tolerance "
        "(a length or % of the part's size) and an angle, one mesh segment per B-Rep face",
        meshes=False),
    "Tessd_Simplify": PanelCommand(
        "simplify", "SimplifyPanel", "simplify", "Simplify\u2026",
        "Simplify the selected meshes (Part objects are tessellated first) by vertex "
        "clustering: a regular grid, a quality goal (max error) or a complexity goal "
        "(vertex count), with a live preview and the partition shown on request"),
    "Tessd_GenerateLods": PanelCommand(
        "lods", "LodsPanel", "lods", "Generate LODs\u2026",
        "Make a chain of levels of detail of the selected objects (a group <Label>_LODs), "
        "optionally written as a USD stage with a LOD variant set"),
    "Tessd_ExportUsd": PanelCommand(
        "export_usd", "ExportUsdPanel", "export_usd", "Export USD\u2026",
        "Write the selected objects as one USD stage: the document tree as Xforms, "
        "placements kept, one GeomSubset per B-Rep face, the view colours"),
    "Tessd_Render": PanelCommand(
        "render", "RenderPanel", "render", "Render precise image\u2026",
        "Render the selected objects with tessd's precise trimmed B-Rep renderer (crack "
        "filling in image or object space), from the active view or a standard one; the "
        "image is shown in the panel before it is saved"),
}

#: The command names, in menu and toolbar order.
NAMES = list(COMMANDS)


def register():
    """Adds the commands to FreeCAD (once; FreeCAD keeps them for the session)."""
    for name, command in COMMANDS.items():
        FreeCADGui.addCommand(name, command)


register()
