"""The extension builds to a per-platform zip that Blender's own tool validates, bundles the
client and the daemon (bin/tessd, executable), and installs and registers as Blender installs
extensions."""

from __future__ import annotations

import importlib.util
import platform
import stat
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import locate
from addon_env import ADDON, REPO


def _build_module():
    spec = importlib.util.spec_from_file_location("tessd_addon_build", REPO / "blender_addon" / "build.py")
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    return build


def _platform():
    """This machine in Blender's spelling, computed here independently of build.py."""
    machine = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64"}.get(
        platform.machine().lower(), platform.machine().lower())
    system = {"darwin": "macos"}.get(platform.system().lower(), platform.system().lower())
    return "%s-%s" % (system, machine)


def test_zip_contents_and_validation(addon_zip):
    path, log = addon_zip
    plat = _platform()
    assert path.name == "tessd-0.1.0-%s.zip" % plat
    assert "Success parsing TOML" in log, log  # blender_ext.py validate (= blender --command extension validate)
    z = zipfile.ZipFile(path)
    names = set(z.namelist())
    for required in ("blender_manifest.toml", "__init__.py", "jobs.py", "convert.py",
                     "vendor/__init__.py", "vendor/tessd/__init__.py", "vendor/tessd/client.py"):
        assert required in names
    assert "build.py" not in names
    # The client is copied at build time, never kept in the add-on folder.
    assert not (REPO / "blender_addon" / "vendor").exists()
    tracked = subprocess.run(["git", "ls-files", "--others", "--cached", "--exclude-standard",
                              "blender_addon"], cwd=REPO, stdout=subprocess.PIPE, text=True).stdout
    assert "vendor/" not in tracked and "dist/" not in tracked
    # The platform: in the zip's manifest only (the one in git lists none).
    manifest = tomllib.loads(z.read("blender_manifest.toml").decode("utf-8"))
    assert manifest["platforms"] == [plat]
    assert manifest["version"] == "0.1.0" and manifest["id"] == "tessd"
    assert "platforms" not in tomllib.loads((REPO / "blender_addon" / "blender_manifest.toml").read_text())
    # The daemon: the release binary, rwxr-xr-x in the zip's external attributes.
    info = z.getinfo("bin/tessd")
    mode = info.external_attr >> 16
    assert stat.S_ISREG(mode) and mode & 0o777 == 0o755, oct(mode)
    assert z.read("bin/tessd") == locate.tessd_bin().read_bytes()


