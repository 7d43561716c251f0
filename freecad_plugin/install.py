#!/usr/bin/env python3
"""Installs the tessd workbench into FreeCAD's user Mod folder.

    python3 freecad_plugin/install.py [--link] [--mod-dir DIR] [--client DIR]

1. Bundles the tessd Python client: copies python/tessd (or ``--client DIR``) into
   freecad_plugin/freecad/tessd/vendor/tessd, where the workbench imports it from (git ignores
   that folder: the copy is made at install, never committed).
2. Copies freecad_plugin to ``<Mod dir>/tessd`` (or, with ``--link``, makes that a symbolic
   link to this folder, so that edits of a checkout take effect at FreeCAD's next start).

The Mod folder defaults to FreeCAD's own answer, ``FreeCAD.getUserAppDataDir() + "Mod"``
(~/.local/share/FreeCAD/Mod on Linux with FreeCAD 0.20), asked from FreeCAD's Python modules
when they can be imported (Debian: /usr/lib/freecad-python3/lib, or $FREECAD_LIB), else the
platform's usual place. An existing ``<Mod dir>/tessd`` is replaced only when it is a link or
an earlier install of this workbench (its package.xml names tessd); anything else there is
left alone and the install refuses. Errors end the script with status 2 and a message.
"""

import argparse
import os
import platform
import re
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
#: The client's source in the repository.
CLIENT = os.path.join(REPO, "python", "tessd")
#: Where the workbench imports the bundled client from.
VENDOR = os.path.join(HERE, "freecad", "tessd", "vendor")
#: Files of freecad_plugin not copied into the Mod folder.
EXCLUDE = ("install.py", "__pycache__", "*.pyc")
#: The folder's name in Mod (the workbench's name in package.xml).
NAME = "tessd"
#: Where Debian's FreeCAD packages put FreeCAD's Python modules.
FREECAD_LIB = "/usr/lib/freecad-python3/lib"


class InstallError(Exception):
    """A reason not to install, for the user."""


def freecad_mod_dir():
    """FreeCAD's user Mod folder: FreeCAD's own answer when its modules import, else the
    platform's default (FreeCAD 0.20's rules: $FREECAD_USER_HOME, XDG on Linux)."""
    lib = os.environ.get("FREECAD_LIB", FREECAD_LIB)
    if os.path.isdir(lib) and lib not in sys.path:
        sys.path.append(lib)
    try:
        import FreeCAD  # noqa: F401 - the application module (no GUI)

        return os.path.join(FreeCAD.getUserAppDataDir(), "Mod")
    except ImportError:
        pass
    home = os.environ.get("FREECAD_USER_HOME") or os.path.expanduser("~")
    system = platform.system()
    if system == "Windows":
        base = os.path.join(os.environ.get("APPDATA", home), "FreeCAD")
    elif system == "Darwin":
        base = os.path.join(home, "Library", "Application Support", "FreeCAD")
    elif os.path.isdir(os.path.join(home, ".FreeCAD")):
        base = os.path.join(home, ".FreeCAD")  # the layout before 0.20, still honoured
    else:
        base = os.path.join(os.environ.get("XDG_DATA_HOME") or os.path.join(home, ".local", "share"),
                            "FreeCAD")
    return os.path.join(base, "Mod")


def bundle_client(client):
    """Copies the client package into vendor/tessd (replacing an older copy); returns its
    version."""
    init = os.path.join(client, "__init__.py")
    if not os.path.isfile(init):
        raise InstallError("no tessd client at %s (expected the python/tessd package of the "
                           "tessd repository; pass --client DIR)" % client)
    with open(init, encoding="utf-8") as f:
        m = re.search(r'^__version__\s*=\s*"([^"]+)"', f.read(), re.M)
    target = os.path.join(VENDOR, "tessd")
    if os.path.realpath(client) == os.path.realpath(target):
        return m.group(1) if m else "?"
    os.makedirs(VENDOR, exist_ok=True)
    if os.path.islink(target) or os.path.isfile(target):
        os.unlink(target)
    elif os.path.isdir(target):
        shutil.rmtree(target)
    shutil.copytree(client, target, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return m.group(1) if m else "?"


def _ours(path):
    """Whether ``path`` is a link or an earlier install of this workbench."""
    if os.path.islink(path):
        return True
    xml = os.path.join(path, "package.xml")
    if not os.path.isfile(xml):
        return False
    with open(xml, encoding="utf-8") as f:
        return re.search(r"<name>\s*%s\s*</name>" % NAME, f.read()) is not None


def install(mod_dir, link):
    """Puts the workbench at ``<mod_dir>/tessd``; returns that path."""
    mod_dir = os.path.abspath(os.path.expanduser(mod_dir))
    target = os.path.join(mod_dir, NAME)
    if os.path.realpath(target) == os.path.realpath(HERE) and not os.path.islink(target):
        raise InstallError("%s is this very folder; nothing to install" % target)
    if os.path.lexists(target):
        if not _ours(target):
            raise InstallError("%s exists and is not an install of the tessd workbench; move "
                               "it away or choose another --mod-dir" % target)
        if os.path.islink(target) or os.path.isfile(target):
            os.unlink(target)
        else:
            shutil.rmtree(target)
    os.makedirs(mod_dir, exist_ok=True)
    if link:
        os.symlink(HERE, target, target_is_directory=True)
    else:
        shutil.copytree(HERE, target, ignore=shutil.ignore_patterns(*EXCLUDE))
    return target


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--link", action="store_true",
                    help="link <Mod dir>/tessd to this folder instead of copying it")
    ap.add_argument("--mod-dir", help="FreeCAD's user Mod folder (default: FreeCAD's own, "
                                      "e.g. ~/.local/share/FreeCAD/Mod)")
    ap.add_argument("--client", default=CLIENT,
                    help="the tessd client package to bundle (default: %(default)s)")
    args = ap.parse_args(argv)
    try:
        version = bundle_client(os.path.abspath(args.client))
        target = install(args.mod_dir or freecad_mod_dir(), args.link)
    except (InstallError, OSError) as e:
        print("install.py: error: %s" % e, file=sys.stderr)
        return 2
    print("tessd workbench %s at %s (client %s bundled from %s)"
          % ("linked" if args.link else "copied", target, version, args.client))
    print("Restart FreeCAD; the workbench is 'tessd' (console API: from freecad.tessd import api)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
