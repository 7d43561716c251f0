"""`mesh.convert` through the daemon: OBJ → PLY → STL → OBJ on shared meshes, each file reopened
with an independent reader and compared; and conversion to arrays (no `output`)."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

import tessd
from daemon_util import read_mesh, read_stl, triangle_soup
from tessd import arrays_to_mesh, mesh_to_arrays

MESHES = ["spot_triangulated.obj", "spot_control_mesh.obj", "fandisk.obj", "suzanne.obj",
          "stanford_bunny.obj", "double_torus.off", "mpi_polygons.off", "bun_zipper.ply"]


@pytest.fixture(scope="module")
def client(daemon):
    with tessd.Client(daemon.socket, timeout=120) as c:
        yield c


def f32(values):
    return np.asarray(values, dtype=np.float32)


def assert_same_polygons(got, expected, what):
    gp, gf = got
    ep, ef = expected
    assert len(gf) == len(ef), "%s: %d faces, expected %d" % (what, len(gf), len(ef))
    assert gf == ef, "%s: faces differ (first: %r vs %r)" % (
        what, next((a, b) for a, b in zip(gf, ef) if a != b), None)
    assert f32(gp).shape == f32(ep).shape, what
    assert np.array_equal(f32(gp), f32(ep)), "%s: positions differ" % what


def soup_key(tris):
    """Triangles as float32 corner tuples, for an order-insensitive comparison."""
    return sorted(tuple(f32(t).ravel().tolist()) for t in tris)


@pytest.mark.parametrize("name", MESHES)
def test_obj_ply_stl_obj_chain(client, shared_data, tmp_path, name):
    source = shared_data / "mesh" / name
    original = read_mesh(source)
    ply, stl, obj = tmp_path / "a.ply", tmp_path / "b.stl", tmp_path / "c.obj"

    result, _ = client.call("mesh.convert", {"input": str(source), "output": str(ply)})
    assert result["output"] == str(ply) and result["faces"] == len(original[1])
    split = result["written"]["split_vertices"]
    if split == 0:
        assert_same_polygons(read_mesh(ply), original, "%s → PLY" % name)
    else:
        # A vertex with several UVs or normals became one vertex per value (PLY holds one per
        # vertex): the mesh's own vertices come first, the copies after, every face corner on
        # the same position.
        got = read_mesh(ply)
        n = len(original[0])
        assert len(got[0]) == n + split == result["written"]["vertices"]
        assert np.array_equal(f32(got[0][:n]), f32(original[0])), name
        assert [len(f) for f in got[1]] == [len(f) for f in original[1]]
        corners = lambda m: f32([m[0][v] for f in m[1] for v in f])
        assert np.array_equal(corners(got), corners(original)), "%s → PLY corners" % name

    result, _ = client.call("mesh.convert", {"input": str(ply), "output": str(stl)})
    tris = read_stl(stl)
    expected_tris = triangle_soup(*original)
    assert len(tris) == len(expected_tris), "%s → STL: triangle count" % name
    # STL keeps the triangles in order: compare corner positions triangle by triangle
    # (a writer may rotate a triangle's corners, never change the set).
    got_corners = [sorted(tuple(c) for c in f32(t).tolist()) for t in tris]
    exp_corners = [sorted(tuple(c) for c in f32(t).tolist()) for t in expected_tris]
    assert got_corners == exp_corners, "%s → STL: triangles differ" % name

    result, _ = client.call("mesh.convert", {"input": str(stl), "output": str(obj)})
    back = read_mesh(obj)
    assert result["faces"] == len(expected_tris) == len(back[1])
    assert all(len(f) == 3 for f in back[1])
    assert soup_key(triangle_soup(*back)) == soup_key(expected_tris), "%s → STL → OBJ" % name
    # Each step wrote exactly its output and nothing else (no temporary files left).
    assert sorted(os.listdir(tmp_path)) == ["a.ply", "b.stl", "c.obj"]


@pytest.mark.parametrize("name", ["spot_triangulated.obj", "double_torus.off", "bun_zipper.ply"])
def test_convert_file_to_arrays(client, shared_data, name):
    positions, faces = read_mesh(shared_data / "mesh" / name)
    result, arrays = client.call("mesh.convert", {"input": str(shared_data / "mesh" / name)})
    mesh = arrays_to_mesh(arrays)
    assert result["vertices"] == mesh.vertex_count and result["faces"] == len(faces)
    assert mesh.faces() == faces
    assert np.array_equal(f32(mesh.positions), f32(positions))


def test_convert_arrays_to_arrays_is_identity(client):
    rng = np.random.default_rng(7)
    positions = rng.random((50, 3), dtype=np.float32)
    faces = [list(rng.choice(50, size=int(n), replace=False)) for n in rng.integers(3, 7, size=40)]
    sent = mesh_to_arrays(positions, faces)
    result, arrays = client.call("mesh.convert", arrays=sent)
    assert result == {"vertices": 50, "faces": 40, "dropped_attributes": []}
    for name in ("positions", "face_indices", "face_sizes"):
        assert arrays[name].dtype == sent[name].dtype, name
        assert np.array_equal(arrays[name], sent[name]), name


def test_convert_arrays_with_attributes(client):
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], dtype=np.float32)
    faces = np.array([0, 1, 2, 3, 1, 4, 2], dtype=np.uint32)
    sizes = np.array([4, 3], dtype=np.uint32)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32)
    uv_indices = np.array([0, 1, 2, 3, 0, 1, 2], dtype=np.uint32)
    normals = np.array([[0, 0, 1]] * 7, dtype=np.float32)  # per corner, no indices
    sent = mesh_to_arrays(positions, (faces, sizes), normals=normals, uvs=uvs, uv_indices=uv_indices,
                          crease_edges=[[1, 2]], crease_values=[2.5], face_groups=[0, 1])
    _, arrays = client.call("mesh.convert", {"group_names": ["a", "b"]}, arrays=sent)
    assert np.array_equal(arrays["positions"], positions)
    assert np.array_equal(arrays["face_indices"], faces)
    assert np.array_equal(arrays["face_sizes"], sizes)
    assert np.array_equal(arrays["uvs"], uvs) and np.array_equal(arrays["uv_indices"], uv_indices)
    # Per-corner normals come back indexed: the values per corner are the same.
    per_corner = arrays["normals"][arrays["normal_indices"]]
    assert np.array_equal(per_corner, normals)
    assert arrays["crease_edges"].tolist() == [[1, 2]] and arrays["crease_values"].tolist() == [2.5]
    assert arrays["face_groups"].tolist() == [0, 1]
    # Bare group indices: the missing names become group<i>; an index past the faces is refused.
    _, arrays = client.call("mesh.convert", {}, arrays=sent)
    assert arrays["face_groups"].tolist() == [0, 1]
    bad = dict(sent, face_groups=np.array([0, 4_000_000_000], dtype=np.uint32))
    with pytest.raises(tessd.TessdError) as e:
        client.call("mesh.convert", {}, arrays=bad)
    assert e.value.code == "invalid_mesh"


def test_convert_without_numpy_gives_raw_arrays(daemon, shared_data):
    with tessd.Client(daemon.socket, timeout=60, use_numpy=False) as c:
        _, arrays = c.call("mesh.convert", {"input": str(shared_data / "mesh" / "mpi_polygons.off")})
    assert isinstance(arrays["positions"], tessd.RawArray)
    mesh = arrays_to_mesh(arrays)
    positions, faces = read_mesh(shared_data / "mesh" / "mpi_polygons.off")
    assert mesh.faces() == faces
    assert np.array_equal(f32(mesh.positions_list()), f32(positions))


def grid_mesh(n):
    """An n × n grid of quads split into 2 n² triangles."""
    ys, xs = np.mgrid[0:n + 1, 0:n + 1].astype(np.float32)
    positions = np.stack([xs.ravel(), ys.ravel(), np.sin(xs.ravel() * 0.01)], axis=1)
    idx = np.arange((n + 1) * (n + 1), dtype=np.uint32).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    tris = np.empty((2 * n * n, 3), dtype=np.uint32)
    tris[0::2] = np.stack([a, b, c], axis=1)
    tris[1::2] = np.stack([a, c, d], axis=1)
    return positions, tris


def test_large_mesh_round_trip(client):
    """~5 M triangles (≈ 90 MB each way) as arrays through mesh.convert, checked exactly."""
    positions, tris = grid_mesh(1581)  # 4,999,122 triangles, 2.5 M vertices
    sent = {"positions": positions, "face_indices": tris}
    nbytes = positions.nbytes + tris.nbytes
    t = time.perf_counter()
    result, arrays = client.call("mesh.convert", arrays=sent)
    elapsed = time.perf_counter() - t
    assert result["faces"] == len(tris)
    assert np.array_equal(arrays["positions"], positions)
    assert np.array_equal(arrays["face_indices"], tris.ravel())
    assert np.all(arrays["face_sizes"] == 3)
    print("\n5M-triangle round trip: %.1f MB each way in %.2fs" % (nbytes / 1e6, elapsed))
