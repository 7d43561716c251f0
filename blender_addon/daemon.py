"""Reaching the daemon: find its binary, connect, start it when allowed, share it, stop it.

**Which binary.** :mod:`binary` finds it (the preference, the bundled one, $TESSD_BIN, PATH),
below this module and the preferences panel that shows it; :class:`DaemonError` and
:data:`PREFERENCES_PLACE` live in :mod:`daemon_error`. ``daemon.DaemonError``,
``daemon.BUNDLED_BINARY``, ``daemon.find_binary`` and ``daemon.this_platform`` still work.

**Windows.** The daemon is ``bin\\tessd.exe`` and listens on the named pipe
``\\\\.\\pipe\\tessd-<user>`` (a bare socket name ``N`` in the preferences is
``\\\\.\\pipe\\tessd-<user>-N``; a file path there is refused). The client package starts it
without a console window and stops it with ``shutdown`` (then by its process handle if it
lingers): the code below is the same on every platform.

**Sharing.** One daemon per user serves Blender, FreeCAD and scripts alike. On the first
connection to a socket in a Blender session the add-on calls ``hello`` and then holds the
daemon (``session.hold`` with Blender's pid, docs/protocol.md). On exit, or when the add-on is
disabled, it releases it and shuts it down only if the add-on started it, the preference "Stop
it on exit" is on and no other holder is left (the daemon decides that last part itself:
``shutdown`` with ``if_unheld``). A daemon someone else started is never stopped.

**Version check.** ``hello``'s ``version`` is compared with ``tessd --version`` of the binary
the add-on would start (the bundled one, normally): that is the daemon the add-on was built
with, and comparing against the binary rather than the manifest means a developer's own build
never gets replaced in a loop. A daemon of another version, or one lacking an operation the
add-on sends, is replaced by the add-on's binary when nobody else holds it and auto-start is
on; when another program holds it, it is left running and a warning says so once
(:func:`take_warnings`). Tests and tools may set :data:`EXPECTED_VERSION` to compare against
another version without building another binary.

**Messages.** A :class:`DaemonError`'s text is written for the artist who clicked a menu entry
(no Python API words); when the fix is in the add-on's preferences its
``offer_preferences`` is true, and :func:`offer_preferences` shows the message with a button
that opens them.
"""

import atexit
import os
import textwrap

import bpy

from . import preferences
from .binary import BUNDLED_BINARY, find_binary, this_platform  # noqa: F401 (re-exported)
from .client import tessd
from .daemon_error import PREFERENCES_PLACE, DaemonError

#: Operations the add-on sends; a daemon without one of them is treated like an old version.
REQUIRED_OPS = frozenset({"simplify", "lod", "subdivide", "mesh.convert", "codec.view", "session.hold",
                          "session.release"})

#: The daemon version the add-on expects. None: what its binary reports (``tessd --version``).
#: Set it (tests, tools) to compare against another version.
EXPECTED_VERSION = None

#: The name the add-on holds daemons under (``session.hold``'s ``host``).
HOST = "blender"

#: Sockets of the daemons this add-on started, with whether to stop each on exit (the
#: preference, refreshed at every connection so a change applies without a restart).
_started = {}
#: Sockets already checked and held in this session (``hello`` and ``session.hold`` once).
_held = set()
#: Warnings not yet shown to the user (see take_warnings).
_warnings = []
#: Every warning given in this session, shown or not (for scripts and tests to inspect).
warned = []
#: ``tessd --version`` by binary path and modification time.
_versions = {}


def socket_path(prefs):
    """The socket the preferences name (the client's default when the field is empty). On
    Windows a named pipe; a file path there is refused with a DaemonError that offers the
    preferences (``tessd.resolve_socket``'s rules)."""
    try:
        return tessd.resolve_socket(prefs.socket or None, create_dir=True)
    except ValueError as e:  # tessd.socket_path.SocketNameError
        raise DaemonError("tessd cannot use the socket set in %s: %s"
                          % (PREFERENCES_PLACE, e), offer_preferences=True) from e


def expected_version(prefs):
    """The daemon version the add-on expects: :data:`EXPECTED_VERSION`, else what the binary
    it would start reports; None when there is no binary to ask (then nothing can replace the
    running daemon anyway)."""
    if EXPECTED_VERSION is not None:
        return EXPECTED_VERSION
    try:
        binary = find_binary(prefs)
        key = (binary, os.stat(binary).st_mtime_ns)
    except (DaemonError, OSError):
        return None
    if key not in _versions:
        try:
            _versions[key] = tessd.daemon.binary_version(binary)
        except tessd.DaemonStartError:
            return None
    return _versions[key]


def _warn(message):
    """Keeps a warning for the next take_warnings() and prints it to Blender's console."""
    _warnings.append(message)
    warned.append(message)
    print("tessd: warning: %s" % message)


def take_warnings():
    """Warnings about the daemon not yet shown (each is returned once): an operator reports
    them with ``self.report({'WARNING'}, w)``."""
    out = list(_warnings)
    _warnings.clear()
    return out


