"""Opens a tessd.batch library with usd-core and prints what it finds as JSON (run by a Python
that has ``pxr``: the tests' .venv, since the CAD venv has none).

    .venv/bin/python tests/batch/usd_check.py OUTDIR

Output: ``{"library": {...}, "assets": {name: {...}}}``: for library.usda its default prim, the
asset prims under it, the layers used, composition errors; for every asset stage
(``assets/<name>/<name>.usda``) opened on its own: its default prim, kind, assetInfo, whether the
reference resolved (a mesh is reachable), usd-core's validators (tests/usd/usd_checks.py:
``validation``, a list of errors), the meshes' faces / triangles / points per LOD variant
(or of the single mesh), and the customData's thumbnail / turntable paths and whether they
exist.
"""

from __future__ import annotations

import json
import os
import sys

from pxr import Usd, UsdGeom

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "usd"))
from usd_checks import validate_stage  # noqa: E402  (usd-core's validators + geometry checks)


def mesh_counts(stage: "Usd.Stage", root: "Usd.Prim") -> dict:
    faces = tris = points = meshes = 0
    for prim in Usd.PrimRange(root):
        if not prim.IsA(UsdGeom.Mesh):
            continue
        m = UsdGeom.Mesh(prim)
        if UsdGeom.Imageable(prim).ComputeVisibility() == UsdGeom.Tokens.invisible:
            continue
        counts = m.GetFaceVertexCountsAttr().Get() or []
        meshes += 1
        faces += len(counts)
        tris += sum(max(0, int(c) - 2) for c in counts)
        points += len(m.GetPointsAttr().Get() or [])
    return {"meshes": meshes, "faces": faces, "triangles": tris, "points": points}


def composition_errors(stage: "Usd.Stage") -> list:
    get = getattr(stage, "GetCompositionErrors", None)
    if get is None:
        return []
    return [str(e.GetMessage() if hasattr(e, "GetMessage") else e) for e in get()]


def check_asset(path: str) -> dict:
    out: dict = {"path": path, "opened": False}
    stage = Usd.Stage.Open(path)
    if stage is None:
        return out
    out["opened"] = True
    prim = stage.GetDefaultPrim()
    out["default_prim"] = prim.GetName() if prim else None
    if not prim:
        return out
    out["kind"] = Usd.ModelAPI(prim).GetKind()
    info = Usd.ModelAPI(prim).GetAssetInfo()
    out["asset_name"] = info.get("name")
    ident = info.get("identifier")
    out["asset_identifier"] = ident.path if ident is not None else None
    out["meters_per_unit"] = UsdGeom.GetStageMetersPerUnit(stage)
    out["composition_errors"] = composition_errors(stage)
    out["validation"] = validate_stage(path)
    out["layers"] = sorted(os.path.basename(layer.identifier) for layer in stage.GetUsedLayers())
    custom = prim.GetCustomData()
    folder = os.path.dirname(path)
    thumb = custom.get("thumbnail")
    out["thumbnail"] = thumb.path if thumb is not None else None
    out["thumbnail_exists"] = bool(thumb) and os.path.isfile(os.path.join(folder, thumb.path))
    frames = custom.get("turntable") or []
    out["turntable"] = [f.path for f in frames]
    out["turntable_exist"] = all(os.path.isfile(os.path.join(folder, f.path)) for f in frames)
    vset = prim.GetVariantSets().GetVariantSet("LOD") if prim.GetVariantSets().HasVariantSet("LOD") else None
    if vset is not None:
        out["lod"] = []
        for name in vset.GetVariantNames():
            vset.SetVariantSelection(name)
            out["lod"].append(dict(mesh_counts(stage, prim), variant=name))
        vset.SetVariantSelection(vset.GetVariantNames()[0])
    else:
        out["mesh"] = mesh_counts(stage, prim)
    return out


def main(outdir: str) -> dict:
    lib_path = os.path.join(outdir, "library.usda")
    result: dict = {"library": {"opened": False}, "assets": {}}
    lib = Usd.Stage.Open(lib_path)
    if lib is not None:
        root = lib.GetDefaultPrim()
        children = {}
        for child in root.GetChildren():
            counts = mesh_counts(lib, child)
            children[child.GetName()] = {
                "kind": Usd.ModelAPI(child).GetKind(),
                "has_reference": child.HasAuthoredReferences(),
                "meshes": counts["meshes"], "faces": counts["faces"],
                "scale": float(UsdGeom.XformCommonAPI(child).GetXformVectors(
                    Usd.TimeCode.Default())[2][0]),
            }
        result["library"] = {
            "opened": True, "default_prim": root.GetName(), "kind": Usd.ModelAPI(root).GetKind(),
            "children": children, "composition_errors": composition_errors(lib),
            "layers": len(lib.GetUsedLayers()),
            "validation": validate_stage(lib_path),
        }
    assets_dir = os.path.join(outdir, "assets")
    for name in sorted(os.listdir(assets_dir)) if os.path.isdir(assets_dir) else []:
        path = os.path.join(assets_dir, name, name + ".usda")
        if os.path.isfile(path):
            result["assets"][name] = check_asset(path)
    return result


if __name__ == "__main__":
    json.dump(main(sys.argv[1]), sys.stdout, indent=1, default=str)
    sys.stdout.write("\n")
