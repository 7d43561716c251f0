"""Starting and stopping the daemon from a host tool.

:func:`ensure_daemon` returns the socket of a running daemon, starting ``tessd serve`` in the
background first when none answers; :func:`stop_daemon` asks one to shut down (with
``only_if_unheld``: unless another program holds it, see :meth:`tessd.Client.hold`).
:func:`find_binary` says which executable is started: the ``binary`` argument, ``$TESSD_BIN``,
the one the tessd wheel installed for this Python (its scripts folder, found even when the venv
is not activated), then ``tessd`` on ``PATH`` (docs/install.md).

Windows: the daemon is ``tessd.exe`` and listens on a named pipe (:mod:`tessd.socket_path`).
It is started without a console window (:func:`spawn_options`: a GUI host such as Blender or
FreeCAD has no console to share, and a console program started from it would open one), and
liveness is always a connection to the pipe (there is no socket file to look at). The same
code runs on every platform; only :func:`spawn_options`' flags and :func:`log_path`'s folder
differ.
"""

from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
import sysconfig
import threading
import time
from typing import IO, Dict, List, Optional, Sequence

from .client import Client, TessdError
from .frame import ProtocolError
from .socket_path import is_windows, resolve_socket
from .transport import DaemonUnavailable

#: Exit code of ``tessd serve`` when another daemon already serves the socket.
EXIT_ALREADY_SERVING = 3

#: Windows process creation flags (winbase.h; named here because the subprocess module defines
#: them on Windows only): no console window, and a process group of its own, so that a Ctrl-C
#: in a console the host was started from does not reach the daemon.
CREATE_NO_WINDOW = 0x08000000
CREATE_NEW_PROCESS_GROUP = 0x00000200

#: The daemons :func:`ensure_daemon` started in this process and that still run, by socket:
#: :func:`stop_daemon`'s last resort ends one by its handle (see there).
_spawned: Dict[str, subprocess.Popen] = {}
_spawned_lock = threading.Lock()


class DaemonStartError(DaemonUnavailable):
    """The daemon could not be started (binary missing, it exited, or it never answered)."""


def ping(socket: Optional[str] = None, timeout: float = 2.0) -> bool:
    """Whether a tessd daemon answers ``ping`` on ``socket`` within ``timeout`` seconds."""
    try:
        with Client(socket, timeout=timeout) as client:
            client.call("ping", {"echo": "tessd.ping"}, timeout=timeout)
        return True
    except (DaemonUnavailable, TimeoutError, ConnectionError):
        return False
    except (OSError, TessdError, ProtocolError):
        return False


def _exe_name() -> str:
    return "tessd.exe" if is_windows() else "tessd"


def spawn_options(windows: bool) -> dict:
    """The ``subprocess.Popen`` keyword arguments that start the daemon detached from the host:
    on Windows the creation flags :data:`CREATE_NO_WINDOW` and
    :data:`CREATE_NEW_PROCESS_GROUP` (a console program started from a GUI host would
    otherwise open a console window, and closing that window would end the daemon); elsewhere a
    session of its own (``start_new_session``: the host's terminal and its signals stay out).
    A pure function of ``windows``, so that either answer can be checked on any platform."""
    if windows:
        return {"creationflags": CREATE_NO_WINDOW | CREATE_NEW_PROCESS_GROUP}
    return {"start_new_session": True}


def _no_window() -> dict:
    """Popen's arguments for a short run of the binary (``--version``): no console window on
    Windows; nothing elsewhere."""
    return {"creationflags": CREATE_NO_WINDOW} if is_windows() else {}


