"""The CPU trim classifier (core/trim through the daemon's `trim.classify`) against OpenCASCADE's:
for every face of every shared part and of the OCP-built parts (ocp_parts.PARTS), 100 000 random (u, v) points in the
face's bounds are classified on / off by both. OCP's answer comes from `IntTools_FClass2d` (its
polygon of the pcurves); where the two disagree, OCP's exact `BRepClass_FaceClassifier` (on the
pcurves themselves) gives its final answer, and every remaining disagreement must lie within the
ε band: its (u, v) distance to the face's exact trim curves (the pcurves, sampled densely) at
most ε_uv, the parameter tolerance that ε = 0.01 mm gives on that face (paper 000, section 3.1).

Runs under OCP 7.9 (.venv-cad) and 8.0 (.venv-b123d); OCP's classification is spread over a
process pool (it costs ~20 µs a point from Python)."""

from __future__ import annotations

import math
import os
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import tessd
from tessd.brep import export_shape
from tessd.brep import ocp as brep_ocp

from OCP.BRepAdaptor import BRepAdaptor_Curve2d
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepTools import BRepTools
from OCP.gp import gp_Pnt2d
from OCP.IntTools import IntTools_FClass2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_IN, TopAbs_ON, TopAbs_OUT
from OCP.TopExp import TopExp_Explorer

from ocp_parts import PARTS
from tessd.brep.ocp_compat import TopTools_IndexedMapOfShape
from tessd.brep.ocp_compat import static
from test_brep_export import BREP_DIR, FILES

_write_brep = static(BRepTools, "Write")

EPS = 0.01  # ε, mm (the documents' units)
POINTS = 100_000
FACES_PER_REQUEST = 8
WORKERS = max(1, min(4, os.cpu_count() or 1))
# Samples per pcurve for the distance to the exact trims (their chord error is far below ε_uv).
CURVE_SAMPLES = 4000
# OCP's state for "on the boundary": a point OCP puts on a pcurve agrees with either answer.
OCP_IN, OCP_OUT, OCP_ON = 1, 0, 2


def document_face(face):
    """The face and mirror flag of the document's (u, v), as the exporter chose them."""
    work, _surf, mirror, _conv = brep_ocp.document_face(face)
    return work, mirror


def faces_of(shape):
    m = TopTools_IndexedMapOfShape()
    brep_ocp._map_shapes(shape, TopAbs_FACE, m)
    return [m.FindKey(i) for i in range(1, m.Extent() + 1)]


def random_points(bounds, seed):
    rng = np.random.default_rng(seed)
    u0, u1, v0, v1 = bounds
    return np.stack([rng.uniform(u0, u1, POINTS), rng.uniform(v0, v1, POINTS)], axis=1)


def trim_polyline(face):
    """Dense samples of every pcurve of `face` (segments as [n, 2, 2])."""
    segs = []
    exp = TopExp_Explorer(face, TopAbs_EDGE)
    while exp.More():
        c = BRepAdaptor_Curve2d(brep_ocp._edge(exp.Current()), face)
        t = np.linspace(c.FirstParameter(), c.LastParameter(), CURVE_SAMPLES)
        p = np.array([[c.Value(x).X(), c.Value(x).Y()] for x in t])
        segs.append(np.stack([p[:-1], p[1:]], axis=1))
        exp.Next()
    return np.concatenate(segs) if segs else np.zeros((0, 2, 2))


def distance_to(segs, p):
    a, b = segs[:, 0], segs[:, 1]
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0, 1)
    return float(np.min(np.linalg.norm(a + t[:, None] * d - p, axis=1)))


_SHAPES = {}


def _shape(path):
    """The shape the document of `path` numbers (sewn where the exporter sews)."""
    if path not in _SHAPES:
        _SHAPES[path] = brep_ocp.prepare(brep_ocp.read_file(path)).shape
    return _SHAPES[path]


def ocp_check(path, index, bounds, seed, ours, eps_uv):
    """One face, in a worker: OCP's classification of the face's points and the disagreements
    with `ours` (bytes of 0/1), each re-checked exactly and measured against the trims."""
    face, mirror = document_face(faces_of(_shape(path))[index])
    pts = random_points(bounds, seed)
    ocp_u = 2 * math.pi - pts[:, 0] if mirror else pts[:, 0]
    fast = IntTools_FClass2d(face, 1e-9)
    state = np.empty(POINTS, np.int8)
    for i, (u, v) in enumerate(zip(ocp_u.tolist(), pts[:, 1].tolist())):
        s = fast.Perform(gp_Pnt2d(u, v))
        state[i] = OCP_IN if s == TopAbs_IN else OCP_OUT if s == TopAbs_OUT else OCP_ON
    ours = np.frombuffer(ours, np.uint8).astype(np.int8)
    suspects = np.nonzero((state != OCP_ON) & (state != ours))[0]
    exact = BRepClass_FaceClassifier()
    segs = None
    polygon_errors, worst, outside = 0, 0.0, []
    for i in suspects.tolist():
        exact.Perform(face, gp_Pnt2d(float(ocp_u[i]), float(pts[i, 1])), 1e-9)
        s = exact.State()
        if s == TopAbs_ON or (s == TopAbs_IN) == bool(ours[i]):
            polygon_errors += 1  # FClass2d's polygon was wrong, the exact classifier agrees
            continue
        if segs is None:
            segs = trim_polyline(face)
        d = distance_to(segs, np.array([ocp_u[i], pts[i, 1]]))
        worst = max(worst, d / eps_uv)
        if d > eps_uv:
            outside.append((float(pts[i, 0]), float(pts[i, 1]), d))
    return {
        "on": int((state == OCP_IN).sum()),
        "fast_disagree": int(len(suspects)),
        "polygon_errors": polygon_errors,
        "disagree": int(len(suspects)) - polygon_errors,
        "worst_over_eps": worst,
        "outside": outside[:5],
        "outside_count": len(outside),
    }


