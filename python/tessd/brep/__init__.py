"""B-Rep export: CAD faces → the `tessd-brep` v1 exchange format (docs/brep-format.md).

    from tessd.brep import export_shape
    doc = export_shape(cadquery_or_build123d_or_OCP_shape, units="mm", source="part")
    doc = export_shape(freecad_part_shape)  # inside FreeCAD (or its Python modules)
    json.dump(doc, f)

or from the command line: `python -m tessd.brep export PART.step OUT.json [--units mm]
[--sew | --no-sew] [--sew-tolerance X]` (STEP, IGES, OpenCASCADE .brep; unsewn IGES surfaces
and open STEP shells are sewn by default). OCP shapes need OCP: 7.9 (cadquery 2.8, the CAD venv
`.venv-cad`) or 8.0 (build123d 0.13, `.venv-b123d`; ocp_compat.py resolves what 8.0 renamed).
FreeCAD shapes go through FreeCAD's own Part API (freecad.py); either is imported only when
something is exported, so `import tessd.brep` works without them.
"""

from __future__ import annotations

import sys
from typing import Any, Dict, Optional

from .document import FORMAT, VERSION


#: What to do when OCP is missing (pyproject's `cad` extra, the venvs scripts/setup.sh makes).
OCP_HINT = ("run it with the CAD venv's Python (.venv-cad/bin/python, cadquery 2.8 / OCP 7.9, or "
            ".venv-b123d/bin/python, build123d 0.13 / OCP 8.0; scripts/setup.sh makes both), or "
            "install OCP into this one: pip install './python[cad]' from the tessd repository "
            "(cadquery-ocp 7.9), or pip install cadquery / build123d")


def missing_ocp_message(error: ImportError) -> str:
    """The message for an OCP that cannot be imported: what failed, in which Python, and
    where OCP comes from (:data:`OCP_HINT`)."""
    return (f"OCP (OpenCASCADE's Python bindings), which reading STEP / IGES / BREP files and "
            f"OCP shapes needs, is not importable in {sys.executable} ({error}): {OCP_HINT}")


def import_ocp() -> Any:
    """The `tessd.brep.ocp` module, or an ImportError saying where OCP comes from."""
    try:
        from . import ocp
    except ImportError as e:
        raise ImportError(missing_ocp_message(e), name=e.name) from e
    return ocp


def _is_freecad(shape: Any) -> bool:
    """A FreeCAD `Part` object (Part.Shape, Part.Solid, ...) or a document object with a
    `Part.Shape` (its type's module says so: nothing of FreeCAD is imported to ask)."""
    def from_part(obj: Any) -> bool:
        mod = type(obj).__module__ or ""
        return mod == "Part" or mod.startswith("Part.")

    return from_part(shape) or ("Part" in sys.modules and from_part(getattr(shape, "Shape", None)))


def export_shape(shape: Any, units: str = "mm", source: Optional[str] = None,
                 sew: Optional[bool] = None, sew_tolerance: Optional[float] = None) -> Dict[str, Any]:
    """The format's document (a JSON-ready dict) for `shape`: an OCP `TopoDS_Shape`, a cadquery
    or build123d shape (anything with a `.wrapped` `TopoDS_Shape`), a cadquery `Workplane`, or
    a FreeCAD `Part.Shape` (or document object; FreeCAD's millimetres are scaled to `units`).
    Every face of the shape is exported (solids, open shells, loose faces alike).

    `sew` / `sew_tolerance` (OCP shapes): unsewn faces are sewn (`BRepBuilderAPI_Sewing`) by
    default when the shape has free edges, never when it is closed; True / False force it (see
    tessd.brep.ocp.prepare). FreeCAD shapes are exported as they are (sew them with Part's
    `sewShape` first): `sew=True` is refused for them."""
    if _is_freecad(shape):
        from . import freecad

        if sew:
            raise ValueError("sewing is done through OCP; sew a FreeCAD shape with "
                             "Part.Shape.sewShape(tolerance) before exporting it")
        return freecad.export_shape(shape, units=units, source=source)
    try:
        from . import ocp
    except ImportError as e:
        raise TypeError(f"not a FreeCAD Part.Shape ({type(shape).__name__}), and "
                        f"{missing_ocp_message(e)}") from e

    return ocp.export_topods(ocp.to_topods(shape), units=units, source=source, sew=sew,
                             sew_tolerance=sew_tolerance)


def export_file(path: str, units: str = "mm", source: Optional[str] = None,
                sew: Optional[bool] = None, sew_tolerance: Optional[float] = None) -> Dict[str, Any]:
    """The document for a STEP / IGES / .brep file (read through OCP, in `units`; an unsewn
    IGES surface model or open STEP shell is sewn unless `sew=False`, as in `export_shape`)."""
    import os

    ocp = import_ocp()
    shape = ocp.read_file(path, units=units)
    return ocp.export_topods(shape, units=units, source=os.path.basename(path) if source is None else source,
                             sew=sew, sew_tolerance=sew_tolerance)


__all__ = ["FORMAT", "OCP_HINT", "VERSION", "export_shape", "export_file", "import_ocp",
           "missing_ocp_message"]
