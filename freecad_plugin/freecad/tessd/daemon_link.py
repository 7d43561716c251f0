"""Reaching the daemon from FreeCAD: the preferences, the connection, holding and releasing.

One daemon per user serves FreeCAD, Blender and scripts alike (docs/protocol.md, "Sharing one
daemon"). :func:`client` returns a connected :class:`tessd.Client`, starting ``tessd serve`` on
demand (:func:`tessd.ensure_daemon`), and the first time a FreeCAD process reaches a socket it
holds that daemon (``session.hold`` with host ``"freecad"``), so that another host that started
it does not stop it under FreeCAD's feet. At exit (atexit) the holds are released, and a daemon
this process started is asked to stop unless another program still holds it (``shutdown`` with
``if_unheld``; the daemon decides, so a hold arriving meanwhile is never overrun).

Preferences live in FreeCAD's parameter tree, ``User parameter:BaseApp/Preferences/Mod/tessd``
(the workbench's preference page edits them; a macro may set them with ``FreeCAD.ParamGet``):

- ``BinaryPath`` (string): the tessd executable to start; empty: ``$TESSD_BIN``, else the one
  the tessd wheel installed for this Python, else ``tessd`` on ``PATH``
  (:func:`tessd.daemon.find_binary`);
- ``Socket`` (string): the socket path or bare name, as ``tessd serve --socket``; empty: the
  client's default (``$XDG_RUNTIME_DIR/tessd.sock`` or ``/tmp/tessd-<uid>/tessd.sock``; on
  Windows the named pipe ``\\\\.\\pipe\\tessd-<user>``, a bare name ``N`` being
  ``\\\\.\\pipe\\tessd-<user>-N`` and a file path refused);
- ``StopOnExit`` (bool, default true): stop a daemon this process started when FreeCAD exits
  (never one somebody else started, never one another program holds);
- ``StartTimeout`` (float, seconds, default 15): how long a started daemon may take to answer.

:func:`client` may be called from any thread (the GUI runs tasks off its own thread).

On Windows the same code runs: the client package starts ``tessd.exe`` without a console window
and ends a daemon that lingers after ``shutdown`` by its process handle; liveness is a
connection to the pipe.
"""

import atexit
import os
import threading
from typing import NamedTuple

import FreeCAD
import tessd  # the client package (this package's __init__ made it importable)

#: FreeCAD's parameter group of the workbench's preferences.
PARAM_PATH = "User parameter:BaseApp/Preferences/Mod/tessd"

#: The name FreeCAD holds daemons under (``session.hold``'s ``host``).
HOST = "freecad"

#: Operations the workbench sends; a daemon lacking one is too old for it.
REQUIRED_OPS = frozenset({"tessellate", "simplify", "lod", "render", "session.hold",
                          "session.release"})

#: Where a FreeCAD user changes the binary and the socket.
PREFERENCES_PLACE = "Edit \u25b8 Preferences \u25b8 tessd"

_lock = threading.Lock()
#: Sockets held by this process (``session.hold`` sent once per socket).
_held = set()
#: Sockets of the daemons this process started, with whether to stop each at exit (the
#: preference when last connected: FreeCAD's parameters are gone by the time atexit runs).
_started = {}


class Settings(NamedTuple):
    """The workbench's preferences, read from FreeCAD's parameter tree."""

    binary_path: str
    socket: str
    stop_on_exit: bool
    start_timeout: float


def settings() -> Settings:
    """The current preferences (read at every connection, so a change applies at once)."""
    p = FreeCAD.ParamGet(PARAM_PATH)
    return Settings(binary_path=p.GetString("BinaryPath", "").strip(),
                    socket=p.GetString("Socket", "").strip(),
                    stop_on_exit=p.GetBool("StopOnExit", True),
                    start_timeout=p.GetFloat("StartTimeout", 15.0) or 15.0)


