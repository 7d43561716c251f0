"""A USD ASCII stage of a tree of Xforms and meshes, written as text.

FreeCAD's Python has no USD library (usd-core's `pxr` is not in it), and the daemon writes
stages of one mesh or one LOD chain, not of a document's tree of several parts. So this module
writes the `.usda` text itself, in the form of the daemon's own writer (core/usd/src/writer.rs):
stage metadata (`defaultPrim`, `metersPerUnit`, `upAxis`), `def Xform` per container with a
`matrix4d xformOp:transform`, `def Mesh` per part with its extent, face counts and indices,
`point3f[] points` (f32, relative to an optional origin given as a `double3
xformOp:translate` after the transform, as the daemon does for parts far from the origin),
`primvars:displayColor`, and one `GeomSubset` per face group (family `materialBind`, a
partition). Prim names are sanitised and made unique among siblings as the daemon does.

Matrices are given row-major in USD's convention (row vectors: the translation is the last
row), i.e. the transpose of FreeCAD's `Matrix`.

Plain Python and numpy, no FreeCAD: safe on a worker thread. The file is written to a
temporary name and renamed when complete.
"""

import os
import re
import tempfile
from dataclasses import dataclass, field
from typing import Any, Iterable, List, Optional, Sequence, Tuple

import numpy as np

Matrix = Sequence[Sequence[float]]  # 4 x 4, USD row-vector convention


@dataclass
class MeshPrim:
    """A triangle mesh prim."""

    name: str
    points: Any  # [V, 3] (written as f32 relative to ``origin``)
    triangles: Any  # [F, 3]
    transform: Optional[Matrix] = None
    #: Written as ``xformOp:translate`` after the transform; the points are relative to it.
    origin: Optional[Tuple[float, float, float]] = None
    #: (name, face indices) per subset, in order.
    subsets: List[Tuple[str, Any]] = field(default_factory=list)
    #: One RGB (constant) or one per face ([F, 3], uniform), or None.
    color: Any = None
    #: A string kept as `customData = {string freecad:name = ...}` (what the prim came from).
    source: Optional[str] = None


@dataclass
class Xform:
    """A transform prim with children (Xforms and MeshPrims)."""

    name: str
    transform: Optional[Matrix] = None
    children: List[Any] = field(default_factory=list)
    source: Optional[str] = None


def sanitize(name: str) -> str:
    """A valid prim name: ASCII letters, digits and `_` (others become `_`), not starting with
    a digit (then `_` is put before), never empty."""
    s = re.sub(r"[^A-Za-z0-9_]", "_", name or "")
    if not s or s[0].isdigit():
        s = "_" + s
    return s


class _UniqueNames:
    """Sanitised names unique among siblings: `a`, `a_1`, `a_2`..."""

    def __init__(self) -> None:
        self.used = set()

    def claim(self, name: str) -> str:
        base = sanitize(name)
        out, k = base, 0
        while out in self.used:
            k += 1
            out = "%s_%d" % (base, k)
        self.used.add(out)
        return out


def _float(v: float) -> str:
    """Shortest text of a finite double that reads back the same."""
    v = float(v)
    return "0" if v == 0.0 and not np.signbit(v) else repr(v)


