"""B-Rep export: CAD faces → the `tessd-brep` v1 exchange format (docs/brep-format.md).

    from tessd.brep import export_shape
    doc = export_shape(cadquery_or_build123d_or_OCP_shape, units="mm", source="part")
    json.dump(doc, f)

or from the command line: `python -m tessd.brep export PART.step OUT.json [--units mm]`
(STEP, IGES, OpenCASCADE .brep). Needs OCP (cadquery-ocp; the CAD venv `.venv-cad`); OCP is
imported only when something is exported, so `import tessd.brep` works without it.
"""

from __future__ import annotations

from typing import Any, Dict, Optional

FORMAT = "tessd-brep"
VERSION = 1


def export_shape(shape: Any, units: str = "mm", source: Optional[str] = None) -> Dict[str, Any]:
    """The format's document (a JSON-ready dict) for `shape`: an OCP `TopoDS_Shape`, a cadquery
    or build123d shape (anything with a `.wrapped` `TopoDS_Shape`) or a cadquery `Workplane`.
    Every face of the shape is exported (solids, open shells, loose faces alike)."""
    mod = type(shape).__module__ or ""
    if mod == "Part" or mod.startswith("Part."):
        raise NotImplementedError("FreeCAD Part.Shape export is not implemented yet")
    from . import ocp

    return ocp.export_topods(ocp.to_topods(shape), units=units, source=source)


def export_file(path: str, units: str = "mm", source: Optional[str] = None) -> Dict[str, Any]:
    """The document for a STEP / IGES / .brep file (read through OCP, in `units`)."""
    import os

    from . import ocp

    shape = ocp.read_file(path, units=units)
    return ocp.export_topods(shape, units=units, source=os.path.basename(path) if source is None else source)


__all__ = ["FORMAT", "VERSION", "export_shape", "export_file"]
