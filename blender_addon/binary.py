"""Which tessd binary the add-on starts.

The preference's path when set, else the daemon bundled in the extension at ``bin/tessd``
(``bin/tessd.exe`` on Windows; build.py puts it there), else $TESSD_BIN, else ``tessd`` on
PATH. The bundled one comes first because a Blender started from a desktop launcher has neither
a shell PATH nor TESSD_BIN, and because it is the daemon this add-on was built and tested with.
Blender's installer extracts the zip with Python's zipfile, which drops permission bits, so the
bundled file is made executable (u+x) before it is run.

Below both the connection (:mod:`daemon`, which starts it) and the preferences panel (which
shows it), so neither imports the other for it.
"""

import os
import platform
import shutil
import stat
import sys

import bpy

from .daemon_error import PREFERENCES_PLACE, DaemonError

ADDON_DIR = os.path.dirname(os.path.abspath(__file__))

#: The bundled daemon, where build.py puts it.
BUNDLED_BINARY = os.path.join(ADDON_DIR, "bin", "tessd.exe" if sys.platform == "win32" else "tessd")


def this_platform():
    """This machine's platform in Blender's extension spelling (linux-x64, macos-arm64, ...),
    the one to name when asking the artist to install the right build."""
    system = platform.system().lower()
    system = {"darwin": "macos"}.get(system, system)
    machine = platform.machine().lower()
    machine = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64"}.get(machine, machine)
    return "%s-%s" % (system, machine)


def _executable(path):
    """A program file: on Windows any existing file (it has no execute bit; the system runs
    ``.exe`` files), elsewhere one with the execute bit for this user."""
    if sys.platform == "win32":
        return os.path.isfile(path)
    return os.path.isfile(path) and os.access(path, os.X_OK)


def bundled_binary():
    """The daemon bundled with the extension, made executable if the installer dropped the
    bit; None when the extension holds none (a source checkout, or another platform's build)."""
    path = BUNDLED_BINARY
    if not os.path.isfile(path):
        return None
    if not os.access(path, os.X_OK) and sys.platform != "win32":
        try:
            os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
        except OSError:
            return None
    return path if _executable(path) else None


def _not_found_message(extra=""):
    # No full stop at the end: operators append "; the scene is unchanged".
    return ("tessd could not start: the tessd program is not in this add-on%s. Reinstall the "
            "tessd extension built for %s, or choose the tessd program in %s"
            % (extra, this_platform(), PREFERENCES_PLACE))


def find_binary(prefs):
    """The tessd executable to start, or raise DaemonError (offering the preferences)."""
    path = bpy.path.abspath(prefs.binary_path) if prefs.binary_path else ""
    if path:
        if _executable(path):
            return path
        raise DaemonError("tessd could not start: the tessd program chosen in %s, %s, is not "
                          "a program file. Choose the tessd program there again, or clear the "
                          "field to use the one in this add-on" % (PREFERENCES_PLACE, path),
                          offer_preferences=True)
    found = bundled_binary()
    if found:
        return found
    env = os.environ.get("TESSD_BIN")
    if env and _executable(env):
        return env
    found = shutil.which("tessd")
    if found:
        return found
    raise DaemonError(_not_found_message(), offer_preferences=True)


def describe_binary(prefs):
    """The binary the add-on would start, or why there is none (for the preferences panel)."""
    try:
        return find_binary(prefs)
    except DaemonError as e:
        return "not found: %s" % e
