"""Menus: Object ▸ tessd and the object context menu (right click in Object mode)."""

import bpy


class VIEW3D_MT_tessd(bpy.types.Menu):
    bl_idname = "VIEW3D_MT_tessd"
    bl_label = "tessd"

    def draw(self, context):
        layout = self.layout
        layout.operator_context = 'INVOKE_DEFAULT'
        layout.operator("tessd.simplify", text="Simplify…")
        layout.operator("tessd.generate_lods", text="Generate LODs…")
        layout.operator("tessd.subdivide", text="Subdivide…")
        layout.separator()
        layout.operator("tessd.export_usd", text="Export USD via tessd…")
        layout.operator("tessd.import_compressed", text="Import compressed mesh (view-dependent)…")
        layout.operator("tessd.view_compressed", text="View compressed mesh live…")


def _draw(self, context):
    self.layout.separator()
    self.layout.menu(VIEW3D_MT_tessd.bl_idname)


def _draw_import(self, context):
    self.layout.operator("tessd.import_compressed", text="Compressed mesh (.tsc, view-dependent)")
    self.layout.operator("tessd.view_compressed", text="Compressed mesh, live (.tsc)")


def register():
    bpy.utils.register_class(VIEW3D_MT_tessd)
    bpy.types.TOPBAR_MT_file_import.append(_draw_import)
    bpy.types.VIEW3D_MT_object.append(_draw)
    bpy.types.VIEW3D_MT_object_context_menu.append(_draw)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_draw_import)
    bpy.types.VIEW3D_MT_object_context_menu.remove(_draw)
    bpy.types.VIEW3D_MT_object.remove(_draw)
    bpy.utils.unregister_class(VIEW3D_MT_tessd)
