"""tests/brep_freecad runs in the system Python, the one FreeCAD's Debian packages are built for
(scripts/test.sh: `PYTHONPATH=python:tests /usr/bin/python3 -m pytest tests/brep_freecad`; apt
packages libfreecad-python3-0.20, python3-pytest, python3-numpy from scripts/setup.sh). The root
conftest (path setup, the `daemon` fixture) needs nothing beyond the standard library there; this
one makes FreeCAD importable (FreeCAD 0.20's modules live outside sys.path) and prints the export
timings the tests collected (fc_checks.TIMINGS) at the end."""

from __future__ import annotations

import os
import sys

FREECAD_LIB = os.environ.get("FREECAD_LIB", "/usr/lib/freecad-python3/lib")
if FREECAD_LIB not in sys.path:
    sys.path.append(FREECAD_LIB)

try:
    import FreeCAD  # noqa: E402,F401
    import Part  # noqa: E402,F401
except ImportError as e:  # a clear failure, not a skip: these tests are there to run FreeCAD
    raise ImportError(f"tests/brep_freecad needs FreeCAD's Python modules in {FREECAD_LIB} "
                      f"(Debian: libfreecad-python3-0.20; scripts/setup.sh installs it) and the "
                      f"Python they are built for (/usr/bin/python3): {e}") from e


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    checks = sys.modules.get("fc_checks")
    if checks is None or not checks.TIMINGS:
        return
    tr = terminalreporter
    tr.section("tessd.brep export from FreeCAD: timings, worst deviations relative to the part size")
    tr.write_line(f"{'part':32} {'faces':>5} {'edges':>5} {'read ms':>7} {'export ms':>9}  "
                  "surface  trim-3D  vertex")
    for name, nf, ne, read_ms, export_ms, st in checks.TIMINGS:
        tr.write_line(f"{name:32} {nf:5d} {ne:5d} {read_ms:7.0f} {export_ms:9.0f}  "
                      f"{st['surface']:.1e}  {st['trim']:.1e}  {st['vertex']:.1e}"
                      + (f"  mirrored {st['mirrored']}" if st["mirrored"] else "")
                      + (f"  converted {st['converted']}" if st["converted"] else "")
                      + (f"  gap bridges {st['bridges']}" if st["bridges"] else ""))
