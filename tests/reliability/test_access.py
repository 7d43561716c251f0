"""Access control (issue 18, part 3), checked with a second system user (created by the
`other_user` fixture; the tests run as root, as CI does).

- The socket is mode 0600, in a 0700 folder owned by the user: the default per-user folder
  (`$TMPDIR/tessd-<uid>`) and any `--socket PATH`. Another user is refused at connect; the
  same probe succeeds once the modes are opened, so it is the modes that refuse.
- Nothing planted at the socket path or its folder is followed or destroyed: a symbolic link
  there (to another daemon's socket, to a file, to another folder, dangling), a regular file,
  or a folder owned by another user makes `tessd serve` refuse to start with a message naming
  it, and leaves the thing and its target as they were.
- A crashed daemon's socket file (SIGKILL) is stale: the next `tessd serve` takes over.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import stat
import subprocess
from typing import Any, Dict, Optional

import pytest

import tessd
from daemon_util import DaemonProcess, raw_frame
from tessd.frame import read_frame


def connect_as(user, path: str) -> Dict[str, Any]:
    """Connects to the socket at `path` as `user` (a forked child that drops to that user's
    uid and gid, no other groups) and sends `ping`. Returns {"errno": 0, "reply": ...} when
    it got an answer, else {"errno": E, "error": text}."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: no Python-level cleanup, exit straight after reporting
        try:
            os.close(r)
            os.setgroups([])
            os.setgid(user.pw_gid)
            os.setuid(user.pw_uid)
            try:
                s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                s.settimeout(10)
                s.connect(path)
                s.sendall(raw_frame({"id": 1, "op": "ping", "params": {"echo": "other"}}))
                message, _ = read_frame(s.recv_into, max_payload=None)
                result = {"errno": 0, "reply": message}
            except OSError as e:
                result = {"errno": e.errno, "error": str(e)}
            os.write(w, json.dumps(result).encode())
        finally:
            os._exit(0)
    os.close(w)
    chunks = []
    while True:
        chunk = os.read(r, 65536)
        if not chunk:
            break
        chunks.append(chunk)
    os.close(r)
    os.waitpid(pid, 0)
    assert chunks, "the probe as the other user reported nothing"
    return json.loads(b"".join(chunks))


def default_env(tmp: str) -> Dict[str, str]:
    """The environment with the default socket under `tmp`: TMPDIR set, XDG_RUNTIME_DIR unset."""
    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    env["TMPDIR"] = tmp
    return env


def mode(path: str) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


def serve_refused(binary: str, args, env: Optional[Dict[str, str]] = None) -> str:
    """Runs `tessd serve ARGS`, which must refuse to start; returns its output."""
    out = subprocess.run([binary, "serve", *args], stdin=subprocess.DEVNULL,
                         capture_output=True, timeout=20, env=env)
    text = (out.stdout + out.stderr).decode("utf-8", "replace")
    assert out.returncode != 0, "tessd serve started:\n" + text
    assert "listening" not in text, text
    return text


# ---------------------------------------------------------------------------------------------
# Modes, and another user at the door