def installed_binary_dirs() -> List[str]:
    """The folders where ``pip install ./python`` (the tessd wheel, python/pyproject.toml) puts the
    ``tessd`` binary for this interpreter, in lookup order, without duplicates: the scripts
    folder of its install scheme (``sysconfig.get_path("scripts")``: a venv's ``bin/`` or
    ``Scripts\\``), the folder of ``sys.executable`` (the same for a venv; where a system or
    conda Python keeps its commands), and the user scheme's scripts folder (``pip install
    --user``, e.g. ``~/.local/bin``). They are looked in whether or not a venv is activated:
    its ``bin/`` need not be on ``PATH``."""
    dirs: List[str] = []

    def add(path: Optional[str]) -> None:
        if path:
            path = os.path.abspath(path)
            if path not in dirs:
                dirs.append(path)

    try:
        add(sysconfig.get_path("scripts"))
    except (KeyError, ValueError, OSError):  # pragma: no cover - an odd embedded Python
        pass
    if sys.executable:
        add(os.path.dirname(sys.executable))
    # `pip install --user`: only where this Python reads the user site (never in a venv that
    # does not see it), as the client package itself would then be importable from there.
    if getattr(site, "ENABLE_USER_SITE", False):
        try:
            preferred = getattr(sysconfig, "get_preferred_scheme", None)  # Python >= 3.10
            if preferred:
                scheme = preferred("user")
            else:
                scheme = "nt_user" if os.name == "nt" else "posix_user"
            add(sysconfig.get_path("scripts", scheme))
        except (KeyError, ValueError, OSError):  # pragma: no cover
            pass
    return dirs


def _is_executable(path: str) -> bool:
    return os.path.isfile(path) and os.access(path, os.X_OK)


def find_binary(binary: Optional[str] = None) -> str:
    """The tessd executable to start, the first of:

    1. ``binary`` (a path, or a command name looked up on ``PATH``);
    2. ``$TESSD_BIN`` (likewise);
    3. the binary that installing the tessd wheel (``pip install ./python`` in the tessd
       repository, or a wheel built by ``pip wheel ./python``) put there for this Python:
       ``tessd`` (``tessd.exe``) in one of :func:`installed_binary_dirs`, i.e. the scripts
       folder of the interpreter's install scheme (``sysconfig.get_path("scripts")``), the
       folder of ``sys.executable``, then the user scheme's scripts folder. So a venv's daemon
       is found from that venv's Python even when the venv is not activated (its ``bin/`` not
       on ``PATH``);
    4. ``tessd`` on ``PATH``.

    A ``binary`` or ``$TESSD_BIN`` that names no executable is an error (no fallback), as is
    finding none at all: :class:`DaemonStartError` either way.
    """
    for candidate, origin in ((binary, "the binary argument"),
                              (os.environ.get("TESSD_BIN"), "TESSD_BIN")):
        if candidate:
            path = os.fspath(candidate)
            if _is_executable(path):
                return path
            found = shutil.which(path)
            if found:
                return found
            raise DaemonStartError("%s names %s, which is not an executable file" % (origin, path))
    dirs = installed_binary_dirs()
    for directory in dirs:
        path = os.path.join(directory, _exe_name())
        if _is_executable(path):
            return path
    found = shutil.which("tessd")
    if found:
        return found
    raise DaemonStartError("cannot find the tessd executable: pass binary=..., set TESSD_BIN, "
                           "install the tessd wheel into this Python (`pip install ./python` in "
                           "the tessd repository; looked in %s), or put tessd on PATH"
                           % (", ".join(dirs) or "no scripts folder"))


def binary_version(binary: Optional[str] = None, timeout: float = 10.0) -> str:
    """The version a tessd executable reports (``tessd --version`` prints ``tessd X.Y.Z``),
    e.g. to tell whether a running daemon (``hello``'s ``version``) is the one a host
    bundles. Raises :class:`DaemonStartError` when it cannot be run or says something else."""
    exe = find_binary(binary)
    try:
        out = subprocess.run([exe, "--version"], stdin=subprocess.DEVNULL,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             timeout=timeout, check=False,
                             **_no_window()).stdout.decode("utf-8", "replace")
    except (OSError, subprocess.SubprocessError) as e:
        raise DaemonStartError("cannot run %s --version: %s" % (exe, e)) from e
    words = out.split()
    if len(words) < 2 or words[0] != "tessd":
        raise DaemonStartError("%s --version printed %r, not `tessd <version>`" % (exe, out.strip()))
    return words[1]


