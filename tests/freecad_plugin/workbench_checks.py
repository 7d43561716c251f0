"""Independent checks for the workbench's tests: mesh topology and area from FreeCAD's own
Mesh, the tessd CLI on the same mesh, USD stages re-read by usd-core (in the project's .venv,
a separate Python: FreeCAD's has no `pxr`), PNG pixels decoded by tests/png_decode.py."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
#: The Python with usd-core (scripts/setup.sh's .venv).
USD_PYTHON = Path(os.environ.get("TESSD_USD_PYTHON", REPO / ".venv" / "bin" / "python"))
#: Background colour of tessd's renders (docs/protocol.md, "render", Images).
BACKGROUND = (224, 224, 224)


def tessd_bin():
    """$TESSD_BIN, else target/release/tessd (must exist)."""
    path = Path(os.environ.get("TESSD_BIN", REPO / "target" / "release" / "tessd"))
    if not path.is_file():
        raise FileNotFoundError("no tessd binary at %s (set TESSD_BIN)" % path)
    return path


def mesh_arrays(mesh):
    """(positions f64 [V, 3], triangles int64 [F, 3]) of a Mesh.Mesh, as FreeCAD holds it."""
    points, facets = mesh.Topology
    return (np.array([(p.x, p.y, p.z) for p in points], dtype=np.float64).reshape(-1, 3),
            np.array(facets, dtype=np.int64).reshape(-1, 3))


def edge_uses(triangles):
    """How many triangles use each undirected edge."""
    t = np.asarray(triangles).reshape(-1, 3)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    return np.unique(edges, axis=0, return_counts=True)[1]


def segment_cover(mesh):
    """Per facet, how many segments hold it."""
    cover = np.zeros(mesh.CountFacets, dtype=np.int64)
    for s in range(mesh.countSegments()):
        cover[np.asarray(mesh.getSegment(s), dtype=np.int64)] += 1
    return cover


def write_obj(path, mesh):
    """The mesh as OBJ: f32 positions with 9 significant digits (they read back exactly), a
    group per segment when it has segments (what the workbench sends as face groups)."""
    positions, triangles = mesh_arrays(mesh)
    groups = None
    if mesh.countSegments():
        groups = np.full(len(triangles), -1)
        for s in range(mesh.countSegments()):
            groups[np.asarray(mesh.getSegment(s), dtype=np.int64)] = s
    with open(path, "w") as f:
        for p in positions.astype(np.float32).tolist():
            f.write("v %.9g %.9g %.9g\n" % tuple(p))
        current = None
        for k, t in enumerate(triangles.tolist()):
            if groups is not None and groups[k] != current:
                current = groups[k]
                f.write("g group%d\n" % current)
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def cli(*args):
    """Runs the tessd CLI; returns (status, stdout, stderr)."""
    p = subprocess.run([str(tessd_bin())] + [str(a) for a in args], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def cli_json(*args):
    """The result JSON of a CLI verb run with --json (fails on a non-zero status)."""
    status, out, err = cli(*(args + ("--json",)))
    if status != 0:
        raise AssertionError("tessd %s failed (%d): %s" % (" ".join(map(str, args)), status, err))
    return json.loads(out)


_USD_SCRIPT = r"""
import json, sys
from pxr import Usd, UsdGeom, Gf
stage = Usd.Stage.Open(sys.argv[1])
out = {"defaultPrim": stage.GetDefaultPrim().GetName(),
       "metersPerUnit": UsdGeom.GetStageMetersPerUnit(stage),
       "upAxis": str(UsdGeom.GetStageUpAxis(stage)), "prims": {}}
cache = UsdGeom.XformCache(Usd.TimeCode.Default())
for prim in stage.Traverse():
    info = {"type": str(prim.GetTypeName())}
    if prim.IsA(UsdGeom.Xformable):
        m = cache.GetLocalToWorldTransform(prim)
        info["world"] = [[m[r][c] for c in range(4)] for r in range(4)]
    if prim.IsA(UsdGeom.Mesh):
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get()
        counts = mesh.GetFaceVertexCountsAttr().Get()
        info["points"] = len(points)
        info["faces"] = len(counts)
        world = [cache.GetLocalToWorldTransform(prim).Transform(Gf.Vec3d(p)) for p in points]
        info["world_min"] = [min(p[k] for p in world) for k in range(3)]
        info["world_max"] = [max(p[k] for p in world) for k in range(3)]
        subsets = UsdGeom.Subset.GetAllGeomSubsets(mesh)
        info["subsets"] = len(subsets)
        info["subset_names"] = [s.GetPrim().GetName() for s in subsets]
        info["subset_faces"] = sum(len(s.GetIndicesAttr().Get()) for s in subsets)
        valid, why = UsdGeom.Subset.ValidateFamily(mesh, UsdGeom.Tokens.face, "materialBind")
        info["family_valid"] = bool(valid)
        info["family_why"] = why
        pv = UsdGeom.PrimvarsAPI(prim).GetPrimvar("displayColor")
        if pv and pv.HasValue():
            info["displayColor"] = {"interpolation": str(pv.GetInterpolation()),
                                    "count": len(pv.Get()),
                                    "first": list(pv.Get()[0])}
        info["customData"] = {k: v for k, v in prim.GetCustomData().items() if k == "freecadName"}
    vsets = prim.GetVariantSets()
    if vsets.GetNames():
        info["variantSets"] = {n: vsets.GetVariantSet(n).GetVariantNames() for n in vsets.GetNames()}
    out["prims"][str(prim.GetPath())] = info
print(json.dumps(out))
"""


def usd_report(path):
    """What usd-core reads in the stage at ``path``: per prim its type, world matrix (USD's
    row-vector convention), and for meshes the counts, world bounds of the points, GeomSubsets
    (and whether they validate as a materialBind family), displayColor; variant sets."""
    if not USD_PYTHON.is_file():
        raise FileNotFoundError("no usd-core Python at %s (scripts/setup.sh makes .venv; or set "
                                "TESSD_USD_PYTHON)" % USD_PYTHON)
    p = subprocess.run([str(USD_PYTHON), "-c", _USD_SCRIPT, str(path)], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, timeout=300)
    if p.returncode != 0:
        raise AssertionError("usd-core could not read %s:\n%s" % (path, p.stderr))
    return json.loads(p.stdout)


def read_png(path):
    """An RGBA PNG as a uint8 array [H, W, 4] (tests/png_decode.py)."""
    sys.path.insert(0, str(REPO / "tests"))
    import png_decode

    return png_decode.read_png(Path(path))


def coverage(image):
    """Share of the pixels that are not the background."""
    return float(np.any(image[:, :, :3] != np.array(BACKGROUND, dtype=np.uint8), axis=2).mean())
