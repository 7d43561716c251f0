"""The extension builds to a zip that Blender's own tool validates, bundles the client, and
installs and registers as Blender installs extensions."""

from __future__ import annotations

import importlib.util
import subprocess
import zipfile

from addon_env import ADDON, REPO


def test_zip_contents_and_validation(addon_zip):
    path, log = addon_zip
    assert path.name == "tessd-0.1.0.zip"
    assert "Success parsing TOML" in log, log  # blender_ext.py validate (= blender --command extension validate)
    names = set(zipfile.ZipFile(path).namelist())
    for required in ("blender_manifest.toml", "__init__.py", "jobs.py", "convert.py",
                     "vendor/__init__.py", "vendor/tessd/__init__.py", "vendor/tessd/client.py"):
        assert required in names
    assert "build.py" not in names
    # The client is copied at build time, never kept in the add-on folder.
    assert not (REPO / "blender_addon" / "vendor").exists()
    tracked = subprocess.run(["git", "ls-files", "--others", "--cached", "--exclude-standard",
                              "blender_addon"], cwd=REPO, stdout=subprocess.PIPE, text=True).stdout
    assert "vendor/" not in tracked and "dist/" not in tracked


def test_validate_rejects_a_broken_manifest(tmp_path):
    """The validation step really checks: a zip whose manifest lacks `id` is refused."""
    spec = importlib.util.spec_from_file_location("tessd_addon_build", REPO / "blender_addon" / "build.py")
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    bad = tmp_path / "bad.zip"
    with zipfile.ZipFile(bad, "w") as z:
        z.writestr("blender_manifest.toml", 'schema_version = "1.0.0"\nname = "x"\n')
        z.writestr("__init__.py", "")
    assert build.validate(str(bad), build.find_blender_ext()) != 0


def test_installed_and_registered(addon):
    import bpy

    assert addon.__name__ == ADDON
    for op in ("simplify", "generate_lods", "subdivide", "export_usd"):
        assert hasattr(bpy.ops.tessd, op)
        rna = getattr(bpy.ops.tessd, op).get_rna_type()
        assert rna.properties  # registered with its properties
    props = bpy.ops.tessd.simplify.get_rna_type().properties
    for name in ("method", "cells", "max_error", "max_error_relative", "target",
                 "target_is_percent", "representative", "show_partition", "replace"):
        assert name in props, name
    assert {i.identifier for i in props["method"].enum_items} == {"GRID", "QUALITY", "COMPLEXITY"}
    assert {i.identifier for i in props["representative"].enum_items} == {
        "BARYCENTER", "HEAVIEST", "QUADRIC"}
    schemes = {i.identifier for i in bpy.ops.tessd.subdivide.get_rna_type().properties["scheme"].enum_items}
    assert {"CATMULL_CLARK", "LOOP", "BUTTERFLY", "DOO_SABIN", "SQRT3", "BILINEAR"} <= schemes
    assert hasattr(bpy.types, "VIEW3D_MT_tessd")
    # The vendored client is the one in use (relative import inside the extension).
    assert addon.client.tessd.__name__ == ADDON + ".vendor.tessd"