def _string(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _ints(values: Iterable[int]) -> str:
    return "[" + ", ".join(str(int(v)) for v in values) + "]"


def _tuples_f32(rows: Any) -> str:
    """``[(x, y, z), ...]`` with 9 significant digits: f32 values read back exactly."""
    rows = np.asarray(rows, dtype=np.float32).reshape(-1, 3)
    return "[" + ", ".join("(%.9g, %.9g, %.9g)" % tuple(r) for r in rows.tolist()) + "]"


def _matrix(m: Matrix) -> str:
    return "( " + ", ".join("(" + ", ".join(_float(v) for v in row) + ")" for row in m) + " )"


def _custom(pad: str, source: Optional[str]) -> str:
    if source is None:
        return ""
    return "%s    customData = {\n%s        string freecadName = %s\n%s    }\n" % (
        pad, pad, _string(source), pad)


def _xform_ops(pad: str, transform: Optional[Matrix], origin: Optional[Sequence[float]]) -> List[str]:
    lines, order = [], []
    if transform is not None:
        lines.append("%smatrix4d xformOp:transform = %s\n" % (pad, _matrix(transform)))
        order.append('"xformOp:transform"')
    if origin is not None:
        lines.append("%sdouble3 xformOp:translate = (%s)\n" % (pad, ", ".join(_float(v) for v in origin)))
        order.append('"xformOp:translate"')
    if order:
        lines.append("%suniform token[] xformOpOrder = [%s]\n" % (pad, ", ".join(order)))
    return lines


def _mesh(out: List[str], prim: MeshPrim, name: str, ind: int) -> None:
    pad, pad1 = "    " * ind, "    " * (ind + 1)
    origin = np.asarray(prim.origin if prim.origin is not None else (0.0, 0.0, 0.0), dtype=np.float64)
    points = (np.asarray(prim.points, dtype=np.float64).reshape(-1, 3) - origin).astype(np.float32)
    tris = np.asarray(prim.triangles, dtype=np.int64).reshape(-1, 3)
    out.append('%sdef Mesh "%s"%s\n%s{\n' % (
        pad, name, " (\n" + _custom(pad, prim.source) + pad + ")" if prim.source else "", pad))
    if len(points):
        out.append("%sfloat3[] extent = %s\n" % (pad1, _tuples_f32([points.min(0), points.max(0)])))
    out.append("%sint[] faceVertexCounts = %s\n" % (pad1, _ints([3] * len(tris))))
    out.append("%sint[] faceVertexIndices = %s\n" % (pad1, _ints(tris.reshape(-1).tolist())))
    out.append('%suniform bool doubleSided = false\n%suniform token orientation = "rightHanded"\n'
               % (pad1, pad1))
    out.append("%spoint3f[] points = %s\n" % (pad1, _tuples_f32(points)))
    if prim.color is not None:
        color = np.asarray(prim.color, dtype=np.float32).reshape(-1, 3)
        constant = len(color) == 1 or bool(np.all(color == color[0]))
        out.append('%scolor3f[] primvars:displayColor = %s (\n%s    interpolation = "%s"\n%s)\n'
                   % (pad1, _tuples_f32(color[:1] if constant else color), pad1,
                      "constant" if constant else "uniform", pad1))
    out.append('%suniform token subdivisionScheme = "none"\n' % pad1)
    if prim.subsets:
        out.append('%suniform token subsetFamily:materialBind:familyType = "partition"\n' % pad1)
    out.extend(_xform_ops(pad1, prim.transform, prim.origin))
    names = _UniqueNames()
    for subset_name, faces in prim.subsets:
        out.append('\n%sdef GeomSubset "%s"\n%s{\n%s    uniform token elementType = "face"\n'
                   '%s    uniform token familyName = "materialBind"\n%s    int[] indices = %s\n%s}\n'
                   % (pad1, names.claim(subset_name), pad1, pad1, pad1, pad1,
                      _ints(np.asarray(faces).reshape(-1).tolist()), pad1))
    out.append("%s}\n" % pad)


def _xform(out: List[str], node: Xform, name: str, ind: int) -> None:
    pad = "    " * ind
    meta = " (\n" + _custom(pad, node.source) + pad + ")" if node.source else ""
    out.append('%sdef Xform "%s"%s\n%s{\n' % (pad, name, meta, pad))
    out.extend(_xform_ops(pad + "    ", node.transform, None))
    _children(out, node.children, ind + 1)
    out.append("%s}\n" % pad)


def _children(out: List[str], children: Sequence[Any], ind: int) -> None:
    names = _UniqueNames()
    for child in children:
        if not out[-1].endswith("{\n"):
            out.append("\n")
        if isinstance(child, MeshPrim):
            _mesh(out, child, names.claim(child.name), ind)
        else:
            _xform(out, child, names.claim(child.name), ind)


def stage_text(root: Xform, meters_per_unit: float = 0.001, up_axis: str = "Z",
               doc: Optional[str] = None) -> str:
    """The `.usda` text of a stage whose default prim is ``root``."""
    name = sanitize(root.name)
    out = ["#usda 1.0\n(\n", '    defaultPrim = "%s"\n' % name]
    if doc:
        out.append("    doc = %s\n" % _string(doc))
    out.append("    metersPerUnit = %s\n    upAxis = \"%s\"\n)\n\n" % (_float(meters_per_unit), up_axis))
    _xform(out, root, name, 0)
    return "".join(out)


def write_stage(path: str, root: Xform, **kwargs: Any) -> str:
    """Writes :func:`stage_text` to ``path`` (through a temporary file renamed when complete,
    so a failure leaves no partial stage); returns the absolute path."""
    path = os.path.abspath(path)
    text = stage_text(root, **kwargs)
    fd, tmp = tempfile.mkstemp(prefix=".tessd-", suffix=".usda.tmp", dir=os.path.dirname(path))
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


__all__ = ["MeshPrim", "Xform", "sanitize", "stage_text", "write_stage"]
