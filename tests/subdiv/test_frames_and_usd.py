"""The `subdivide` op beyond one mesh: animation frames (one topology phase, one apply per
frame), USD output as time samples or as a cage with `subdivisionScheme` (re-opened with
usd-core), the other schemes through the daemon, and bad input (named errors, daemon stays up).

The frame checks use an independent fact rather than our own output: subdivision is affine
invariant (every stencil row sums to 1), so refining an affinely moved cage must give the
refined rest pose moved by the same map.
"""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
from pxr import Usd, UsdGeom

import locate
import tessd
from tessd import TessdError
from usd_checks import validate_stage

CAGE = locate.shared_data() / "mesh" / "spot_control_mesh.obj"


def read_obj(path):
    verts, faces = [], []
    for line in open(path):
        t = line.split()
        if t and t[0] == "v":
            verts.append([float(x) for x in t[1:4]])
        elif t and t[0] == "f":
            faces.append([int(x.split("/")[0]) - 1 for x in t[1:]])
    return np.array(verts, dtype=np.float32), faces


def affine(k: int):
    """A different rotation + scale + translation per frame."""
    a = 0.3 * k
    rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    return rot * (1.0 + 0.1 * k), np.array([0.5 * k, -0.25 * k, 0.1 * k])


def call(daemon, params, arrays=None):
    with tessd.Client(daemon.socket, timeout=300) as c:
        return c.call("subdivide", params, arrays)


def cage_arrays(extra=None):
    pos, faces = read_obj(CAGE)
    arrays = tessd.mesh_to_arrays(pos, faces)
    arrays.update(extra or {})
    return pos, arrays


@pytest.mark.parametrize("gpu", [False, True])
def test_frames_are_the_moved_rest_pose(daemon, gpu):
    pos, arrays = cage_arrays()
    maps = [affine(k) for k in range(5)]
    frames = np.stack([(pos @ m.T + t).astype(np.float32) for m, t in maps])
    arrays["frames"] = frames
    result, out = call(daemon, {"levels": 3, "gpu": gpu}, arrays)
    assert result["frames"] == 5 and result["apply_ms_per_frame"] >= 0
    rest = np.asarray(out["positions"], dtype=np.float64)
    got = np.asarray(out["frame_positions"], dtype=np.float64)
    assert got.shape == (5, rest.shape[0], 3)
    for k, (m, t) in enumerate(maps):
        want = rest @ m.T + t
        size = np.ptp(want, axis=0).max()
        err = np.abs(got[k] - want).max()
        assert err <= 1e-5 * size, f"frame {k}: off by {err} of {size}"
    # Topology once: the faces are those of the rest pose.
    assert len(out["face_sizes"]) == 4 ** 2 * 732


def test_frames_as_usd_time_samples(daemon, tmp_path):
    pos, arrays = cage_arrays()
    frames = np.stack([pos + np.float32(0.1 * k) for k in range(3)])
    arrays["frames"] = frames
    _, direct = call(daemon, {"levels": 2}, dict(arrays))
    usd = tmp_path / "anim.usda"
    result, _ = call(daemon, {"levels": 2, "output": str(usd), "name": "spot"}, arrays)
    assert result["output"] == str(usd)
    assert validate_stage(usd) == []
    stage = Usd.Stage.Open(str(usd))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1, 3)
    points = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/spot")).GetPointsAttr()
    for k in range(3):
        got = np.array(points.Get(k + 1), dtype=np.float64)
        assert np.abs(got - direct["frame_positions"][k]).max() < 1e-6


def test_cage_output_keeps_scheme_rules_and_creases(daemon, tmp_path):
    pos, faces = read_obj(CAGE)
    creases = {"crease_edges": np.array([faces[0][:2]], dtype=np.uint32),
               "crease_values": np.array([2.5], dtype=np.float32)}
    arrays = tessd.mesh_to_arrays(pos, faces, **creases)
    usd = tmp_path / "cage.usda"
    result, _ = call(daemon, {"usd": "cage", "output": str(usd), "levels": 3,
                              "boundary": "edge-and-corner", "uv_interpolation": "linear",
                              "name": "cage"}, arrays)
    assert result["usd"] == "cage"
    assert validate_stage(usd) == []
    stage = Usd.Stage.Open(str(usd))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/cage"))
    assert mesh.GetSubdivisionSchemeAttr().Get() == "catmullClark"
    assert mesh.GetInterpolateBoundaryAttr().Get() == "edgeAndCorner"
    assert mesh.GetFaceVaryingLinearInterpolationAttr().Get() == "all"
    assert list(mesh.GetCreaseSharpnessesAttr().Get()) == [2.5]
    assert list(mesh.GetCreaseIndicesAttr().Get()) == faces[0][:2]
    assert np.abs(np.array(mesh.GetPointsAttr().Get()) - pos).max() == 0
    assert len(mesh.GetFaceVertexCountsAttr().Get()) == len(faces)


