"""The host-side rules that differ on Windows, checked here on Linux as pure functions, and the
platform-independent way hosts stop a daemon they started (issue 37, point 5).

- The team's Windows endpoint naming (tessd.socket_path.windows_pipe / pipe_user): the same
  table as the daemon's Rust resolver (core/ipc/src/socket.rs, its pipe_name_tests, whose cases
  are all here too); every other path-like value is refused with an error that names it.
- How the daemon is started (tessd.daemon.spawn_options: no console window on Windows) and where
  its log goes (tessd.daemon.log_path).
- stop_daemon's last resort, the process handle of a daemon this process started: run for real
  against a real daemon frozen with SIGSTOP (it still accepts connections into the listen
  backlog, but answers nothing); on Windows the same lines call TerminateProcess.
"""

from __future__ import annotations

import os
import signal
import time

import pytest

import tessd
from tessd import daemon as tdaemon
from tessd.daemon import ensure_daemon, log_path, spawn_options, stop_daemon
from tessd.socket_path import PIPE_PREFIX, SocketNameError, pipe_user, windows_pipe

P = PIPE_PREFIX  # \\.\pipe\

# (socket value, %USERNAME%, pipe)
PIPES = [
    (None, "alice", P + "tessd-alice"),
    ("", "alice", P + "tessd-alice"),
    ("work", "alice", P + "tessd-alice-work"),
    ("my daemon", "alice", P + "tessd-alice-my daemon"),
    ("v1.2_x-y", "alice", P + "tessd-alice-v1.2_x-y"),
    (P + "custom", "alice", P + "custom"),
    (P + "tessd-bob", "alice", P + "tessd-bob"),
    (P + "a\\b", "alice", P + "a\\b"),
    ("\\\\.\\PIPE\\Up", "alice", "\\\\.\\PIPE\\Up"),  # the prefix in any case
    (None, "J\u00f6rg M\u00fcller", P + "tessd-J_rg_M_ller"),
    (None, "a.b_c-D9", P + "tessd-a.b_c-D9"),
    ("n", "dom$ user@x", P + "tessd-dom__user_x-n"),
    (None, "Jos\u00e9 Ruiz", P + "tessd-Jos__Ruiz"),
    (None, "DOM\\ann", P + "tessd-DOM_ann"),
    (None, None, P + "tessd-user"),
    (None, "", P + "tessd-user"),
]

# Values that name files, not pipes: refused on Windows.
REFUSED = [
    "C:\\Users\\alice\\tessd.sock",
    "C:tessd",
    "c:/tmp/tessd.sock",
    "\\\\server\\share\\tessd",
    "\\\\server\\pipe\\tessd",  # a remote pipe: not the local \\.\pipe\ namespace
    "dir\\tessd",
    "dir/tessd",
    "/tmp/tessd.sock",
    "//./pipe/tessd",
    P,  # the prefix alone names no pipe
    "\\\\?\\pipe\\tessd",
]


@pytest.mark.parametrize("value,user,pipe", PIPES)
def test_windows_pipe_names(value, user, pipe):
    assert windows_pipe(value, user) == pipe


@pytest.mark.parametrize("value", REFUSED)
def test_windows_refuses_file_paths_naming_the_value(value):
    with pytest.raises(SocketNameError) as info:
        windows_pipe(value, "alice")
    text = str(info.value)
    assert "'%s'" % value in text, text
    assert P + "tessd-alice-N" in text and P + "tessd-alice)" in text, text
    assert isinstance(info.value, ValueError) and isinstance(info.value, tessd.Error)


def test_pipe_user_replaces_each_character_outside_the_set():
    assert pipe_user("Ab9._-") == "Ab9._-"
    assert pipe_user("a b\\c/d:e") == "a_b_c_d_e"
    assert pipe_user("\u00e9\u00e9") == "__"  # one per character, not per UTF-8 byte
    assert pipe_user(None) == pipe_user("") == "user"


