"""The USD stages the batch writes itself, as ``.usda`` text (no USD library needed on the
workers): each asset's interface stage and the library's root stage.

An asset stage ``assets/<name>/<name>.usda`` has one prim, ``/<name>`` (its ``defaultPrim``,
kind ``component``, ``assetInfo`` with its identifier and name), that references the geometry
the daemon wrote beside it (the LOD chain, else the tessellation, else the converted mesh; each
has ``defaultPrim = "Root"``), so the LOD variant set comes through the reference. Its
``customData`` names the source file, the thumbnail and the turntable frames. All asset paths
are relative (``@./...@``): an output folder can be moved or served from shared storage.

``library.usda`` has ``/Library`` (kind ``assembly``) with one child per asset referencing the
asset stage; an asset whose ``metersPerUnit`` differs from the library's (CAD parts are in mm:
0.001) gets the corrective ``xformOp:scale``, as USD's units guidance asks. The assets are not
laid out (all sit at their own origin): the library is a catalogue to reference from, not a
scene. The text is deterministic, so a re-run writes nothing when nothing changed.
"""

from __future__ import annotations

from typing import Iterable, List, NamedTuple, Optional, Sequence

METERS_PER_UNIT = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254}


def usd_string(text: str) -> str:
    """A USD string literal."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def usd_asset(rel: str) -> str:
    """A USD asset path literal for a relative path (``@./x@``)."""
    rel = rel.replace("\\", "/")
    if "@" in rel:
        raise ValueError("an asset path cannot hold '@': %r" % rel)
    if not rel.startswith(("./", "../", "/")):
        rel = "./" + rel
    return "@" + rel + "@"


def _float(x: float) -> str:
    return repr(float(x))


def asset_stage(name: str, geometry: str, source: str, meters_per_unit: float = 1.0,
                thumbnail: Optional[str] = None, turntable: Sequence[str] = (),
                kind_label: str = "") -> str:
    """The text of an asset's stage. ``geometry``, ``thumbnail``, ``turntable``: paths relative
    to the asset's folder."""
    custom = ["        string source = %s" % usd_string(source)]
    if kind_label:
        custom.append("        string sourceKind = %s" % usd_string(kind_label))
    if thumbnail:
        custom.append("        asset thumbnail = %s" % usd_asset(thumbnail))
    if turntable:
        custom.append("        asset[] turntable = [%s]" % ", ".join(usd_asset(t) for t in turntable))
    return "\n".join([
        "#usda 1.0",
        "(",
        "    defaultPrim = %s" % usd_string(name),
        "    doc = %s" % usd_string("tessd.batch asset %s" % name),
        "    metersPerUnit = %s" % _float(meters_per_unit),
        '    upAxis = "Z"',
        ")",
        "",
        'def Xform "%s" (' % name,
        "    assetInfo = {",
        "        asset identifier = %s" % usd_asset(name + ".usda"),
        "        string name = %s" % usd_string(name),
        "    }",
        "    customData = {",
        *custom,
        "    }",
        '    kind = "component"',
        "    prepend references = %s" % usd_asset(geometry),
        ")",
        "{",
        "}",
        "",
    ])


class LibraryEntry(NamedTuple):
    name: str
    stage: str  # relative to OUTDIR
    meters_per_unit: float


def library_stage(entries: Iterable[LibraryEntry], meters_per_unit: float = 1.0) -> str:
    """The text of ``library.usda``: ``/Library`` referencing every asset stage."""
    lines: List[str] = [
        "#usda 1.0",
        "(",
        '    defaultPrim = "Library"',
        '    doc = "tessd.batch asset library"',
        "    metersPerUnit = %s" % _float(meters_per_unit),
        '    upAxis = "Z"',
        ")",
        "",
        'def Xform "Library" (',
        '    kind = "assembly"',
        ")",
        "{",
    ]
    for e in sorted(entries, key=lambda e: e.name):
        lines += [
            '    def "%s" (' % e.name,
            "        prepend references = %s" % usd_asset(e.stage),
            "    )",
            "    {",
        ]
        scale = e.meters_per_unit / meters_per_unit
        if abs(scale - 1.0) > 1e-12:
            s = _float(scale)
            lines += [
                "        float3 xformOp:scale = (%s, %s, %s)" % (s, s, s),
                '        uniform token[] xformOpOrder = ["xformOp:scale"]',
            ]
        lines.append("    }")
    lines += ["}", ""]
    return "\n".join(lines)


__all__ = ["LibraryEntry", "METERS_PER_UNIT", "asset_stage", "library_stage", "usd_asset",
           "usd_string"]