def test_default_socket_is_0600_in_a_0700_folder_and_refuses_another_user(
        tessd_bin, tmpdir_short, other_user):
    os.chmod(tmpdir_short, 0o755)  # others may pass through the temporary folder itself
    folder = os.path.join(tmpdir_short, "tessd-%d" % os.getuid())
    sock = os.path.join(folder, "tessd.sock")
    env = default_env(tmpdir_short)
    d = DaemonProcess(tessd_bin, sock, socket_arg=False, env=env,
                      log_path=os.path.join(tmpdir_short, "d.log")).start()
    try:
        st = os.lstat(folder)
        assert stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid()
        assert mode(folder) == 0o700, oct(mode(folder))
        assert stat.S_ISSOCK(os.lstat(sock).st_mode) and mode(sock) == 0o600, oct(mode(sock))

        refused = connect_as(other_user, sock)
        assert refused["errno"] == 13, refused  # EACCES
        # The same probe gets an answer once both modes are opened: the modes refuse.
        os.chmod(folder, 0o755)
        os.chmod(sock, 0o666)
        try:
            opened = connect_as(other_user, sock)
        finally:
            os.chmod(sock, 0o600)
            os.chmod(folder, 0o700)
        assert opened["errno"] == 0 and opened["reply"]["result"]["echo"] == "other", opened
        # The socket's own mode refuses even where the folder lets others through.
        os.chmod(folder, 0o755)
        try:
            refused_by_socket = connect_as(other_user, sock)
        finally:
            os.chmod(folder, 0o700)
        assert refused_by_socket["errno"] == 13, refused_by_socket
        with tessd.Client(sock, timeout=10) as c:  # its own user still gets in
            assert c.ping("owner") == "owner"
    finally:
        d.stop()
    # A folder opened up meanwhile is closed again by the next start.
    os.chmod(folder, 0o755)
    d = DaemonProcess(tessd_bin, sock, socket_arg=False, env=env,
                      log_path=os.path.join(tmpdir_short, "d.log")).start()
    try:
        assert mode(folder) == 0o700, oct(mode(folder))
        assert connect_as(other_user, sock)["errno"] == 13
    finally:
        d.stop()


def test_socket_path_option_is_0600_and_refuses_another_user(tessd_bin, tmpdir_short,
                                                             other_user):
    os.chmod(tmpdir_short, 0o755)
    # An existing folder others may enter: the socket's mode alone keeps them out.
    shared = os.path.join(tmpdir_short, "shared")
    os.mkdir(shared, 0o755)
    os.chmod(shared, 0o755)
    # A missing folder: created for the user alone.
    fresh = os.path.join(tmpdir_short, "new", "sub")
    for sock in (os.path.join(shared, "t.sock"), os.path.join(fresh, "t.sock")):
        d = DaemonProcess(tessd_bin, sock, log_path=os.path.join(tmpdir_short, "d.log")).start()
        try:
            assert mode(sock) == 0o600, oct(mode(sock))
            assert connect_as(other_user, sock)["errno"] == 13
        finally:
            d.stop()
    assert mode(fresh) == 0o700 and mode(os.path.dirname(fresh)) == 0o700
    assert mode(shared) == 0o755  # an existing folder is the user's choice: left as it is


# ---------------------------------------------------------------------------------------------
# Things planted at the socket path or its folder


def test_symlink_at_the_socket_path_is_refused_not_followed(tessd_bin, tmpdir_short):
    # Another daemon's live socket, a file, and nothing at all as the link's target.
    victim_dir = os.path.join(tmpdir_short, "victim")
    os.mkdir(victim_dir)
    other = DaemonProcess(tessd_bin, os.path.join(victim_dir, "other.sock")).start()
    try:
        victim_file = os.path.join(victim_dir, "notes.txt")
        with open(victim_file, "w") as f:
            f.write("precious")
        link = os.path.join(tmpdir_short, "t.sock")
        for target in (other.socket, victim_file, os.path.join(victim_dir, "nothing")):
            os.symlink(target, link)
            text = serve_refused(tessd_bin, ["--socket", link])
            assert f"refusing to listen on {link}" in text and "symbolic link" in text, text
            assert target in text, text
            assert os.readlink(link) == target  # the link is left, not removed or replaced
            os.unlink(link)
        assert not os.path.lexists(link + ".lock"), "a refused start left its lock file"
        # A link at the start lock beside the socket is not followed either.
        lock_link = link + ".lock"
        os.symlink(victim_file, lock_link)
        text = serve_refused(tessd_bin, ["--socket", link])
        assert f"its lock file {lock_link} is a symbolic link" in text, text
        assert os.readlink(lock_link) == victim_file
        os.unlink(lock_link)
        with open(victim_file) as f:
            assert f.read() == "precious"
        assert not os.path.exists(os.path.join(victim_dir, "nothing"))
        with tessd.Client(other.socket, timeout=10) as c:
            assert c.hello()["pid"] == other.pid  # the other daemon was not taken over
        assert sorted(os.listdir(victim_dir)) == ["notes.txt", "other.sock", "other.sock.lock",
                                                  "other.sock.out"]
    finally:
        other.stop()


