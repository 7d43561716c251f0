"""tests/brep runs under OCP 7.9 (.venv-cad: cadquery 2.8) and OCP 8.0 (.venv-b123d: build123d 0.13), scripts/test.sh.
The root conftest puts python/ and tests/ on sys.path and imports nothing the CAD venv lacks;
this one prints the export timings the tests collected (brep_checks.TIMINGS) at the end."""

from __future__ import annotations

import sys


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    checks = sys.modules.get("brep_checks")
    if checks is None or not checks.TIMINGS:
        return
    tr = terminalreporter
    tr.section("tessd.brep export timings (worst deviations relative to the part size)")
    tr.write_line(f"{'part':32} {'faces':>5} {'edges':>5} {'read ms':>7} {'export ms':>9}  "
                  "surface  trim-3D  trim/tol  pcurve(uv)")
    for name, nf, ne, read_ms, export_ms, st in checks.TIMINGS:
        trim = max(st["trim_at_t"], st["trim_projected"])
        tr.write_line(f"{name:32} {nf:5d} {ne:5d} {read_ms:7.0f} {export_ms:9.0f}  "
                      f"{st['surface']:.1e}  {trim:.1e}  {st['trim_vs_tol']:8.2f}  {st['pcurve']:.1e}"
                      + (f"  mirrored {st['mirrored_faces']}" if st["mirrored_faces"] else "")
                      + (f"  converted {st['converted_faces']}" if st["converted_faces"] else "")
                      + (f"  gap bridges {st['bridges']}" if st["bridges"] else ""))