def test_zip_installs_on_this_platform_only(addon_zip, tmp_path):
    """Blender's own tool accepts the zip here and refuses it for another platform, so
    `platforms` really is what Blender checks."""
    build = _build_module()
    tool = build.find_blender_ext()
    other = "windows-x64" if _platform() != "windows-x64" else "linux-x64"

    def install(zip_path, repo):
        repo.mkdir()
        return subprocess.run([sys.executable, tool, "install-files", "--local-dir", str(repo),
                               "--blender-version", "5.0.1", "--python-version", "3.11.0", str(zip_path)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True).stdout

    log = install(addon_zip[0], tmp_path / "here")
    assert (tmp_path / "here" / "tessd" / "bin" / "tessd").is_file(), log
    # build.py takes only a binary of the platform's format (PE for windows-*): a stand-in
    # with a PE header, as the binary's content plays no part in Blender's platform check
    # (tests/windows builds the real windows-x64 zip from the cross-built tessd.exe).
    stand_in = tmp_path / "tessd.exe"
    stand_in.write_bytes(b"MZ" + bytes(62))
    foreign = build.build(str(tmp_path / "dist"), binary=str(stand_in), platform=other)
    assert foreign.endswith("tessd-0.1.0-%s.zip" % other)
    assert "bin/tessd.exe" in zipfile.ZipFile(foreign).namelist()
    log = install(foreign, tmp_path / "there")
    assert not (tmp_path / "there" / "tessd").exists(), log
    assert "isn't one of (%s)" % other in log, log


def test_build_refuses_a_binary_of_another_platform(tmp_path):
    """The Linux binary never goes into a Windows zip (nor a PE file into a Linux one): the
    error names the platform, the binary and the format it has."""
    for plat, binary, has in (("windows-x64", locate.tessd_bin(), "an ELF executable"),
                              ("macos-arm64", locate.tessd_bin(), "an ELF executable"),
                              ("linux-x64", REPO / "README.md", "none of PE, ELF")):
        proc = subprocess.run([sys.executable, str(REPO / "blender_addon" / "build.py"), "--out",
                               str(tmp_path), "--binary", str(binary), "--platform", plat,
                               "--no-validate"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert proc.returncode != 0, proc.stdout
        assert "--platform %s needs" % plat in proc.stdout, proc.stdout
        assert str(binary) in proc.stdout and has in proc.stdout, proc.stdout
    assert not list(tmp_path.glob("*.zip"))


def test_default_binary_of_a_cross_build(monkeypatch, tmp_path):
    """Without --binary a foreign platform's zip takes cargo's cross build of it."""
    build = _build_module()
    monkeypatch.setenv("CARGO_TARGET_DIR", str(tmp_path))
    assert build.default_binary("windows-x64") == str(
        tmp_path / "x86_64-pc-windows-gnu" / "release" / "tessd.exe")
    assert build.default_binary(_platform()) == str(tmp_path / "release" / "tessd")


def test_build_needs_the_binary(tmp_path):
    proc = subprocess.run([sys.executable, str(REPO / "blender_addon" / "build.py"), "--out",
                           str(tmp_path), "--binary", str(tmp_path / "nope" / "tessd")],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.returncode != 0
    assert "nope/tessd does not exist" in proc.stdout and "cargo build --release" in proc.stdout
    assert not list(tmp_path.glob("*.zip"))


def test_validate_rejects_a_broken_manifest(tmp_path):
    """The validation step really checks: a zip whose manifest lacks `id` is refused."""
    build = _build_module()
    bad = tmp_path / "bad.zip"
    with zipfile.ZipFile(bad, "w") as z:
        z.writestr("blender_manifest.toml", 'schema_version = "1.0.0"\nname = "x"\n')
        z.writestr("__init__.py", "")
    assert build.validate(str(bad), build.find_blender_ext()) != 0


def test_default_output_is_outside_the_sources():
    """Without --out the zip goes to dist/ at the repository's root, not into blender_addon/."""
    build = _build_module()
    out = build.make_parser().parse_args([]).out
    assert out == str(REPO / "dist") == build.DEFAULT_OUT
    assert not out.startswith(str(REPO / "blender_addon"))


def test_validator_is_found_in_the_running_python_and_on_path(tmp_path, monkeypatch):
    """build.py looks for Blender's blender_ext.py in the running Python's bpy (here .venv's),
    then beside a `blender` on PATH, and says where it looked when none has it."""
    import sysconfig

    build = _build_module()
    places = build.blender_ext_places()
    # The running Python (.venv's) has bpy installed: the first place is its package.
    assert places[0] == str(Path(sysconfig.get_paths()["purelib"]) / "bpy" / "*" / build.BLENDER_EXT)
    assert build.find_blender_ext([places[0]]) is not None
    # A Blender install on PATH: <prefix>/blender and <prefix>/5.0/scripts/addons_core/...
    install = tmp_path / "blender-5.0-linux-x64"
    tool = install / "5.0" / "scripts" / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    tool.parent.mkdir(parents=True)
    tool.write_text("# stand-in\n")
    exe = install / "blender"
    exe.write_text("#!/bin/sh\n")
    exe.chmod(0o755)
    monkeypatch.setenv("PATH", "%s:/usr/bin:/bin" % install)
    places = build.blender_ext_places()
    assert str(install / "*" / build.BLENDER_EXT) in places
    assert build.find_blender_ext([p for p in places if p.startswith(str(install))]) == str(tool)
    # Nowhere: the output names every place it looked.
    monkeypatch.setattr(build, "blender_ext_places", lambda: [str(tmp_path / "nowhere" / "*.py")])
    monkeypatch.setattr(build, "build", lambda out, binary, plat: str(tmp_path / "x.zip"))
    import contextlib
    import io

    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert build.main(["--out", str(tmp_path)]) == 0
    print("\n" + text.getvalue())
    assert "blender_ext.py not found; looked in:" in text.getvalue()
    assert str(tmp_path / "nowhere" / "*.py") in text.getvalue()


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
    assert hasattr(bpy.ops.tessd, "open_preferences")  # the button failures offer
    # The vendored client is the one in use (relative import inside the extension).
    assert addon.client.tessd.__name__ == ADDON + ".vendor.tessd"