def test_symlink_at_the_socket_folder_is_refused_not_followed(tessd_bin, tmpdir_short,
                                                              other_user):
    elsewhere = os.path.join(tmpdir_short, "elsewhere")
    os.mkdir(elsewhere, 0o755)
    os.chown(elsewhere, other_user.pw_uid, other_user.pw_gid)
    # The default per-user folder, planted as a link to a folder someone else owns.
    default_folder = os.path.join(tmpdir_short, "tessd-%d" % os.getuid())
    os.symlink(elsewhere, default_folder)
    text = serve_refused(tessd_bin, [], env=default_env(tmpdir_short))
    assert default_folder in text and "symbolic link" in text and elsewhere in text, text
    # A --socket PATH whose folder is a link.
    link_folder = os.path.join(tmpdir_short, "linkdir")
    os.symlink(elsewhere, link_folder)
    text = serve_refused(tessd_bin, ["--socket", os.path.join(link_folder, "t.sock")])
    assert "its folder " + link_folder in text and "symbolic link" in text, text
    assert os.listdir(elsewhere) == [], "something was created through the link"
    assert os.readlink(default_folder) == elsewhere and os.readlink(link_folder) == elsewhere


def test_a_file_or_a_foreign_folder_at_the_socket_path_is_refused(tessd_bin, tmpdir_short,
                                                                  other_user):
    path = os.path.join(tmpdir_short, "t.sock")
    with open(path, "w") as f:
        f.write("not a socket")
    text = serve_refused(tessd_bin, ["--socket", path])
    assert path in text and "is not a socket" in text, text
    with open(path) as f:
        assert f.read() == "not a socket"
    foreign = os.path.join(tmpdir_short, "foreign")
    os.mkdir(foreign, 0o777)
    os.chmod(foreign, 0o777)
    os.chown(foreign, other_user.pw_uid, other_user.pw_gid)
    text = serve_refused(tessd_bin, ["--socket", os.path.join(foreign, "t.sock")])
    assert foreign in text and "belongs to another user" in text, text
    assert os.listdir(foreign) == []


# ---------------------------------------------------------------------------------------------
# A crash leaves the socket file: the next daemon takes over


@pytest.mark.parametrize("default_socket", [False, True], ids=["--socket", "default"])
def test_stale_socket_after_a_crash_is_taken_over(default_socket, tessd_bin, tmpdir_short):
    if default_socket:
        sock = os.path.join(tmpdir_short, "tessd-%d" % os.getuid(), "tessd.sock")
        make = lambda: DaemonProcess(tessd_bin, sock, socket_arg=False,  # noqa: E731
                                     env=default_env(tmpdir_short),
                                     log_path=os.path.join(tmpdir_short, "d.log"))
    else:
        sock = os.path.join(tmpdir_short, "t.sock")
        make = lambda: DaemonProcess(tessd_bin, sock)  # noqa: E731
    rounds = 5
    d = make().start()
    try:
        for _ in range(rounds):
            old = d.pid
            os.kill(old, signal.SIGKILL)
            d.proc.wait(10)
            assert stat.S_ISSOCK(os.lstat(sock).st_mode), "the kill should leave the socket file"
            with pytest.raises(tessd.DaemonUnavailable):
                tessd.Client(sock, timeout=2)
            d = make().start()
            with tessd.Client(sock, timeout=10) as c:
                assert c.hello()["pid"] == d.pid != old
            assert mode(sock) == 0o600
        assert d.log_text().count("removing stale socket") >= 1
    finally:
        d.stop()
    print(f"\n{'default' if default_socket else '--socket'}: {rounds} SIGKILLs, "
          f"{rounds} takeovers of the stale socket")