def _start(prefs, path):
    """Starts the add-on's binary on ``path`` and records that the add-on started it."""
    binary = find_binary(prefs)
    try:
        tessd.ensure_daemon(path, binary=binary, timeout=prefs.timeout)
    except tessd.DaemonUnavailable as e:
        raise DaemonError("tessd could not start (%s): %s" % (binary, e)) from e
    _started[path] = bool(prefs.stop_on_exit)
    _held.discard(path)  # a new daemon: check and hold it again
    try:
        return tessd.Client(path, timeout=5.0)
    except (tessd.DaemonUnavailable, OSError) as e:
        raise DaemonError("the tessd daemon started on %s but does not answer: %s"
                          % (path, e)) from e


def _other_holders(hello):
    """Holders of the daemon other than this Blender process (0 for a daemon too old to
    count them: nobody can have held it)."""
    me = os.getpid()
    held_by = hello.get("held_by")
    if isinstance(held_by, list):
        return sum(1 for h in held_by if isinstance(h, dict) and h.get("pid") != me)
    return int(hello.get("holders") or 0)


def _first_contact(client, prefs, path):
    """The once-per-socket check: version and operations, replacement when allowed, hold."""
    hello = client.hello()
    expected = expected_version(prefs)
    running = str(hello.get("version", "?"))
    missing = sorted(REQUIRED_OPS - set(hello.get("ops") or ()))
    problem = None
    if expected is not None and running != expected:
        problem = "the running tessd daemon is version %s; this add-on expects %s" % (running,
                                                                                      expected)
    elif missing and expected is not None:
        problem = ("the running tessd daemon (version %s) lacks %s, which this add-on needs"
                   % (running, ", ".join(missing)))
    if problem is not None:
        if _other_holders(hello) == 0 and prefs.auto_start:
            client.close()
            if tessd.stop_daemon(path, timeout=prefs.timeout, only_if_unheld=True):
                print("tessd: %s; replaced it" % problem)
                client = _start(prefs, path)
                hello = client.hello()
            else:  # someone held it in the meantime
                client = tessd.Client(path, timeout=5.0)
                _warn("%s; it is shared with another program, so it was left running" % problem)
        elif _other_holders(hello) > 0:
            _warn("%s; it is shared with another program, so it was left running" % problem)
        else:
            _warn("%s; turn on \"Start the daemon automatically\" in %s to let the add-on "
                  "replace it" % (problem, PREFERENCES_PLACE))
    if "session.hold" in (hello.get("ops") or ()):
        client.hold(HOST)
    _held.add(path)
    return client


def connect(context=None):
    """A tessd.Client on the configured socket; starts the daemon first when none answers
    and the preferences allow it. On the first connection to a socket in this session the
    daemon is checked and held (see the module's notes); warnings that check gave (each once
    per session) are on the client as ``tessd_warnings``, a list of strings for the
    operator's report. Raises DaemonError with a message for the user."""
    prefs = preferences.get(context)
    path = socket_path(prefs)
    try:
        client = tessd.Client(path, timeout=5.0)
    except (tessd.DaemonUnavailable, OSError) as e:
        if not prefs.auto_start:
            raise DaemonError("no tessd daemon answers on %s (%s); start `tessd serve` or turn "
                              "on \"Start the daemon automatically\" in %s"
                              % (path, e, PREFERENCES_PLACE), offer_preferences=True) from e
        client = _start(prefs, path)
    if path in _started:
        _started[path] = bool(prefs.stop_on_exit)
    if path not in _held:
        try:
            client = _first_contact(client, prefs, path)
        except tessd.TessdError as e:
            client.close()
            raise DaemonError("the program answering on %s does not behave like the tessd "
                              "daemon (%s)" % (path, e)) from e
        except BaseException:
            client.close()
            raise
    client.tessd_warnings = take_warnings()
    return client


def stop_started():
    """Blender's exit (and the add-on's disable) path: releases every daemon this session
    held, and shuts down those the add-on started when "Stop it on exit" is on and no other
    program holds them."""
    me = os.getpid()
    for path in sorted(_held | set(_started)):
        try:
            with tessd.Client(path, timeout=5.0) as client:
                client.release(me)
        except Exception:  # gone already, or too old to know holders: nothing to release
            pass
        if _started.get(path):
            try:
                tessd.stop_daemon(path, timeout=5.0, only_if_unheld=True)
            except Exception:  # exiting: nothing useful to do with the error
                pass
    _held.clear()
    _started.clear()


def offer_preferences(context, message):
    """Shows ``message`` in a popup with a button that opens the add-on's preferences (for a
    :class:`DaemonError` whose ``offer_preferences`` is true). Returns whether it was shown:
    without a window (scripts, background mode) nothing is shown and the caller's report is
    all the user gets."""
    context = context or bpy.context
    if bpy.app.background or getattr(context, "window", None) is None:
        return False
    lines = textwrap.wrap(message, 72) or [message]

    def draw(menu, _context):
        layout = menu.layout
        for line in lines:
            layout.label(text=line)
        layout.separator()
        layout.operator(preferences.OpenPreferences.bl_idname, icon='PREFERENCES')

    context.window_manager.popup_menu(draw, title="tessd", icon='ERROR')
    return True


def register():
    atexit.register(stop_started)


def unregister():
    atexit.unregister(stop_started)
    stop_started()