def test_cage_output_refuses_schemes_usd_cannot_name(daemon, tmp_path):
    pos, faces = read_obj(locate.shared_data() / "subdiv" / "loop_icosahedron_level0.obj")
    arrays = tessd.mesh_to_arrays(pos, faces)
    usd = tmp_path / "cage.usda"
    with pytest.raises(TessdError) as e:
        call(daemon, {"usd": "cage", "output": str(usd), "scheme": "sqrt3"}, arrays)
    assert e.value.code == "unsupported" and "sqrt3" in e.value.message
    assert not usd.exists()
    result, _ = call(daemon, {"usd": "cage", "output": str(usd), "scheme": "loop"}, arrays)
    stage = Usd.Stage.Open(str(usd))
    assert UsdGeom.Mesh(stage.GetPrimAtPath("/Root/cage")).GetSubdivisionSchemeAttr().Get() == "loop"


@pytest.mark.parametrize("scheme,faces_per_face", [
    ("loop", 4), ("butterfly", 4), ("sqrt3", 3), ("doo-sabin", None), ("bilinear", None)])
def test_every_scheme_through_the_daemon(daemon, scheme, faces_per_face):
    pos, faces = read_obj(locate.shared_data() / "subdiv" / "loop_icosahedron_level0.obj")
    result, out = call(daemon, {"scheme": scheme, "levels": 2}, tessd.mesh_to_arrays(pos, faces))
    assert result["scheme"] == scheme
    n = len(out["face_sizes"])
    if faces_per_face:
        assert n == len(faces) * faces_per_face ** 2
    else:
        assert n > 4 * len(faces)
    refined = np.asarray(out["positions"])
    assert np.isfinite(refined).all()
    if scheme == "butterfly":
        # Interpolating: every cage vertex is a vertex of the result.
        d = np.linalg.norm(refined[None, :, :] - pos[:, None, :], axis=2).min(axis=1)
        assert d.max() < 1e-6


BAD = [
    ("non-manifold edge", lambda p, f: (np.vstack([p, [[0, 0, 5]]]), f + [[f[0][0], f[0][1], len(p)]]),
     "invalid_mesh", "shared by 3 faces"),
    ("isolated vertex", lambda p, f: (np.vstack([p, [[9, 9, 9]]]), f),
     "invalid_mesh", "is isolated"),
    ("degenerate face", lambda p, f: (p, f[:-1] + [[f[-1][0], f[-1][0], f[-1][1]]]),
     "invalid_mesh", "degenerate"),
]


@pytest.mark.parametrize("what,make,code,words", BAD, ids=[b[0] for b in BAD])
def test_bad_cages_are_named_and_the_daemon_stays_up(daemon, what, make, code, words):
    pos, faces = read_obj(locate.shared_data() / "subdiv" / "loop_icosahedron_level0.obj")
    p, f = make(pos, faces)
    for scheme in ("catmull-clark", "loop"):
        with pytest.raises(TessdError) as e:
            call(daemon, {"scheme": scheme, "levels": 1}, tessd.mesh_to_arrays(np.asarray(p, np.float32), f))
        assert e.value.code == code and words in e.value.message, (what, e.value.message)
    assert call(daemon, {"levels": 1}, tessd.mesh_to_arrays(pos, faces))[0]["faces"] == 3 * len(faces)


def test_too_many_levels_and_bad_frames(daemon, tmp_path):
    pos, arrays = cage_arrays()
    with pytest.raises(TessdError) as e:
        call(daemon, {"levels": 10}, arrays)
    assert e.value.code == "too_large" and "bytes" in e.value.message
    bad = dict(arrays, frames=np.zeros((2, len(pos) - 1, 3), np.float32))
    with pytest.raises(TessdError) as e:
        call(daemon, {"levels": 1}, bad)
    assert e.value.code == "invalid_mesh"
    assert f"has {len(pos) - 1} vertices; the cage has {len(pos)}" in e.value.message
    nan = np.stack([pos, pos])
    nan[1, 7, 2] = np.nan
    with pytest.raises(TessdError) as e:
        call(daemon, {"levels": 1}, dict(arrays, frames=nan))
    assert "frame 1, vertex 7" in e.value.message
    out = tmp_path / "x.obj"
    with pytest.raises(TessdError) as e:
        call(daemon, {"levels": 1, "output": str(out)}, dict(arrays, frames=np.stack([pos])))
    assert e.value.code == "invalid_request" and ".usda" in e.value.message
    assert not out.exists()


def test_cli_frames_and_cage(tmp_path):
    pos, faces = read_obj(CAGE)
    frames = []
    for k in range(2):
        path = tmp_path / f"f{k}.obj"
        with open(path, "w") as f:
            for v in pos + np.float32(k):
                f.write("v %r %r %r\n" % tuple(float(x) for x in v))
            for face in faces:
                f.write("f " + " ".join(str(i + 1) for i in face) + "\n")
        frames.append(str(path))
    out = tmp_path / "anim.usda"
    run = subprocess.run([str(locate.tessd_bin()), "subdivide", str(CAGE), str(out), "--levels", "2",
                          "--frames", *frames], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    stage = Usd.Stage.Open(str(out))
    assert stage.GetEndTimeCode() == 2
    cage = tmp_path / "cage.usda"
    run = subprocess.run([str(locate.tessd_bin()), "subdivide", str(CAGE), str(cage), "--usd-cage"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "marked" in run.stdout
    stage = Usd.Stage.Open(str(cage))
    mesh = UsdGeom.Mesh(stage.GetDefaultPrim().GetChildren()[0])
    assert mesh.GetSubdivisionSchemeAttr().Get() == "catmullClark"
