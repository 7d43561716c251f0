"""tessd for Blender: the daemon's mesh operations one click away.

The add-on is thin on purpose: it converts Blender meshes to the protocol's arrays and back
(convert.py), drives daemon requests without blocking the UI (jobs.py) and offers the
operators and menus. All geometry is computed by the `tessd` daemon, reached through the
`tessd` Python client that build.py bundles as the `vendor` subpackage.

Scripting contract (public API): bpy.ops.tessd.simplify, generate_lods, subdivide, export_usd,
import_compressed, view_compressed.
"""

from . import (daemon, jobs, menus, ops_export, ops_import_compressed, ops_lods, ops_simplify,
               ops_subdivide, ops_view_compressed, preferences)

_MODULES = (preferences, jobs, ops_simplify, ops_lods, ops_subdivide, ops_export,
            ops_import_compressed, ops_view_compressed, menus)


def register():
    for module in _MODULES:
        module.register()
    daemon.register()


def unregister():
    daemon.unregister()
    for module in reversed(_MODULES):
        module.unregister()
