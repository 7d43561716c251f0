"""Reaching the daemon: find its binary, connect, start it when allowed, stop it on exit.

The binary is looked up in this order: the preference's path, a `tessd` file next to the
add-on (or in its `bin/` folder), $TESSD_BIN, `tessd` on PATH. A daemon this add-on started
is shut down when Blender exits or the add-on is disabled, if the preference says so; a
daemon someone else started is never stopped.
"""

import atexit
import os

import bpy

from . import preferences
from .client import tessd

ADDON_DIR = os.path.dirname(os.path.abspath(__file__))

#: Sockets of the daemons this add-on started, with whether to stop each on exit.
_started = {}


class DaemonError(Exception):
    """The daemon cannot be reached; the message says why and what to do."""


def find_binary(prefs):
    """The tessd executable, or raise DaemonError naming the places that were searched."""
    path = bpy.path.abspath(prefs.binary_path) if prefs.binary_path else ""
    if path:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
        raise DaemonError("the tessd binary set in the preferences, %s, is not an executable "
                          "file" % path)
    for candidate in (os.path.join(ADDON_DIR, "tessd"), os.path.join(ADDON_DIR, "bin", "tessd")):
        if os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return candidate
    try:
        return tessd.daemon.find_binary(None)
    except tessd.DaemonStartError as e:
        raise DaemonError("%s (or set its path in Preferences > Add-ons > tessd)" % e) from e


def describe_binary(prefs):
    try:
        return find_binary(prefs)
    except DaemonError as e:
        return "not found: %s" % e


def socket_path(prefs):
    return tessd.resolve_socket(prefs.socket or None, create_dir=True)


def connect(context=None):
    """A tessd.Client on the configured socket; starts the daemon first when none answers
    and the preferences allow it. Raises DaemonError with a message for the user."""
    prefs = preferences.get(context)
    path = socket_path(prefs)
    try:
        return tessd.Client(path, timeout=5.0)
    except (tessd.DaemonUnavailable, OSError) as e:
        if not prefs.auto_start:
            raise DaemonError("no tessd daemon answers on %s (%s); start `tessd serve` or turn "
                              "on \"Start the daemon automatically\" in the add-on's preferences"
                              % (path, e)) from e
    binary = find_binary(prefs)
    try:
        tessd.ensure_daemon(path, binary=binary, timeout=prefs.timeout)
    except tessd.DaemonUnavailable as e:
        raise DaemonError("could not start the tessd daemon: %s" % e) from e
    _started[path] = bool(prefs.stop_on_exit)
    try:
        return tessd.Client(path, timeout=5.0)
    except (tessd.DaemonUnavailable, OSError) as e:
        raise DaemonError("the tessd daemon started on %s but does not answer: %s" % (path, e)) from e


def stop_started():
    """Shuts down the daemons this add-on started (those marked to stop on exit)."""
    for path, stop in list(_started.items()):
        _started.pop(path, None)
        if stop:
            try:
                tessd.stop_daemon(path, timeout=5.0)
            except Exception:  # exiting: nothing useful to do with the error
                pass


def register():
    atexit.register(stop_started)


def unregister():
    atexit.unregister(stop_started)
    stop_started()
