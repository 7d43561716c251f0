"""Add-on preferences: where the daemon binary is, which socket to use, and whether the
add-on starts the daemon itself (and stops it again when Blender exits)."""

import bpy

#: The add-on's module name ("bl_ext.<repo>.tessd" as an extension).
ADDON_ID = __package__


class TessdPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_ID

    binary_path: bpy.props.StringProperty(
        name="tessd binary",
        description="Path of the tessd executable. Empty: next to the add-on, then "
                    "$TESSD_BIN, then `tessd` on PATH",
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
                    "add-on is disabled", default=True)
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
        from . import daemon
        layout.label(text="Binary: " + daemon.describe_binary(self))


class _Defaults:
    """The preferences' defaults, when the add-on is imported without being enabled."""

    binary_path = ""
    socket = ""
    auto_start = True
    stop_on_exit = True
    timeout = 15.0


def get(context=None):
    """The add-on's preferences (or their defaults)."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ADDON_ID)
    return addon.preferences if addon is not None else _Defaults()


def register():
    bpy.utils.register_class(TessdPreferences)


def unregister():
    bpy.utils.unregister_class(TessdPreferences)
