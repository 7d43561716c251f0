"""The win_amd64 wheel from maturin's cross build (scripts/windows/wheel.sh: `pip wheel ./python`
with MATURIN_PEP517_ARGS="--target x86_64-pc-windows-gnu", linked by mingw): its tag, the
tessd.exe in its scripts data (the very file of $TESSD_WINDOWS_EXE: cargo reuses that build),
the pure-Python client as in python/tessd, no Linux binary; and pip, asked to install it for
win_amd64, puts tessd.exe in the scripts folder and the package beside it."""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from win_checks import REPO, file_says, pe_kind

VERSION = "0.1.0"
DATA = "tessd-%s.data/scripts/" % VERSION


@pytest.fixture(scope="module")
def wheel(windows_exe, tmp_path_factory) -> Path:
    """The wheel scripts/windows/wheel.sh builds into the cargo target folder of
    $TESSD_WINDOWS_EXE (<target dir>/x86_64-pc-windows-gnu/release/tessd.exe)."""
    release = windows_exe.parent
    assert release.name == "release" and release.parent.name == "x86_64-pc-windows-gnu", (
        "TESSD_WINDOWS_EXE must be <target dir>/x86_64-pc-windows-gnu/release/tessd.exe, "
        "not %s" % windows_exe)
    out = tmp_path_factory.mktemp("wheel")
    env = dict(os.environ, CARGO_TARGET_DIR=str(release.parent.parent), PYTHON=sys.executable)
    proc = subprocess.run(["bash", str(REPO / "scripts" / "windows" / "wheel.sh"), str(out)],
                          env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    path = Path(proc.stdout.strip().splitlines()[-1])
    assert path.parent == out and path.is_file(), proc.stdout
    return path


def test_tag_is_win_amd64(wheel):
    assert wheel.name == "tessd-%s-py3-none-win_amd64.whl" % VERSION
    meta = zipfile.ZipFile(wheel).read("tessd-%s.dist-info/WHEEL" % VERSION).decode()
    fields = dict(line.split(": ", 1) for line in meta.splitlines() if ": " in line)
    assert fields["Tag"] == "py3-none-win_amd64", meta
    assert fields["Root-Is-Purelib"] == "false", meta


def test_carries_the_cross_built_exe_and_no_linux_binary(wheel, windows_exe, tmp_path):
    z = zipfile.ZipFile(wheel)
    scripts = sorted(n for n in z.namelist() if n.startswith(DATA))
    assert scripts == [DATA + "tessd.exe"], scripts
    exe = z.read(DATA + "tessd.exe")
    assert exe == windows_exe.read_bytes(), "the wheel's tessd.exe is not $TESSD_WINDOWS_EXE"
    assert pe_kind(exe) == "PE32+ x86-64 console"
    described = file_says(exe, tmp_path)
    assert described.startswith("PE32+ executable") and "MS Windows" in described, described
    for name in z.namelist():
        assert z.read(name)[:4] != b"\x7fELF", name


def test_carries_the_pure_python_client(wheel):
    z = zipfile.ZipFile(wheel)
    names = set(z.namelist())
    sources = sorted(p.relative_to(REPO / "python").as_posix()
                     for p in (REPO / "python" / "tessd").rglob("*.py")
                     if "__pycache__" not in p.parts)
    assert "tessd/socket_path.py" in sources and "tessd/transport.py" in sources
    for name in sources:
        assert name in names, name
        assert z.read(name) == (REPO / "python" / name).read_bytes(), name
    assert not [n for n in names if n.endswith((".pyc", ".so", ".pyd"))]
    record = z.read("tessd-%s.dist-info/RECORD" % VERSION).decode()
    recorded = {line.split(",", 1)[0] for line in record.splitlines() if line}
    assert names <= recorded | {"tessd-%s.dist-info/RECORD" % VERSION}, names - recorded


def test_pip_installs_it_for_windows(wheel, windows_exe, tmp_path):
    """pip (this Python's) accepts the tag for win_amd64 and lays out what a Windows venv gets:
    tessd.exe among the scripts (bin/ under --target), the package importable beside them."""
    target = tmp_path / "site"
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index",
                           "--disable-pip-version-check", "--platform", "win_amd64",
                           "--only-binary=:all:", "--target", str(target), str(wheel)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.returncode == 0, proc.stdout
    assert (target / "bin" / "tessd.exe").read_bytes() == windows_exe.read_bytes()
    assert (target / "tessd" / "socket_path.py").is_file()
    # The installed client maps the Windows names as the daemon does (pure functions).
    check = ("import sys; sys.path.insert(0, sys.argv[1]); import tessd.socket_path as s; "
             "print(s.__file__); print(s.windows_pipe('work', 'Ann Lee'))")
    out = subprocess.run([sys.executable, "-I", "-c", check, str(target)], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, cwd=str(tmp_path)).stdout.split("\n")
    assert out[0] == str(target / "tessd" / "socket_path.py"), out
    assert out[1] == "\\\\.\\pipe\\tessd-Ann_Lee-work", out
