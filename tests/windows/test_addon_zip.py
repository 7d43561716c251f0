"""The windows-x64 Blender extension: `blender_addon/build.py --platform windows-x64 --binary
tessd.exe` bundles the cross-built daemon as bin/tessd.exe, the manifest names windows-x64 only,
Blender's own validator (blender_ext.py of the bpy module in .venv) passes the zip, and nothing
of the Linux build is in it."""

from __future__ import annotations

import subprocess
import sys
import tomllib
import zipfile

import pytest

from win_checks import REPO, file_says, pe_kind


@pytest.fixture(scope="module")
def windows_zip(windows_exe, tmp_path_factory):
    """(zip path, build.py's output) for the windows-x64 extension, validated by build.py."""
    out = tmp_path_factory.mktemp("dist")
    proc = subprocess.run([sys.executable, str(REPO / "blender_addon" / "build.py"),
                           "--platform", "windows-x64", "--binary", str(windows_exe),
                           "--out", str(out)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.returncode == 0, proc.stdout
    zips = sorted(out.glob("*.zip"))
    assert [z.name for z in zips] == ["tessd-0.1.0-windows-x64.zip"], proc.stdout
    return zips[0], proc.stdout


def test_blenders_validator_passes_it(windows_zip):
    path, log = windows_zip
    # build.py ran Blender's `extension validate` (blender_ext.py) and exited 0 only on success.
    assert 'Success parsing TOML in "%s"' % path in log, log
    assert "not validated" not in log, log


def test_manifest_names_windows_only(windows_zip):
    z = zipfile.ZipFile(windows_zip[0])
    manifest = tomllib.loads(z.read("blender_manifest.toml").decode("utf-8"))
    assert manifest["platforms"] == ["windows-x64"]
    assert manifest["id"] == "tessd" and manifest["version"] == "0.1.0"


def test_bundles_the_cross_built_exe_and_no_linux_binary(windows_zip, windows_exe, tmp_path):
    z = zipfile.ZipFile(windows_zip[0])
    names = z.namelist()
    binaries = [n for n in names if n.startswith("bin/")]
    assert binaries == ["bin/tessd.exe"], binaries
    exe = z.read("bin/tessd.exe")
    assert exe == windows_exe.read_bytes()
    assert pe_kind(exe) == "PE32+ x86-64 console"
    described = file_says(exe, tmp_path)
    assert described.startswith("PE32+ executable") and "x86-64" in described, described
    assert "MS Windows" in described, described
    # Not one ELF (or Mach-O) file anywhere in the zip.
    for name in names:
        head = z.read(name)[:4]
        assert head != b"\x7fELF" and head not in (b"\xcf\xfa\xed\xfe", b"\xca\xfe\xba\xbe"), name


def test_carries_the_client_with_the_windows_rules(windows_zip):
    """The vendored client is python/tessd as it is (its named-pipe naming and transport)."""
    z = zipfile.ZipFile(windows_zip[0])
    for module in ("socket_path.py", "transport.py", "daemon.py", "client.py"):
        assert z.read("vendor/tessd/" + module) == (REPO / "python" / "tessd" / module).read_bytes()
    assert b"def windows_pipe(" in z.read("vendor/tessd/socket_path.py")
    assert z.read("daemon.py") == (REPO / "blender_addon" / "daemon.py").read_bytes()
