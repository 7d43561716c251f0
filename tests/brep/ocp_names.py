"""Every OCP name a module uses, resolved against the installed OCP: the `from OCP.X import Y`
imports, the static methods reached through `static(Class, "Name")` (tessd.brep.ocp_compat;
`_static` / `_s` in ocp.py and brep_checks.py), the collections ocp_compat maps, and attributes
spelled out on an imported OCP class (`BRepGProp.SurfaceProperties_s`). tests/brep (with
test_ocp_names.py) runs under OCP 7.9 (.venv-cad) and OCP 8.0 (.venv-b123d), so a name that one
of them lacks fails a test instead of an export, or instead of a test far from the name."""

from __future__ import annotations

import ast
import importlib
import types
from pathlib import Path
from typing import Any, Dict, List

REPO = Path(__file__).resolve().parents[2]
STATIC_HELPERS = {"static", "_static", "_s"}
# The modules both OCP versions must load: the exporter, every module of tests/brep (which runs
# under both) and the OCP benchmark's peer.
SHARED = ([REPO / "python" / "tessd" / "brep" / "ocp.py", REPO / "bench" / "brep" / "peer_ocp.py"]
          + sorted((REPO / "tests" / "brep").glob("*.py")))


def unresolved(path: Path) -> List[str]:
    """The OCP names used in `path` that the installed OCP does not have ([] when all resolve)."""
    from tessd.brep import ocp_compat

    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    missing: List[str] = []
    bound: Dict[str, Any] = {}
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom) or not node.module:
            continue
        if node.module.startswith("OCP"):
            for a in node.names:
                try:
                    bound[a.asname or a.name] = getattr(importlib.import_module(node.module), a.name)
                except (ImportError, AttributeError) as e:
                    missing.append(f"{path.name}:{node.lineno}: {node.module}.{a.name} ({e})")
        elif node.module.endswith("ocp_compat"):
            for a in node.names:
                if a.name in ocp_compat._COLLECTIONS:
                    try:
                        bound[a.asname or a.name] = ocp_compat.collection(a.name)
                    except (ImportError, AttributeError) as e:
                        missing.append(f"{path.name}:{node.lineno}: {a.name} ({e})")
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in STATIC_HELPERS and len(node.args) == 2
                and isinstance(node.args[0], ast.Name) and isinstance(node.args[1], ast.Constant)):
            cls, name = bound.get(node.args[0].id), node.args[1].value
            if cls is not None and not (hasattr(cls, name + "_s") or hasattr(cls, name)):
                missing.append(f"{path.name}:{node.lineno}: {node.args[0].id}.{name}(_s)")
        elif (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
              and isinstance(bound.get(node.value.id), (type, types.ModuleType))  # (8.0: TopoDS)
              and not hasattr(bound[node.value.id], node.attr)):
            missing.append(f"{path.name}:{node.lineno}: {node.value.id}.{node.attr}")
    return missing