def log_path(socket_path: str, windows: bool, temp_dir: Optional[str] = None) -> str:
    """Where a daemon that :func:`ensure_daemon` starts on ``socket_path`` writes its output.

    Linux and macOS: beside the socket, ``<name>.log`` for ``<name>.sock``. Windows: a pipe has
    no folder, so ``<temp_dir>\\<pipe name>.log`` (``%TEMP%\\tessd-alice.log`` for the pipe
    ``\\\\.\\pipe\\tessd-alice``), ``temp_dir`` being ``%TEMP%`` when not given. A pure
    function of its arguments."""
    if windows:
        directory = temp_dir or os.environ.get("TEMP") or os.environ.get("TMP") or "."
        name = socket_path.replace("/", "\\").rstrip("\\").rsplit("\\", 1)[-1] or "tessd"
        return directory.rstrip("\\/") + "\\" + name + ".log"
    directory = os.path.dirname(socket_path) or "."
    base = os.path.basename(socket_path)
    if base.endswith(".sock"):
        base = base[: -len(".sock")]
    return os.path.join(directory, base + ".log")


def _log_path(socket_path: str) -> Optional[str]:
    return log_path(socket_path, is_windows())


def _tail(path: Optional[str], lines: int = 20) -> str:
    if not path:
        return ""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            size = f.tell()
            f.seek(max(0, size - 16384))
            text = f.read().decode("utf-8", "replace")
    except OSError:
        return ""
    tail = text.splitlines()[-lines:]
    return "\n".join(tail)


def _open_log(path: Optional[str]) -> "IO[bytes] | int":
    if path:
        try:
            return open(path, "ab")
        except OSError:
            pass
    return subprocess.DEVNULL


def _spawn(binary: str, socket_path: str, args: Sequence[str], log: "IO[bytes] | int") -> subprocess.Popen:
    cmd = [binary, "serve", "--socket", socket_path] + [str(a) for a in args]
    return subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                            close_fds=True, **spawn_options(is_windows()))


def ensure_daemon(socket: Optional[str] = None, binary: Optional[str] = None, timeout: float = 10.0,
                  args: Sequence[str] = ()) -> str:
    """Makes sure a daemon serves ``socket`` and returns the socket path.

    If a daemon answers ``ping`` there, it is used. Otherwise the binary (see
    :func:`find_binary`) is started as ``tessd serve --socket PATH *args``, detached in its
    own session with output appended to ``<socket dir>/<name>.log``, and polled with backoff
    until it answers. Raises :class:`DaemonStartError` (with the end of the log) if it exits
    or does not answer within ``timeout`` seconds.
    """
    path = resolve_socket(socket, create_dir=True)
    if ping(path, timeout=min(2.0, timeout)):
        return path
    exe = find_binary(binary)
    log_path = _log_path(path)
    log = _open_log(log_path)
    if log is subprocess.DEVNULL:
        log_path = None
    try:
        proc = _spawn(exe, path, args, log)
    except OSError as e:
        raise DaemonStartError("cannot start %s: %s" % (exe, e)) from e
    finally:
        if log is not subprocess.DEVNULL:
            log.close()
    deadline = time.monotonic() + timeout
    delay = 0.005
    while True:
        code = proc.poll()
        if code is not None:
            if code == EXIT_ALREADY_SERVING and ping(path, timeout=2.0):
                return path  # another caller started one first
            raise DaemonStartError(_start_failure(
                "tessd serve --socket %s exited with status %d" % (path, code), log_path))
        if ping(path, timeout=max(0.1, min(2.0, deadline - time.monotonic()))):
            _reap_later(path, proc)
            return path
        if time.monotonic() >= deadline:
            proc.kill()
            proc.wait()
            raise DaemonStartError(_start_failure(
                "tessd serve --socket %s did not answer within %gs" % (path, timeout), log_path))
        time.sleep(delay)
        delay = min(delay * 2, 0.2)


