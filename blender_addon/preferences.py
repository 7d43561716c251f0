"""Add-on preferences: where the daemon binary is, which socket to use, and whether the
add-on starts the daemon itself (and stops it again when Blender exits); and the
``tessd.open_preferences`` operator, the button a failure offers when the fix is here."""

import bpy

from . import binary

#: The add-on's module name ("bl_ext.<repo>.tessd" as an extension).
ADDON_ID = __package__


class TessdPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_ID

    binary_path: bpy.props.StringProperty(
        name="tessd binary",
        description="The tessd program to start. Empty: the one bundled with this add-on "
                    "(then $TESSD_BIN, then tessd on PATH)",
        subtype='FILE_PATH', default="")
    socket: bpy.props.StringProperty(
        name="Socket",
        description="Socket path or bare name as for `tessd serve --socket`. Empty: the "
                    "per-user default socket", default="")
    auto_start: bpy.props.BoolProperty(
        name="Start the daemon automatically",
        description="Start `tessd serve` when no daemon answers on the socket", default=True)
    stop_on_exit: bpy.props.BoolProperty(
        name="Stop it on exit",
        description="Shut down a daemon this add-on started when Blender exits or the "
                    "add-on is disabled, unless another program (FreeCAD, a script) still "
                    "uses it", default=True)
    timeout: bpy.props.FloatProperty(
        name="Start timeout", description="Seconds to wait for a started daemon to answer",
        default=15.0, min=1.0, soft_max=120.0, subtype='TIME_ABSOLUTE')

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "binary_path")
        layout.prop(self, "socket")
        row = layout.row()
        row.prop(self, "auto_start")
        row.prop(self, "stop_on_exit")
        layout.prop(self, "timeout")
        layout.label(text="Binary: " + binary.describe_binary(self))


class _Defaults:
    """The preferences' defaults, when the add-on is imported without being enabled."""

    binary_path = ""
    socket = ""
    auto_start = True
    stop_on_exit = True
    timeout = 15.0


class OpenPreferences(bpy.types.Operator):
    """Open Preferences at the tessd add-on (to choose the tessd program or the socket)"""

    bl_idname = "tessd.open_preferences"
    bl_label = "Open tessd Preferences"
    bl_options = {'INTERNAL'}

    @classmethod
    def poll(cls, context):
        # Preferences open in a window of their own; background Blender has none.
        if bpy.app.background or not context.window_manager.windows:
            cls.poll_message_set("Preferences need a Blender window")
            return False
        return True

    def execute(self, context):
        try:
            bpy.ops.preferences.addon_show(module=ADDON_ID)
        except RuntimeError as e:
            self.report({'ERROR'}, "cannot open Preferences: %s" % e)
            return {'CANCELLED'}
        return {'FINISHED'}


def get(context=None):
    """The add-on's preferences (or their defaults)."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ADDON_ID)
    return addon.preferences if addon is not None else _Defaults()


def register():
    bpy.utils.register_class(TessdPreferences)
    bpy.utils.register_class(OpenPreferences)


def unregister():
    bpy.utils.unregister_class(OpenPreferences)
    bpy.utils.unregister_class(TessdPreferences)