@pytest.fixture(scope="module")
def pool():
    with ProcessPoolExecutor(WORKERS) as ex:
        yield ex


def check_part(daemon, pool, doc, path, label, eps=EPS, expect_failures=False):
    """Classifies every face of `doc` with tessd at `eps` and with OCP, holding the disagreements
    to the band of ε = EPS (`expect_failures`: a negative control, which must break it)."""
    faces = doc["faces"]
    results = []
    with tessd.Client(daemon.socket, timeout=600) as c:
        for start in range(0, len(faces), FACES_PER_REQUEST):
            chunk = faces[start:start + FACES_PER_REQUEST]
            uv = np.stack([random_points(f["bounds"], f["id"]) for f in chunk])
            res, arrays = c.call("trim.classify", {"brep": doc, "faces": [f["id"] for f in chunk],
                                                    "tolerance": eps}, arrays={"uv": uv})
            on = np.asarray(arrays["on"]).reshape(len(chunk), POINTS)
            assert res["points"] == len(chunk) * POINTS
            for k, (f, rep) in enumerate(zip(chunk, res["faces"])):
                assert rep["id"] == f["id"]
                results.append((f, rep, pool.submit(ocp_check, path, start + k, f["bounds"], f["id"],
                                                    on[k].astype(np.uint8).tobytes(),
                                                    rep["eps_uv"] * EPS / eps)))
    total = {"points": 0, "fast_disagree": 0, "polygon_errors": 0, "disagree": 0, "worst": 0.0}
    failures = []
    for f, rep, fut in results:
        r = fut.result()
        total["points"] += POINTS
        total["fast_disagree"] += r["fast_disagree"]
        total["polygon_errors"] += r["polygon_errors"]
        total["disagree"] += r["disagree"]
        total["worst"] = max(total["worst"], r["worst_over_eps"])
        if r["outside_count"]:
            failures.append(f"face {f['id']}: {r['outside_count']} disagreements outside the ε band "
                            f"(ε_uv {rep['eps_uv']:.3g}), e.g. (u, v, distance) {r['outside']}")
    print(f"{label}: {len(faces)} faces, {total['points']} points, {total['fast_disagree']} "
          f"disagreements with IntTools_FClass2d, {total['polygon_errors']} of them its polygon's "
          f"(BRepClass_FaceClassifier agrees with us), {total['disagree']} left, the farthest at "
          f"{total['worst']:.2f} ε_uv from the trims")
    if expect_failures:
        assert failures, f"{label}: a structure at ε = {eps} stayed within the band of ε = {EPS}"
    else:
        assert not failures, f"{label}:\n" + "\n".join(failures)
    return total


@pytest.mark.parametrize("name", FILES)
def test_shared_part_classification(daemon, pool, name):
    path = str(BREP_DIR / name)
    doc = brep_ocp.export_topods(brep_ocp.read_file(path), source=name)
    check_part(daemon, pool, doc, path, name)


@pytest.mark.parametrize("name", sorted(PARTS))
def test_built_part_classification(daemon, pool, name, tmp_path):
    path = str(tmp_path / f"{name}.brep")
    assert _write_brep(PARTS[name](), path)
    doc = export_shape(brep_ocp.read_file(path), source=name)
    check_part(daemon, pool, doc, path, name)


@pytest.mark.parametrize("name", ["revolved", "island"])
def test_a_coarse_structure_breaks_the_band(daemon, pool, name, tmp_path):
    """The comparison can fail: trims approximated at ε = 2 mm disagree with OCP outside the
    0.01 mm band."""
    path = str(tmp_path / f"{name}.brep")
    assert _write_brep(PARTS[name](), path)
    doc = export_shape(brep_ocp.read_file(path), source=name)
    check_part(daemon, pool, doc, path, f"{name} at ε = 2 mm", eps=2.0, expect_failures=True)


def test_bad_points_are_refused(daemon):
    doc = export_shape(PARTS["island"](), source="island")
    fid = doc["faces"][0]["id"]
    uv = np.zeros((1, 3, 2))
    uv[0, 2, 1] = np.nan
    with tessd.Client(daemon.socket, timeout=60) as c:
        with pytest.raises(tessd.TessdError) as e:
            c.call("trim.classify", {"brep": doc, "faces": [fid], "tolerance": EPS}, arrays={"uv": uv})
        assert e.value.code == "invalid_brep" and f"point 2 of face {fid}" in e.value.message
        with pytest.raises(tessd.TessdError) as e:
            c.call("trim.classify", {"brep": doc, "faces": [fid, fid], "tolerance": EPS},
                   arrays={"uv": uv})
        assert e.value.code == "invalid_request" and "[2, points, 2]" in e.value.message
        with pytest.raises(tessd.TessdError) as e:
            c.call("trim.classify", {"brep": doc, "faces": [99999], "tolerance": EPS}, arrays={"uv": uv})
        assert "no face with id 99999" in e.value.message
        # The daemon is still up and answers a good request.
        res, arrays = c.call("trim.classify", {"brep": doc, "faces": [fid], "tolerance": "0.01mm"},
                             arrays={"uv": np.zeros((1, 1, 2))})
        assert res["points"] == 1 and np.asarray(arrays["on"]).shape == (1, 1)
