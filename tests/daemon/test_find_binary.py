"""Which executable `tessd.daemon.find_binary` (and so `ensure_daemon`) starts: the `binary`
argument, then $TESSD_BIN, then the binary the tessd wheel installed for this Python (the scripts
folder of its install scheme, the folder of `sys.executable`, the user scheme's scripts folder),
then `tessd` on PATH.

Real files: each candidate is a small executable shell script that answers `--version` with its
own name, run for real through `binary_version`; only where the interpreter says its folders are
(sysconfig's scripts path, sys.executable, the user site switch) and PATH are redirected to
temporary folders, so that a tessd installed on this machine never takes part.
"""

from __future__ import annotations

import os
import site
import stat
import sys
import sysconfig

import pytest

from tessd import daemon
from tessd.daemon import DaemonStartError, binary_version, find_binary, installed_binary_dirs

EXE = "tessd.exe" if os.name == "nt" else "tessd"

pytestmark = pytest.mark.skipif(os.name == "nt", reason="the fake binaries are shell scripts")


def fake_tessd(folder, version, name=EXE, executable=True):
    """A `tessd` in `folder` that prints `tessd <version>` for `--version`."""
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(str(folder), name)
    with open(path, "w") as f:
        f.write("#!/bin/sh\necho 'tessd %s'\n" % version)
    mode = stat.S_IRUSR | stat.S_IWUSR
    if executable:
        mode |= stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH
    os.chmod(path, mode)
    return path


@pytest.fixture
def places(tmp_path, monkeypatch):
    """Empty stand-ins for every place find_binary looks: returns the folders
    (scripts, exe_dir, path_dir); TESSD_BIN unset, the user site off."""
    scripts = tmp_path / "venv" / "bin"
    exe_dir = tmp_path / "python" / "bin"
    path_dir = tmp_path / "on-path"
    for d in (scripts, exe_dir, path_dir):
        d.mkdir(parents=True)
    real_get_path = sysconfig.get_path

    def get_path(name, *args, **kwargs):
        if name == "scripts" and not args and not kwargs:
            return str(scripts)
        return real_get_path(name, *args, **kwargs)

    monkeypatch.setattr(sysconfig, "get_path", get_path)
    monkeypatch.setattr(sys, "executable", str(exe_dir / "python3"))
    monkeypatch.setattr(site, "ENABLE_USER_SITE", False)
    monkeypatch.setenv("PATH", str(path_dir))
    monkeypatch.delenv("TESSD_BIN", raising=False)
    return scripts, exe_dir, path_dir


def test_installed_dirs_in_order(places):
    scripts, exe_dir, _ = places
    assert installed_binary_dirs() == [str(scripts), str(exe_dir)]


def test_installed_dirs_of_this_interpreter():
    """Unpatched: the first folder is where pip puts this interpreter's commands."""
    dirs = installed_binary_dirs()
    assert dirs[0] == os.path.abspath(sysconfig.get_path("scripts"))
    assert os.path.dirname(os.path.abspath(sys.executable)) in dirs
    assert len(dirs) == len(set(dirs))


def test_binary_argument_wins(places, tmp_path, monkeypatch):
    scripts, exe_dir, path_dir = places
    arg = fake_tessd(tmp_path / "arg", "1.0.0")
    monkeypatch.setenv("TESSD_BIN", fake_tessd(tmp_path / "env", "2.0.0"))
    fake_tessd(scripts, "3.0.0")
    fake_tessd(path_dir, "5.0.0")
    assert find_binary(arg) == arg
    assert binary_version(arg) == "1.0.0"


def test_tessd_bin_wins_over_installed_and_path(places, tmp_path, monkeypatch):
    scripts, exe_dir, path_dir = places
    env = fake_tessd(tmp_path / "env", "2.0.0")
    monkeypatch.setenv("TESSD_BIN", env)
    fake_tessd(scripts, "3.0.0")
    fake_tessd(exe_dir, "4.0.0")
    fake_tessd(path_dir, "5.0.0")
    assert find_binary() == env
    assert binary_version() == "2.0.0"


def test_bad_tessd_bin_is_an_error(places, tmp_path, monkeypatch):
    """A TESSD_BIN that names no executable fails rather than falling back to another binary."""
    scripts, _, _ = places
    fake_tessd(scripts, "3.0.0")
    monkeypatch.setenv("TESSD_BIN", str(tmp_path / "missing" / "tessd"))
    with pytest.raises(DaemonStartError, match="TESSD_BIN"):
        find_binary()


def test_scripts_folder_wins_over_path(places):
    """The wheel's binary in the scripts folder is found though that folder is not on PATH
    (a venv used without activating it), and before a tessd on PATH."""
    scripts, exe_dir, path_dir = places
    installed = fake_tessd(scripts, "3.0.0")
    fake_tessd(exe_dir, "4.0.0")
    fake_tessd(path_dir, "5.0.0")
    assert find_binary() == installed
    assert binary_version() == "3.0.0"


def test_next_to_sys_executable(places):
    _, exe_dir, path_dir = places
    beside = fake_tessd(exe_dir, "4.0.0")
    fake_tessd(path_dir, "5.0.0")
    assert find_binary() == beside
    assert binary_version() == "4.0.0"


def test_user_scripts_folder_when_user_site_is_on(places, tmp_path, monkeypatch):
    _, _, path_dir = places
    user_scripts = tmp_path / "user" / "bin"
    real_get_path = sysconfig.get_path  # the `places` stand-in

    def get_path(name, *args, **kwargs):
        if name == "scripts" and args and args[0].endswith("_user"):
            return str(user_scripts)
        return real_get_path(name, *args, **kwargs)

    monkeypatch.setattr(sysconfig, "get_path", get_path)
    monkeypatch.setattr(site, "ENABLE_USER_SITE", True)
    assert installed_binary_dirs()[-1] == str(user_scripts)
    user = fake_tessd(user_scripts, "6.0.0")
    fake_tessd(path_dir, "5.0.0")
    assert find_binary() == user


def test_not_executable_is_skipped(places):
    scripts, _, path_dir = places
    fake_tessd(scripts, "3.0.0", executable=False)
    on_path = fake_tessd(path_dir, "5.0.0")
    assert find_binary() == on_path


def test_path_is_last(places):
    _, _, path_dir = places
    on_path = fake_tessd(path_dir, "5.0.0")
    assert find_binary() == on_path
    assert binary_version() == "5.0.0"


def test_none_found(places):
    scripts, exe_dir, _ = places
    with pytest.raises(DaemonStartError) as e:
        find_binary()
    assert str(scripts) in str(e.value) and str(exe_dir) in str(e.value)
    assert "TESSD_BIN" in str(e.value)


def test_ensure_daemon_starts_the_installed_binary(places, tessd_bin, tmpdir_short):
    """ensure_daemon with no binary, no TESSD_BIN and nothing on PATH starts the real daemon
    from the scripts folder (as a wheel installs it there; a link to the build here)."""
    scripts, _, _ = places
    os.symlink(tessd_bin, str(scripts / EXE))
    sock = os.path.join(tmpdir_short, "t.sock")
    assert daemon.ensure_daemon(sock, timeout=20) == sock
    try:
        assert daemon.ping(sock)
        assert binary_version() == binary_version(tessd_bin)
    finally:
        assert daemon.stop_daemon(sock)
