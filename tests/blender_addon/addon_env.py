"""Installing the built extension the way Blender does, shared by the add-on tests."""

from __future__ import annotations

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
REPO_NAME = "tessd_test"
ADDON = "bl_ext.%s.tessd" % REPO_NAME

def install_addon(zip_path, repo_dir, socket, auto_start=False, binary=""):
    """A fresh empty Blender session with the extension installed and enabled; returns the
    add-on's package module."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    prefs = bpy.context.preferences
    repo = prefs.extensions.repos.new(name=REPO_NAME, module=REPO_NAME,
                                      custom_directory=str(repo_dir), source='USER')
    assert repo.enabled
    result = bpy.ops.extensions.package_install_files(
        filepath=str(zip_path), repo=REPO_NAME, enable_on_install=True)
    assert result == {'FINISHED'}
    assert ADDON in prefs.addons, [a.module for a in prefs.addons]
    p = prefs.addons[ADDON].preferences
    p.socket = socket
    p.auto_start = auto_start
    p.binary_path = binary
    return sys.modules[ADDON]

def uninstall_addon():
    import addon_utils
    import bpy

    addon_utils.disable(ADDON, default_set=True)
    repos = bpy.context.preferences.extensions.repos
    for r in list(repos):
        if r.module == REPO_NAME:
            repos.remove(r)