def test_linux_resolution_is_unchanged(monkeypatch, tmp_path):
    """On this platform the Unix rules still apply (a Windows-style value is a bare name)."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    assert tessd.resolve_socket("work") == str(tmp_path / "work.sock")
    assert tessd.resolve_socket("/abs/x.sock") == "/abs/x.sock"
    assert tessd.resolve_socket(None) == str(tmp_path / "tessd.sock")


def test_spawn_options_per_platform():
    win = spawn_options(True)
    assert win == {"creationflags": 0x08000000 | 0x00000200}  # CREATE_NO_WINDOW | NEW_PROCESS_GROUP
    assert "start_new_session" not in win
    assert spawn_options(False) == {"start_new_session": True}


def test_log_path_per_platform():
    temp = "C:\\Users\\alice\\AppData\\Local\\Temp"
    assert log_path(P + "tessd-alice", True, temp) == temp + "\\tessd-alice.log"
    assert log_path(P + "tessd-alice-work", True, temp + "\\") == temp + "\\tessd-alice-work.log"
    assert log_path("/run/user/7/tessd.sock", False) == "/run/user/7/tessd.log"
    assert log_path("/tmp/x/other", False) == "/tmp/x/other.log"


def _pid(path):
    with tessd.Client(path, timeout=10) as c:
        return c.hello()["pid"]


def _gone(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    # A zombie until the reaper thread's wait(): count it as gone once its state says so.
    with open("/proc/%d/stat" % pid) as f:
        return f.read().split(") ", 1)[1].startswith("Z")


def test_stop_ends_a_started_daemon_that_does_not_answer(tessd_bin, tmpdir_short):
    """The host's exit path when the daemon it started hangs: shutdown times out, then the
    process handle ends it (terminate, then kill: a stopped process keeps SIGTERM pending)."""
    path = os.path.join(tmpdir_short, "h.sock")
    assert ensure_daemon(path, binary=tessd_bin, timeout=20) == path
    pid = _pid(path)
    os.kill(pid, signal.SIGSTOP)
    try:
        # Holders can't be asked: with only_if_unheld nothing is ended, the timeout is raised.
        t = time.monotonic()
        with pytest.raises(TimeoutError):
            stop_daemon(path, timeout=1.0, only_if_unheld=True)
        assert time.monotonic() - t < 5
        assert not _gone(pid), "a daemon was ended although others may hold it"
        t = time.monotonic()
        assert stop_daemon(path, timeout=1.0) is True
        took = time.monotonic() - t
        assert took < 6, took
        deadline = time.monotonic() + 5
        while not _gone(pid) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert _gone(pid), "the daemon still runs after stop_daemon returned True"
        assert path not in tdaemon._spawned
    finally:
        try:
            os.kill(pid, signal.SIGCONT)
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    # The socket is free again: a new daemon starts there and stops by shutdown alone.
    assert ensure_daemon(path, binary=tessd_bin, timeout=20) == path
    assert _pid(path) != pid
    assert stop_daemon(path, timeout=10) is True
    assert stop_daemon(path) is False


def test_stop_leaves_a_daemon_it_did_not_start(tessd_bin, tmpdir_short):
    """Only a daemon started by this process is ever ended by its handle: another one that
    hangs gives TimeoutError, and keeps running."""
    import subprocess

    path = os.path.join(tmpdir_short, "o.sock")
    proc = subprocess.Popen([tessd_bin, "serve", "--socket", path], stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 20
        while not tdaemon.ping(path, timeout=1.0):
            assert time.monotonic() < deadline and proc.poll() is None, "tessd serve did not start"
            time.sleep(0.05)
        os.kill(proc.pid, signal.SIGSTOP)
        with pytest.raises(TimeoutError):
            stop_daemon(path, timeout=1.0)
        assert proc.poll() is None
        os.kill(proc.pid, signal.SIGCONT)
        # The timed-out shutdown may still be read once the daemon runs again (it then exits
        # by itself, and this call finds nobody): either way it ends cleanly, by shutdown.
        assert stop_daemon(path, timeout=10) in (True, False)
        assert proc.wait(timeout=10) == 0
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGCONT)
            proc.kill()
            proc.wait()