def _reap_later(path: str, proc: subprocess.Popen) -> None:
    """Keeps the started daemon's handle in :data:`_spawned` and waits for it in a background
    thread, so that it leaves no zombie process when it exits while this host process runs on
    (and leaves :data:`_spawned` then)."""
    with _spawned_lock:
        _spawned[path] = proc

    def reap() -> None:
        proc.wait()
        with _spawned_lock:
            if _spawned.get(path) is proc:
                del _spawned[path]

    threading.Thread(target=reap, name="tessd-daemon-reaper", daemon=True).start()


def _end_started(path: str, grace: float = 5.0) -> bool:
    """Ends the daemon this process started on ``path`` (when it did and it still runs):
    ``terminate()`` (SIGTERM, which the daemon answers like ``shutdown``; on Windows
    TerminateProcess), then after ``grace`` seconds ``kill()``. Returns whether such a process
    was there and has exited."""
    with _spawned_lock:
        proc = _spawned.get(path)
    if proc is None:
        return False
    for end in (proc.terminate, proc.kill):
        try:
            end()
        except OSError:  # exited meanwhile
            pass
        deadline = time.monotonic() + grace
        while proc.returncode is None and time.monotonic() < deadline:
            time.sleep(0.02)  # the reaper thread's wait() sets returncode
        if proc.returncode is not None:
            return True
    return False


def _start_failure(what: str, log_path: Optional[str]) -> str:
    tail = _tail(log_path)
    if tail:
        return "%s; the end of %s:\n%s" % (what, log_path, tail)
    return what


def stop_daemon(socket: Optional[str] = None, timeout: float = 10.0, *,
                only_if_unheld: bool = False) -> bool:
    """Asks the daemon on ``socket`` to shut down and waits until it stops answering.

    With ``only_if_unheld``, the daemon stops only when no live process holds it
    (``session.hold``; the daemon decides, so a hold arriving meanwhile is never overrun).
    Returns True when the daemon stopped, False if no daemon was running there or (with
    ``only_if_unheld``) it is still held and keeps running.

    When :func:`ensure_daemon` started the daemon in this process, its process handle is the
    last resort: one that accepted the shutdown but still answers after ``timeout`` seconds, or
    (without ``only_if_unheld``: then nobody else's hold can be overrun) one that did not
    answer the shutdown within ``timeout``, is ended (``terminate()``: TerminateProcess on
    Windows, SIGTERM then SIGKILL elsewhere) and True returned once it has exited. Otherwise
    such a daemon raises ``TimeoutError``.
    """
    path = resolve_socket(socket)
    params = {"if_unheld": True} if only_if_unheld else None
    try:
        with Client(path, timeout=timeout) as client:
            result, _ = client.call("shutdown", params, timeout=timeout)
    except DaemonUnavailable:
        return False
    except TimeoutError:
        if not only_if_unheld and _end_started(path, grace=min(5.0, timeout)):
            return True
        raise
    if result.get("ok") is False:
        return False
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            probe = Client(path, timeout=1.0)
        except (DaemonUnavailable, OSError):
            return True
        probe.close()
        time.sleep(0.02)
    if _end_started(path, grace=min(5.0, timeout)):
        return True
    raise TimeoutError("the daemon on %s still accepts connections %gs after shutdown"
                       % (path, timeout))


__all__ = ["DaemonStartError", "binary_version", "ensure_daemon", "find_binary",
           "installed_binary_dirs", "log_path", "ping", "spawn_options", "stop_daemon"]


if __name__ == "__main__":  # pragma: no cover - manual use: python -m tessd.daemon [socket]
    print(ensure_daemon(sys.argv[1] if len(sys.argv) > 1 else None))
