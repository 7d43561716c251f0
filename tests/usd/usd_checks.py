"""Reusable checks of USD files with usd-core (``pxr``), for every test that writes a stage.

    from usd_checks import validate_stage
    assert validate_stage(path) == []

``validate_stage`` runs usd-core's own validators (the ``pxr.UsdValidation`` framework; the
usd-core wheel ships no ``usdchecker``, and 26.8+ has no ``UsdUtils.ComplianceChecker``) plus a
few geometry checks usd-core has no validator for (mesh topology, extent, primvar sizes), on
the stage as composed *and* once per variant of every variant set (so each ``LOD`` level is
checked, not only the selected one).

How the 26.11 API works: ``UsdValidation.ValidationRegistry()`` knows every registered
validator by name (``GetAllValidatorMetadata()``, ``GetOrLoadValidatorsByName(names)``);
``UsdValidation.ValidationContext(validators).Validate(stage)`` returns a list of
``ValidationError`` whose ``GetType()`` is ``ValidationErrorType.Error`` / ``Warn`` / ``Info``,
with ``GetErrorAsString()`` for a one-line message.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from pxr import Tf, Usd, UsdGeom, UsdValidation

#: Validator groups (metadata keywords) relevant to geometry and stage metadata:
#: ``UsdCoreValidators`` (defaultPrim, attribute types vs schema, composition errors),
#: ``UsdGeomValidators`` (upAxis / metersPerUnit, GeomSubset families and parents, no nested
#: gprims), ``UsdShadeValidators`` (materialBind subset families, binding relationships) and
#: ``UsdUtilsValidators`` (file extensions, unresolvable references, package layout).
#: Left out as irrelevant to tessd's output: physics, lights, skeletons, media.
RELEVANT_KEYWORDS = (
    "UsdCoreValidators",
    "UsdGeomValidators",
    "UsdShadeValidators",
    "UsdUtilsValidators",
)


@dataclass
class Report:
    """Everything one validation run found, as one-line messages."""

    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    validators: list[str] = field(default_factory=list)


def validator_names(keywords: Iterable[str] | None = RELEVANT_KEYWORDS) -> list[str]:
    """Names of the registered validators tagged with any of ``keywords`` (all if ``None``),
    suites excluded, sorted."""
    registry = UsdValidation.ValidationRegistry()
    if keywords is None:
        metadata = registry.GetAllValidatorMetadata()
    else:
        metadata = registry.GetValidatorMetadataForKeywords(list(keywords))
    return sorted({m.name for m in metadata if not m.isSuite})


def validate_stage(path: str | Path, keywords: Iterable[str] | None = RELEVANT_KEYWORDS) -> list[str]:
    """Error messages for the stage at ``path`` (an empty list when it is valid).

    Runs the usd-core validators named by :func:`validator_names` and :func:`geometry_errors`,
    for the stage as composed and for every variant of every variant set. A file that does not
    open gives one ``open failed`` message. Warnings are not errors: see :func:`check_stage`.
    """
    return check_stage(path, keywords).errors


def check_stage(path: str | Path, keywords: Iterable[str] | None = RELEVANT_KEYWORDS) -> Report:
    """Like :func:`validate_stage`, but also returns the warnings and the validators run."""
    names = validator_names(keywords)
    report = Report(validators=names)
    try:
        stage = Usd.Stage.Open(str(path), Usd.Stage.LoadAll)
    except Tf.ErrorException as e:
        report.errors.append(f"open failed: {str(e).strip()}")
        return report
    if stage is None:
        report.errors.append(f"open failed: {path}")
        return report
    validators = UsdValidation.ValidationRegistry().GetOrLoadValidatorsByName(names)
    context = UsdValidation.ValidationContext(validators)

    seen: set[str] = set()

    def run(label: str) -> None:
        for e in context.Validate(stage):
            if e.HasNoError():
                continue
            msg = f"{label}{e.GetErrorAsString()}"
            if msg in seen:
                continue
            seen.add(msg)
            kind = e.GetType()
            if kind == UsdValidation.ValidationErrorType.Error:
                report.errors.append(msg)
            elif kind == UsdValidation.ValidationErrorType.Warn:
                report.warnings.append(msg)
        for msg in geometry_errors(stage):
            if f"{label}{msg}" not in seen:
                seen.add(f"{label}{msg}")
                report.errors.append(f"{label}{msg}")

    run("")
    # Every variant of every variant set, one set at a time, selected in the session layer so
    # the file is not touched.
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        for prim in [p for p in stage.Traverse() if p.HasVariantSets()]:
            vsets = prim.GetVariantSets()
            for set_name in vsets.GetNames():
                vset = vsets.GetVariantSet(set_name)
                original = vset.GetVariantSelection()
                for variant in vset.GetVariantNames():
                    if variant == original:
                        continue
                    vset.SetVariantSelection(variant)
                    run(f"[{prim.GetPath()} {set_name}={variant}] ")
                vset.ClearVariantSelection()
    return report


def geometry_errors(stage: Usd.Stage) -> list[str]:
    """Checks usd-core has no validator for, on every Mesh of the composed stage: topology
    (``UsdGeom.Mesh.ValidateTopology``), finite points, authored extent = computed extent, and
    for every authored primvar a valid interpolation, element count and index range."""
    errors: list[str] = []
    time = Usd.TimeCode.Default()
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh):
            continue
        mesh = UsdGeom.Mesh(prim)
        where = f"tessd:mesh <{prim.GetPath()}>"
        points = mesh.GetPointsAttr().Get(time)
        counts = mesh.GetFaceVertexCountsAttr().Get(time)
        indices = mesh.GetFaceVertexIndicesAttr().Get(time)
        if points is None or counts is None or indices is None:
            errors.append(f"{where}: points, faceVertexCounts or faceVertexIndices missing")
            continue
        ok, why = UsdGeom.Mesh.ValidateTopology(indices, counts, len(points))
        if not ok:
            errors.append(f"{where}: invalid topology: {why}")
        if not np.isfinite(np.asarray(points, dtype=np.float64)).all():
            errors.append(f"{where}: non-finite point")
        extent = mesh.GetExtentAttr().Get(time)
        if len(points) > 0:
            expected = UsdGeom.PointBased.ComputeExtent(points)
            if extent is None:
                errors.append(f"{where}: no extent authored")
            elif [tuple(v) for v in extent] != [tuple(v) for v in expected]:
                errors.append(f"{where}: extent {list(extent)} != computed {list(expected)}")
        sizes = {
            UsdGeom.Tokens.constant: 1,
            UsdGeom.Tokens.uniform: len(counts),
            UsdGeom.Tokens.vertex: len(points),
            UsdGeom.Tokens.varying: len(points),
            UsdGeom.Tokens.faceVarying: len(indices),
        }
        for pv in UsdGeom.PrimvarsAPI(prim).GetAuthoredPrimvars():
            name = pv.GetPrimvarName()
            values = pv.Get(time)
            if values is None:
                continue
            interp = pv.GetInterpolation()
            if interp not in sizes:
                errors.append(f"{where}: primvar {name}: unknown interpolation {interp!r}")
                continue
            n = sizes[interp] * pv.GetElementSize()
            if pv.IsIndexed():
                idx = np.asarray(pv.GetIndices(time), dtype=np.int64)
                if len(idx) != n:
                    errors.append(f"{where}: primvar {name}: {len(idx)} indices for {n} elements")
                if len(idx) and (idx.min() < 0 or idx.max() >= len(values)):
                    errors.append(f"{where}: primvar {name}: index out of range")
            elif len(values) != n:
                errors.append(f"{where}: primvar {name}: {len(values)} values for {n} elements")
    return errors


if __name__ == "__main__":
    import sys

    status = 0
    for arg in sys.argv[1:]:
        r = check_stage(arg)
        for w in r.warnings:
            print(f"{arg}: warning: {w}")
        for e in r.errors:
            print(f"{arg}: error: {e}")
        status |= bool(r.errors)
    sys.exit(status)
