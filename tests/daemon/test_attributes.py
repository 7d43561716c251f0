"""Generic attributes (`point:` / `corner:` / `face:` arrays) and `sharp_edges` through the real
daemon: simplify, lod (arrays, `return_arrays` with a .usda output reopened by usd-core),
subdivide and mesh.convert, and bad attribute arrays refused with `invalid_mesh` naming the
array while the daemon serves on.

The checks are analytic: with uniform weights and barycentre representatives an output vertex
is the plain mean of its cluster, which is exactly what a point attribute gets, so `point:x`
must equal the output's x; subdivision stencils are affine, so `point:x` must equal the refined
x; `face:id` must name a face whose corners moved onto the output face.
"""

from __future__ import annotations

import numpy as np
import pytest

import tessd
from tessd import TessdError


@pytest.fixture(scope="module")
def client(daemon):
    with tessd.Client(daemon.socket, timeout=120) as c:
        yield c


@pytest.fixture(scope="module")
def bunny(client, shared_data):
    """The Stanford bunny as arrays (read by the daemon itself)."""
    _, arrays = client.call("mesh.convert", {"input": str(shared_data / "mesh" / "stanford_bunny.obj")})
    return {k: np.asarray(arrays[k]) for k in ("positions", "face_indices", "face_sizes")}