def socket_path(prefs: Settings = None) -> str:
    """The socket the preferences name (the client's default when empty)."""
    prefs = prefs or settings()
    try:
        return tessd.resolve_socket(prefs.socket or None, create_dir=True)
    except ValueError as e:  # tessd.socket_path.SocketNameError (a file path on Windows)
        raise tessd.DaemonStartError("tessd cannot use the Socket set in %s: %s"
                                     % (PREFERENCES_PLACE, e)) from e


def describe_binary(prefs: Settings = None) -> str:
    """The binary that would be started, or why there is none (for the preference page)."""
    prefs = prefs or settings()
    try:
        return tessd.daemon.find_binary(prefs.binary_path or None)
    except tessd.DaemonStartError as e:
        return "not found: %s" % e


def _start(prefs: Settings, path: str) -> None:
    """Starts the configured binary on ``path``; the error names the preference to change."""
    binary = prefs.binary_path or None
    if binary and not (os.path.isfile(binary) and (os.name == "nt" or os.access(binary, os.X_OK))):
        raise tessd.DaemonStartError(
            "tessd could not start: BinaryPath (%s) is %s, which is not an executable file; "
            "choose the tessd program there or clear it to use $TESSD_BIN or PATH"
            % (PREFERENCES_PLACE, binary))
    try:
        tessd.ensure_daemon(path, binary=binary, timeout=prefs.start_timeout)
    except tessd.DaemonStartError as e:
        raise tessd.DaemonStartError(
            "tessd could not start: %s (set the tessd program in %s, or TESSD_BIN)"
            % (e, PREFERENCES_PLACE)) from e
    _started[path] = prefs.stop_on_exit


def _first_contact(c: "tessd.Client", path: str) -> None:
    """Once per socket and process: checks the daemon has the workbench's operations, holds it."""
    hello = c.hello()
    missing = sorted(REQUIRED_OPS - set(hello.get("ops") or ()))
    if missing:
        raise tessd.TessdError(
            "unsupported", "the tessd daemon on %s (version %s) lacks %s, which the workbench "
            "needs: stop it (tessd.stop_daemon(socket) from Python, or end its process) so that "
            "the workbench starts its own"
            % (path, hello.get("version", "?"), ", ".join(missing)))
    c.hold(host=HOST)
    _held.add(path)


def client() -> "tessd.Client":
    """A connected :class:`tessd.Client` (close it, or use it in a ``with`` block).

    Starts the daemon when none answers on the configured socket, and holds it on the first
    connection of this process. Raises :class:`tessd.DaemonStartError` (its message says which
    preference to change) when no daemon can be started, :class:`tessd.TessdError` for a daemon
    too old for the workbench.
    """
    prefs = settings()
    path = socket_path(prefs)
    with _lock:
        try:
            c = tessd.Client(path, timeout=10.0)
        except (tessd.DaemonUnavailable, OSError):
            _start(prefs, path)
            c = tessd.Client(path, timeout=10.0)
        if path in _started:
            _started[path] = prefs.stop_on_exit
        try:
            if path not in _held:
                _first_contact(c, path)
        except BaseException:
            c.close()
            raise
    c.timeout = None  # requests are waited on by the tasks, which poll their cancel flag
    return c


def release_all() -> None:
    """FreeCAD's exit path: releases this process's holds and stops the daemons it started
    (when ``StopOnExit`` is on and no other program holds them). Errors are ignored: the daemon
    forgets holders whose process has exited anyway."""
    with _lock:
        for path in sorted(_held | set(_started)):
            try:
                with tessd.Client(path, timeout=5.0) as c:
                    c.release()
            except Exception:  # gone already
                pass
            if _started.get(path):
                try:
                    tessd.stop_daemon(path, timeout=5.0, only_if_unheld=True)
                except Exception:
                    pass
        _held.clear()
        _started.clear()


atexit.register(release_all)

__all__ = ["HOST", "PARAM_PATH", "Settings", "client", "describe_binary", "release_all",
           "settings", "socket_path"]
