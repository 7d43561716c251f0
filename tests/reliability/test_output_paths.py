"""Where requests and job files may write (issue 18, part 3). The rule: the daemon runs as its
user and writes only where that user may; it never opens a symbolic link planted at an
output's temporary name (`O_CREAT | O_EXCL | O_NOFOLLOW`), replaces a symbolic link planted
at the destination itself (rename) rather than writing through it, and creates outputs with
mode 0666 less the user's umask (tessd_mesh::io::TempOutput, which every output goes through).
"""

from __future__ import annotations

import json
import os
import stat
import subprocess

import numpy as np
import pytest

import tessd
from daemon_util import DaemonProcess, read_ply, tessd_temps

TRIANGLE = {"positions": np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32),
            "face_indices": np.array([[0, 1, 2], [2, 1, 3]], np.uint32)}

#: The writers: the shared one (meshes, USD, PNG) and the codec's own file output.
WRITES = {
    "ply": ("mesh.convert", {}, TRIANGLE),
    "tsc": ("codec.compress", {}, TRIANGLE),
}


def write(client: tessd.Client, ext: str, dest: str) -> None:
    op, params, arrays = WRITES[ext]
    result, _ = client.call(op, dict(params, output=dest), arrays)
    assert os.path.getsize(dest) > 0, result


def check_written(ext: str, dest: str) -> None:
    st = os.lstat(dest)
    assert stat.S_ISREG(st.st_mode), f"{dest} is not a regular file"
    if ext == "ply":
        positions, faces = read_ply(dest)
        assert faces == [[0, 1, 2], [2, 1, 3]] and len(positions) == 4
    else:
        with open(dest, "rb") as f:
            assert len(f.read()) > 16


@pytest.fixture
def daemon(tessd_bin, tmpdir_short):
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "o.sock")).start()
    try:
        yield d
    finally:
        d.stop()


@pytest.mark.parametrize("ext", sorted(WRITES))
def test_a_symlink_at_the_destination_is_replaced_not_written_through(ext, daemon,
                                                                      tmpdir_short):
    out = os.path.join(tmpdir_short, "out")
    victims = os.path.join(tmpdir_short, "victims")
    os.mkdir(out)
    os.mkdir(victims)
    victim = os.path.join(victims, "precious." + ext)
    with open(victim, "wb") as f:
        f.write(b"precious")
    dangling = os.path.join(victims, "never-created." + ext)
    with tessd.Client(daemon.socket, timeout=30) as c:
        for target in (victim, dangling):
            dest = os.path.join(out, "asset." + ext)
            os.symlink(target, dest)
            write(c, ext, dest)
            check_written(ext, dest)
            os.unlink(dest)
    with open(victim, "rb") as f:
        assert f.read() == b"precious"
    assert sorted(os.listdir(victims)) == ["precious." + ext]
    assert os.listdir(out) == []


@pytest.mark.parametrize("ext", sorted(WRITES))
def test_symlinks_planted_at_temporary_names_are_not_followed(ext, tessd_bin, tmpdir_short):
    # A fresh daemon numbers its temporary files from 0: plant links at the first names.
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "p.sock")).start()
    try:
        out = os.path.join(tmpdir_short, "out")
        victims = os.path.join(tmpdir_short, "victims")
        os.mkdir(out)
        os.mkdir(victims)
        victim = os.path.join(victims, "precious")
        with open(victim, "wb") as f:
            f.write(b"precious")
        planted = 64
        for n in range(planted):
            target = victim if n % 2 else os.path.join(victims, "new-%d" % n)
            os.symlink(target, os.path.join(out, ".asset.%s.tmp-%d-%d" % (ext, d.pid, n)))
        dest = os.path.join(out, "asset." + ext)
        with tessd.Client(d.socket, timeout=30) as c:
            write(c, ext, dest)
        check_written(ext, dest)
        with open(victim, "rb") as f:
            assert f.read() == b"precious"
        assert os.listdir(victims) == ["precious"], "a link was written through"
        links = [n for n in os.listdir(out) if n != "asset." + ext]
        assert len(links) == planted and all(os.path.islink(os.path.join(out, n)) for n in links)
    finally:
        d.stop()


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o077])
def test_outputs_get_the_users_umask(umask, tessd_bin, tmpdir_short):
    d = DaemonProcess(tessd_bin, os.path.join(tmpdir_short, "u.sock"), umask=umask).start()
    try:
        with tessd.Client(d.socket, timeout=30) as c:
            for ext in sorted(WRITES):
                dest = os.path.join(tmpdir_short, "out." + ext)
                write(c, ext, dest)
                assert stat.S_IMODE(os.stat(dest).st_mode) == 0o666 & ~umask, (ext, umask)
    finally:
        d.stop()


def test_the_daemon_writes_only_where_its_user_may(public_bin, tmpdir_short, other_user):
    """A daemon (and a job file) run by the other user cannot write into root's folder, through
    `..` or otherwise; its own folder gets files owned by it."""
    os.chmod(tmpdir_short, 0o755)
    home = os.path.join(tmpdir_short, "other")
    os.mkdir(home, 0o700)
    os.chown(home, other_user.pw_uid, other_user.pw_gid)
    roots = os.path.join(tmpdir_short, "roots")
    os.mkdir(roots, 0o755)
    os.chmod(roots, 0o755)
    d = DaemonProcess(public_bin, os.path.join(home, "d.sock"), user=other_user.pw_uid,
                      log_path=os.path.join(tmpdir_short, "d.log"))
    d.start()
    try:
        with tessd.Client(d.socket, timeout=30) as c:
            for dest in (os.path.join(roots, "x.ply"),
                         os.path.join(home, "..", "roots", "y.ply")):
                with pytest.raises(tessd.TessdError) as info:
                    c.call("mesh.convert", {"output": dest}, TRIANGLE)
                assert info.value.code == "io", info.value
                assert dest in info.value.message and "Permission denied" in info.value.message
            mine = os.path.join(home, "mine.ply")
            c.call("mesh.convert", {"output": mine}, TRIANGLE)
            assert os.stat(mine).st_uid == other_user.pw_uid
        assert os.listdir(roots) == []
        assert tessd_temps(home) == []
    finally:
        d.stop()
    # The same with a job file the other user runs, its output relative to the job's folder.
    job = os.path.join(home, "job.json")
    with open(job, "w") as f:
        json.dump({"op": "mesh.convert", "params": {
            "input": "mine.ply", "output": "../roots/z.ply"}}, f)
    os.chown(job, other_user.pw_uid, other_user.pw_gid)
    out = subprocess.run([public_bin, "job", "run", job], capture_output=True, timeout=30,
                         user=other_user.pw_uid, group=other_user.pw_gid, extra_groups=[])
    text = (out.stdout + out.stderr).decode("utf-8", "replace")
    assert out.returncode != 0 and "Permission denied" in text and "z.ply" in text, text
    assert os.listdir(roots) == []
