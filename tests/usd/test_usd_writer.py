"""Checks tessd-usd's .usda output with real usd-core.

Builds and runs ``cargo run -q -p tessd-usd --example write_samples -- OUTDIR`` from the repo
root, then opens every stage with ``pxr.Usd`` and checks its content against ``samples.json``
(the arrays the example wrote) and usd-core's validators (see ``usd_checks.py``).
Run with ``-s`` to see which validators ran and any warnings they printed.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from usd_checks import check_stage, validate_stage, validator_names

ROOT = Path(__file__).absolute().parents[2]
FILES = ["full.usda", "multi.usda", "lod.usda", "plain.usda"]


@pytest.fixture(scope="module")
def samples(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("usd_samples")
    subprocess.run(
        ["cargo", "run", "-q", "-p", "tessd-usd", "--example", "write_samples", "--", str(out)],
        cwd=ROOT,
        check=True,
    )
    return out, json.loads((out / "samples.json").read_text())


def open_stage(samples, name: str) -> Usd.Stage:
    stage = Usd.Stage.Open(str(samples[0] / name))
    assert stage, name
    return stage


def bits(a) -> np.ndarray:
    """float32 bit patterns, so that 0 and -0 (and every last bit) must match."""
    return np.asarray(a, dtype=np.float32).view(np.uint32)


def check_arrays(mesh: UsdGeom.Mesh, expected: dict) -> None:
    np.testing.assert_array_equal(bits(mesh.GetPointsAttr().Get()), bits(expected["points"]))
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == expected["counts"]
    assert list(mesh.GetFaceVertexIndicesAttr().Get()) == expected["indices"]
    assert mesh.GetFaceCount() == len(expected["counts"])


def test_full_mesh(samples):
    stage = open_stage(samples, "full.usda")
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(0.01)
    assert stage.GetRootLayer().defaultPrim == "Root"
    assert stage.GetRootLayer().documentation == 'tessd sample: "full"\nquad + triangle'
    root = stage.GetDefaultPrim()
    assert root.GetPath() == "/Root" and root.GetTypeName() == "Xform"
    assert Usd.ModelAPI(root).GetKind() == "component"

    # "Part 1" is sanitized.
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/Part_1"))
    assert mesh
    check_arrays(mesh, samples[1]["full.usda"]["/Root/Part_1"])
    assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none
    assert mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.rightHanded
    assert mesh.GetDoubleSidedAttr().Get() is True
    assert [tuple(v) for v in mesh.GetExtentAttr().Get()] == [
        tuple(v) for v in UsdGeom.PointBased.ComputeExtent(mesh.GetPointsAttr().Get())
    ]

    primvars = UsdGeom.PrimvarsAPI(mesh)
    normals = primvars.GetPrimvar("normals")
    assert normals.GetTypeName() == "normal3f[]"
    assert normals.GetInterpolation() == UsdGeom.Tokens.faceVarying
    assert normals.IsIndexed()
    assert [tuple(v) for v in normals.Get()] == [(0, 0, 1), (0, np.float32(0.6), np.float32(0.8))]
    assert list(normals.GetIndices()) == [0, 0, 0, 0, 1, 1, 1]
    st = primvars.GetPrimvar("st")
    assert st.GetTypeName() == "texCoord2f[]"
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    assert st.IsIndexed()
    assert [tuple(v) for v in st.Get()] == [(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0.25)]
    assert list(st.GetIndices()) == [0, 1, 2, 3, 1, 4, 2]
    assert len(st.ComputeFlattened()) == 7

    assert list(mesh.GetCreaseIndicesAttr().Get()) == [1, 2, 0, 1]
    assert list(mesh.GetCreaseLengthsAttr().Get()) == [2, 2]
    assert list(mesh.GetCreaseSharpnessesAttr().Get()) == [10, 2.5]

    subsets = UsdGeom.Subset.GetAllGeomSubsets(mesh)
    assert [s.GetPrim().GetName() for s in subsets] == ["Red_Paint", "metal_001"]
    assert [list(s.GetIndicesAttr().Get()) for s in subsets] == [[1], [0]]
    for s in subsets:
        assert s.GetElementTypeAttr().Get() == UsdGeom.Tokens.face
        assert s.GetFamilyNameAttr().Get() == "materialBind"
    assert UsdGeom.Subset.GetFamilyType(mesh, "materialBind") == UsdGeom.Tokens.partition
    assert UsdGeom.Subset.ValidateFamily(mesh, UsdGeom.Tokens.face, "materialBind") == (True, "")


def test_multi_object_stage(samples):
    stage = open_stage(samples, "multi.usda")
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetRootLayer().defaultPrim == "Scene"
    root = stage.GetDefaultPrim()
    assert [c.GetName() for c in root.GetChildren()] == ["Cube", "Cube_1", "Tri"]
    expected = samples[1]["multi.usda"]
    schemes = {"Cube": "catmullClark", "Cube_1": "catmullClark", "Tri": "loop"}
    offsets = {"Cube": (2, 0, 0), "Cube_1": (-2, 0.5, 0), "Tri": (0, 0, 3)}
    for name, scheme in schemes.items():
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath(f"/Scene/{name}"))
        check_arrays(mesh, expected[f"/Scene/{name}"])
        assert mesh.GetSubdivisionSchemeAttr().Get() == scheme
        assert not UsdGeom.PrimvarsAPI(mesh).GetAuthoredPrimvars()
        world = mesh.ComputeLocalToWorldTransform(Usd.TimeCode.Default())
        assert tuple(world.ExtractTranslation()) == offsets[name]
        assert [op.GetOpName() for op in mesh.GetOrderedXformOps()] == ["xformOp:transform"]
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_])
    box = cache.ComputeWorldBound(root).ComputeAlignedRange()
    assert tuple(box.GetMin()) == (-2, 0, 0) and tuple(box.GetMax()) == (3, 1.5, 3)


def test_lod_variants(samples):
    stage = open_stage(samples, "lod.usda")
    assert UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(0.001)
    root = stage.GetPrimAtPath("/Root")
    vsets = root.GetVariantSets()
    assert vsets.GetNames() == ["LOD"]
    lod = vsets.GetVariantSet("LOD")
    assert lod.GetVariantNames() == ["LOD0", "LOD1", "LOD2"]
    assert lod.GetVariantSelection() == "LOD0"
    levels = samples[1]["lod.usda"]
    counts = []
    for i, name in enumerate(["LOD0", "LOD1", "LOD2"]):
        assert lod.SetVariantSelection(name)
        mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/mesh"))
        check_arrays(mesh, levels[i])
        counts.append(len(mesh.GetPointsAttr().Get()))
    assert counts == [25, 9, 4]


def test_plain_mesh(samples):
    stage = open_stage(samples, "plain.usda")
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetRootLayer().defaultPrim == "Root"
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/mesh"))
    check_arrays(mesh, samples[1]["plain.usda"]["/Root/mesh"])
    assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none
    assert not UsdGeom.PrimvarsAPI(mesh).GetAuthoredPrimvars()
    assert not mesh.GetCreaseIndicesAttr().HasAuthoredValue()
    assert not UsdGeom.Subset.GetAllGeomSubsets(mesh)
    assert not mesh.GetPrim().GetAttribute("xformOpOrder").HasAuthoredValue()


def test_relevant_validators_exist():
    names = validator_names()
    print("\nusd-core validators run:", *names, sep="\n  ")
    for required in [
        "usdGeomValidators:StageMetadataChecker",
        "usdGeomValidators:SubsetFamilies",
        "usdGeomValidators:SubsetParentIsImageable",
        "usdGeomValidators:EncapsulationChecker",
        "usdShadeValidators:SubsetsMaterialBindFamily",
        "usdValidation:StageMetadataChecker",
        "usdValidation:AttributeTypeMismatch",
        "usdValidation:CompositionErrorTest",
    ]:
        assert required in names


@pytest.mark.parametrize("name", FILES)
def test_validators_pass(samples, name):
    report = check_stage(samples[0] / name)
    for w in report.warnings:
        print(f"{name}: warning: {w}")
    assert report.errors == []


@pytest.mark.parametrize("name", FILES)
def test_every_registered_validator_passes(samples, name):
    report = check_stage(samples[0] / name, keywords=None)
    for w in report.warnings:
        print(f"{name}: warning: {w}")
    assert len(report.validators) >= len(validator_names())
    assert report.errors == []


# The checks must be able to fail: broken copies of the samples.


def test_checks_catch_missing_metadata_and_bad_subsets(samples, tmp_path):
    text = (samples[0] / "full.usda").read_text()
    text = text.replace('    upAxis = "Z"\n', "").replace("int[] indices = [0]", "int[] indices = [1]")
    bad = tmp_path / "bad.usda"
    bad.write_text(text)
    errors = validate_stage(bad)
    assert any("MissingUpAxisMetadata" in e for e in errors), errors
    assert any("InvalidSubsetFamily" in e for e in errors), errors


def test_checks_look_inside_every_variant(samples, tmp_path):
    text = (samples[0] / "lod.usda").read_text()
    # Break LOD1 only (not the selected variant): a face uses vertex 99 of 9.
    head, lod1 = text.split('"LOD1" {')
    lod1 = lod1.replace("int[] faceVertexIndices = [0,", "int[] faceVertexIndices = [99,", 1)
    bad = tmp_path / "bad_lod.usda"
    bad.write_text(head + '"LOD1" {' + lod1)
    errors = validate_stage(bad)
    assert len(errors) == 1, errors
    assert errors[0].startswith("[/Root LOD=LOD1] tessd:mesh </Root/mesh>: invalid topology")


def test_checks_report_unparsable_files(tmp_path):
    bad = tmp_path / "garbage.usda"
    bad.write_text('#usda 1.0\ndef Mesh "x" { int[] faceVertexCounts = [3 }\n')
    errors = validate_stage(bad)
    assert len(errors) == 1 and errors[0].startswith("open failed"), errors