def faces_of(arrays, prefix=""):
    idx = np.asarray(arrays[prefix + "face_indices"], dtype=np.int64)
    sizes = np.asarray(arrays[prefix + "face_sizes"], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    return [idx[s:s + n] for s, n in zip(starts.tolist(), sizes.tolist())]


def edge_set(faces):
    out = set()
    for f in faces:
        for a, b in zip(f, np.roll(f, -1)):
            out.add((min(int(a), int(b)), max(int(a), int(b))))
    return out


def with_attributes(mesh):
    """`mesh` plus point:x (1-D), corner:uvmap2 ([K, 2], constant), face:id (1-D) and
    sharp_edges (every edge crossing the plane x = middle)."""
    pos = mesh["positions"].astype(np.float32)
    k = len(mesh["face_indices"])
    f = len(mesh["face_sizes"])
    faces = faces_of(mesh)
    mid = float(pos[:, 0].min() + pos[:, 0].max()) / 2 + 1e-4
    sharp = sorted(e for e in edge_set(faces) if (pos[e[0], 0] - mid) * (pos[e[1], 0] - mid) < 0)
    out = dict(mesh)
    out["point:x"] = pos[:, 0].copy()
    out["corner:uvmap2"] = np.tile(np.array([[0.25, -2.0]], np.float32), (k, 1))
    out["face:id"] = np.arange(f, dtype=np.float32)
    out["sharp_edges"] = np.array(sharp, dtype=np.uint32).reshape(-1, 2)
    return out


def check_level(mesh, result, arrays, prefix=""):
    """The analytic checks of one simplified mesh (arrays named with `prefix`)."""
    pos = np.asarray(arrays[prefix + "positions"])
    x = np.asarray(arrays[prefix + "point:x"])
    assert x.shape == (len(pos),), "1-D in, 1-D out"
    assert np.abs(x - pos[:, 0]).max() <= 1e-5
    uv = np.asarray(arrays[prefix + "corner:uvmap2"])
    assert uv.shape == (len(arrays[prefix + "face_indices"]), 2)
    assert np.all(uv == np.array([0.25, -2.0], np.float32))
    ids = np.asarray(arrays[prefix + "face:id"])
    out_faces = faces_of(arrays, prefix)
    assert ids.shape == (len(out_faces),)
    assert np.all(ids == np.round(ids))
    in_faces = faces_of(mesh)
    in_pos = mesh["positions"]
    reach = result["max_displacement"] * (1 + 1e-6) + 1e-6
    for f in range(0, len(out_faces), max(1, len(out_faces) // 500)):
        src = in_faces[int(ids[f])]
        for v in out_faces[f]:
            d = np.linalg.norm(in_pos[src] - pos[v], axis=1).min()
            assert d <= reach, (f, v, d, reach)
    sharp = np.asarray(arrays[prefix + "sharp_edges"])
    assert sharp.ndim == 2 and sharp.shape[1] == 2 and len(sharp) > 0
    edges = edge_set(out_faces)
    assert all((min(a, b), max(a, b)) in edges for a, b in sharp.tolist())
    assert result["dropped_attributes"] == []


def test_simplify_carries_attributes(client, bunny):
    mesh = with_attributes(bunny)
    params = {"weighting": "uniform", "representative": "barycenter"}
    for goal in ({"method": "complexity", "target_vertices": "10%"},
                 {"method": "quality", "max_error": "1%"},
                 {"method": "grid", "cells": 24}):
        result, arrays = client.call("simplify", {**params, **goal}, arrays=mesh)
        check_level(mesh, result, arrays)


def test_lod_arrays_and_return_arrays_with_usda(client, bunny, tmp_path):
    from pxr import Usd, UsdGeom

    mesh = with_attributes(bunny)
    params = {"levels": ["30%", "5%"], "weighting": "uniform"}
    result, arrays = client.call("lod", params, arrays=mesh)
    for i, level in enumerate(result["levels"], start=1):
        check_level(mesh, level, arrays, "lod%d." % i)
    assert result["dropped_attributes"] == []

    out = tmp_path / "lods.usda"
    result2, arrays2 = client.call(
        "lod", {**params, "output": str(out), "lod_schema": "usdlod", "return_arrays": True},
        arrays=mesh)
    assert result2["output"] == str(out)
    assert result2["dropped_attributes"] == ["sharp_edges"]
    for i, level in enumerate(result2["levels"], start=1):
        check_level(mesh, level, arrays2, "lod%d." % i)
        assert np.array_equal(arrays2["lod%d.positions" % i], arrays["lod%d.positions" % i])

    stage = Usd.Stage.Open(str(out))
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == 3
    for prim in meshes:
        geom = UsdGeom.Mesh(prim)
        points = len(geom.GetPointsAttr().Get())
        counts = geom.GetFaceVertexCountsAttr().Get()
        api = UsdGeom.PrimvarsAPI(prim)
        expect = {"x": ("vertex", points, "float[]"),
                  "uvmap2": ("faceVarying", int(sum(counts)), "float2[]"),
                  "id": ("uniform", len(counts), "float[]")}
        for name, (interp, n, type_name) in expect.items():
            pv = api.GetPrimvar(name)
            assert pv and pv.IsDefined(), (prim.GetPath(), name)
            assert pv.GetInterpolation() == interp
            assert str(pv.GetTypeName()) == type_name
            assert len(pv.Get()) == n, (prim.GetPath(), name)
        # point:x = x, read back from the stage.
        xs = np.asarray(api.GetPrimvar("x").Get())
        pts = np.asarray(geom.GetPointsAttr().Get())
        assert np.abs(xs - pts[:, 0]).max() <= 1e-5


def icosphere(levels=1):
    """An icosphere (triangles, closed) from the icosahedron, split `levels` times."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(levels):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = verts[a] + verts[b]
                verts.append(p / np.linalg.norm(p))
                mid[key] = len(verts) - 1
            return mid[key]

        f = [g for a, b, c in f for g in ((a, m(a, b), m(c, a)), (b, m(b, c), m(a, b)),
                                           (c, m(c, a), m(b, c)), (m(a, b), m(b, c), m(c, a)))]
    faces = np.array(f, dtype=np.uint32)
    return {"positions": np.array(verts, np.float32), "face_indices": faces.reshape(-1),
            "face_sizes": np.full(len(faces), 3, np.uint32)}


def test_subdivide_carries_attributes(client):
    mesh = with_attributes(icosphere(1))
    n_sharp = len(mesh["sharp_edges"])
    for scheme, levels in (("loop", 2), ("catmull-clark", 1), ("bilinear", 2)):
        result, arrays = client.call("subdivide", {"scheme": scheme, "levels": levels}, arrays=mesh)
        pos = arrays["positions"]
        x = np.asarray(arrays["point:x"])
        assert x.shape == (len(pos),)
        assert np.abs(x - pos[:, 0]).max() <= 1e-5, scheme
        ids = np.asarray(arrays["face:id"])
        assert ids.shape == (len(arrays["face_sizes"]),)
        assert len(arrays["sharp_edges"]) == n_sharp << levels, scheme
        edges = edge_set(faces_of(arrays))
        assert all((min(a, b), max(a, b)) in edges for a, b in arrays["sharp_edges"].tolist())
        if scheme == "loop":
            # Loop has no face-varying refinement: the corner attribute is dropped, said so.
            assert "corner:uvmap2" not in arrays
            assert result["dropped_attributes"] == ["corner:uvmap2"]
        else:
            uv = np.asarray(arrays["corner:uvmap2"])
            assert uv.shape == (len(arrays["face_indices"]), 2)
            assert np.abs(uv - np.array([0.25, -2.0])).max() <= 1e-6
            assert result["dropped_attributes"] == []
        # Every refined face lies inside its parent: on the sphere, the cage face whose
        # centroid direction is nearest its own is the one `face:id` names.
        cage = mesh["positions"][np.array(faces_of(mesh))].mean(axis=1)
        cage /= np.linalg.norm(cage, axis=1)[:, None]
        for f, face in enumerate(faces_of(arrays)):
            c = pos[face].mean(axis=0)
            assert int(np.argmax(cage @ c)) == int(ids[f]), (scheme, f)
    result, arrays = client.call("subdivide", {"scheme": "doo-sabin"}, arrays=mesh)
    assert "sharp_edges" not in arrays and "point:x" in arrays and "face:id" in arrays
    assert result["dropped_attributes"] == ["sharp_edges", "corner:uvmap2"]


def test_convert_round_trip_and_files(client, tmp_path):
    from pxr import Usd, UsdGeom

    mesh = with_attributes(icosphere(2))
    mesh["point:rgb"] = np.random.default_rng(1).random((len(mesh["positions"]), 3), np.float32)
    mesh["face:wide"] = np.random.default_rng(2).random((len(mesh["face_sizes"]), 5), np.float32)
    mesh["point:col1"] = mesh["point:x"].reshape(-1, 1).copy()
    result, arrays = client.call("mesh.convert", {}, arrays=mesh)
    assert result["dropped_attributes"] == []
    for name in ("point:x", "point:rgb", "point:col1", "corner:uvmap2", "face:id", "face:wide",
                 "sharp_edges"):
        assert arrays[name].shape == mesh[name].shape, name
        assert np.array_equal(arrays[name], mesh[name]), name

    result, _ = client.call("mesh.convert", {"output": str(tmp_path / "m.obj")}, arrays=mesh)
    assert result["dropped_attributes"] == [
        "sharp_edges", "point:x", "corner:uvmap2", "face:id", "point:rgb", "face:wide",
        "point:col1"]
    usda = tmp_path / "m.usda"
    result, _ = client.call("mesh.convert", {"output": str(usda)}, arrays=mesh)
    assert result["dropped_attributes"] == ["sharp_edges"]
    stage = Usd.Stage.Open(str(usda))
    prim = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    api = UsdGeom.PrimvarsAPI(prim)
    wide = api.GetPrimvar("wide")
    assert wide.GetInterpolation() == "uniform" and wide.GetElementSize() == 5
    assert np.allclose(np.asarray(wide.Get()).reshape(-1, 5), mesh["face:wide"])
    rgb = api.GetPrimvar("rgb")
    assert str(rgb.GetTypeName()) == "float3[]" and rgb.GetInterpolation() == "vertex"
    assert np.allclose(np.asarray(rgb.Get()), mesh["point:rgb"])
    assert api.GetPrimvar("col1").GetInterpolation() == "vertex"


@pytest.mark.parametrize("case", ["nan", "rows", "dtype", "sharp", "components", "empty_name"])
def test_bad_attributes_are_refused_by_name(client, case):
    mesh = with_attributes(icosphere(1))
    v = len(mesh["positions"])
    if case == "nan":
        mesh["point:x"][7] = np.nan
        expect = "point:x row 7 is NaN"
    elif case == "rows":
        mesh["point:weight"] = np.zeros(v - 2, np.float32)
        expect = 'array "point:weight" has %d rows; the mesh has %d vertices' % (v - 2, v)
    elif case == "dtype":
        mesh["face:id"] = mesh["face:id"].astype(np.float64)
        expect = '"face:id" has dtype f64; expected f32'
    elif case == "sharp":
        edges = mesh["sharp_edges"].copy()
        edges[3, 1] = 99
        mesh["sharp_edges"] = edges
        expect = "sharp_edges[3] names vertex 99; the mesh has %d" % v
    elif case == "components":
        mesh["corner:wide"] = np.zeros((len(mesh["face_indices"]), 65), np.float32)
        expect = '"corner:wide" has 65 components'
    else:
        mesh["point:"] = np.zeros(v, np.float32)
        expect = '"point:" needs a name'
    for op, params in (("simplify", {"method": "grid", "cells": 4}), ("subdivide", {}),
                       ("mesh.convert", {})):
        with pytest.raises(TessdError) as err:
            client.call(op, params, arrays=mesh)
        assert err.value.code == "invalid_mesh", (op, err.value)
        assert expect in err.value.message, (op, err.value.message)
    assert client.call("ping", {})[0]["pong"] is True
