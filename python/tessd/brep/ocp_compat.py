"""What differs between the two OCP releases the exporter supports, in one place.

- cadquery-ocp 7.9 (OCCT 7.9; cadquery 2.8, the CAD venv `.venv-cad`);
- cadquery-ocp(-novtk) 8.0 (OCCT 8.0; build123d 0.13, `.venv-b123d`).

Checked name by name against both (tests/brep_build123d/test_ocp_names.py and its twin in
tests/brep import every OCP name that ocp.py and the tests use):

- OCCT's NCollection instantiations left their packages in 8.0 for `OCP.collections`, under
  their template names: `TopTools_IndexedMapOfShape` is
  `OCP.collections.IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher` there, `TColgp_Array1OfPnt`
  `Array1_gp_Pnt`, ... (`_COLLECTIONS`). Import them from here under their 7.9 names:
  `from tessd.brep.ocp_compat import TopTools_IndexedMapOfShape`.
- Static methods: 7.9 spells every one `Class.Method_s`; 8.0 keeps the suffix except on the
  `TopoDS` casts (`TopoDS` is a namespace of functions there: `TopoDS.Face_s` → `TopoDS.Face`,
  `Edge`, `Wire`, `Vertex`, ...). `static(cls, "Method")` takes whichever the installed OCP has.
- (Tests only) 8.0 cannot return `Bnd_Box.Get()`'s `Bnd_Box::Limits`: `CornerMin()` /
  `CornerMax()` work in both.

Importing this module imports nothing of OCP; each name is resolved on first use.
"""

from __future__ import annotations

import importlib
from typing import Any, Dict, Tuple

# 7.9 name → (its 7.9 module, its name in OCP 8.0's `OCP.collections`)
_COLLECTIONS: Dict[str, Tuple[str, str]] = {
    "TopTools_IndexedMapOfShape": ("OCP.TopTools", "IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher"),
    "TColgp_Array1OfPnt": ("OCP.TColgp", "Array1_gp_Pnt"),
    "TColgp_Array1OfPnt2d": ("OCP.TColgp", "Array1_gp_Pnt2d"),
    "TColgp_Array2OfPnt": ("OCP.TColgp", "Array2_gp_Pnt"),
    "TColStd_Array1OfInteger": ("OCP.TColStd", "Array1_int"),
    "TColStd_Array1OfReal": ("OCP.TColStd", "Array1_double"),
    "TColStd_Array2OfReal": ("OCP.TColStd", "Array2_double"),
}

_resolved: Dict[str, Any] = {}


def static(cls: Any, name: str) -> Any:
    """The static method `name` of an OCP class: `cls.name_s` (OCP 7.9, and 8.0 outside the
    `TopoDS` casts) or `cls.name` (8.0's `TopoDS.Face`, `TopoDS.Edge`, ...)."""
    f = getattr(cls, name + "_s", None)
    return f if f is not None else getattr(cls, name)


def collection(name: str) -> Any:
    """The OCP class of the NCollection type that OCP 7.9 calls `name` (a key of
    `_COLLECTIONS`), from its 7.9 module or else from 8.0's `OCP.collections`."""
    if name not in _resolved:
        module, new = _COLLECTIONS[name]
        cls = getattr(importlib.import_module(module), name, None)
        if cls is None:
            cls = getattr(importlib.import_module("OCP.collections"), new)
        _resolved[name] = cls
    return _resolved[name]


def __getattr__(name: str) -> Any:  # `from tessd.brep.ocp_compat import TColgp_Array1OfPnt`
    if name in _COLLECTIONS:
        return collection(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["static", "collection", *_COLLECTIONS]
