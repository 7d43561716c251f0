"""tessd for FreeCAD: the workbench package `freecad.tessd`.

FreeCAD imports this package at start-up from <user Mod dir>/tessd (package.xml names it); the
GUI registers the workbench from `init_gui.py`. Everything the commands do is in the console API,
`freecad.tessd.api` (tessellate, simplify, generate_lods, export_usd, render), which a macro or
`freecadcmd` script calls the same way.

The workbench is thin glue over the `tessd` Python client (python/tessd in the repository). The
client is bundled at install time (`python3 freecad_plugin/install.py` copies it into
`vendor/tessd` beside this file; git keeps no copy), and that bundled copy is preferred: it is the
one this workbench was installed with. Without it, an installed `tessd` package is used. Importing
this package makes the client importable as `tessd`, or raises an ImportError that says how to
install it.
"""

import os
import sys

__version__ = "0.1.0"

#: Where install.py bundles the client (`vendor/tessd`); this folder goes on sys.path.
VENDOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vendor")


def _import_client():
    """The `tessd` client package: the bundled copy when there is one, else an installed one."""
    if os.path.isfile(os.path.join(VENDOR, "tessd", "__init__.py")) and VENDOR not in sys.path:
        sys.path.insert(0, VENDOR)
    try:
        import tessd
    except ImportError as e:
        raise ImportError(
            "the tessd workbench needs the tessd Python client, which is bundled when the "
            "workbench is installed: run `python3 freecad_plugin/install.py` from the tessd "
            "repository (or put the `tessd` package on FreeCAD's Python path); bundled copy "
            "looked for in %s: %s" % (os.path.join(VENDOR, "tessd"), e)) from e
    return tessd


#: The `tessd` client package this workbench uses (its modules simply `import tessd`: the
#: top-level client, not this package, once the line below has run).
client_package = _import_client()

__all__ = ["VENDOR", "__version__", "client_package"]
