"""`tessd view` (issue 35) in real windows on the tests' own Xvfb with lavapipe: scripted
screenshots against `tessd render`, `.tsc` streaming (bytes read, frames while refining, the
session kept), real key presses through xdotool (W, +, F12, Esc), `--frames`, and the errors
(no display, bad inputs). Small sizes and short scripts: the whole file runs in well under a
minute on two cores."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

from view_util import checked, face_ids, run_tessd, run_view
from png_decode import read_png


# ---------------------------------------------------------------------------------------------
# 1. A scripted screenshot equals `tessd render` with the same camera, size and shading


def _compare_with_render(xvfb, tmp_path, inp, size, eye, target, up, fov, extra=()):
    """Screenshot + face ids of `tessd view` and of `tessd render` for one camera: (view ids,
    render ids, view colour, render colour)."""
    shot, shot_ids = tmp_path / "view.png", tmp_path / "view_ids.png"
    script = [
        {"camera": {"eye": eye, "target": target, "up": up, "fov": fov}},
        {"wait": 1},
        {"screenshot": str(shot), "face_ids": str(shot_ids)},
        {"quit": True},
    ]
    w, h = size
    checked(run_view(xvfb, [inp, "--size", f"{w}x{h}", *extra], script, tmp_path))
    ref, ref_ids = tmp_path / "render.png", tmp_path / "render_ids.png"
    csv = lambda v: ",".join(map(str, v))  # noqa: E731
    run_tessd("render", inp, ref, "--size", f"{w}x{h}", "--eye", csv(eye), "--target",
              csv(target), "--up", csv(up), "--fov", fov, "--face-ids", ref_ids, *extra)
    a, b = face_ids(shot_ids), face_ids(ref_ids)
    assert a.shape == b.shape == (h, w)
    return a, b, read_png(shot).astype(int), read_png(ref).astype(int)


def _agreement(a, b):
    covered = (a > 0) | (b > 0)
    return covered.sum(), float((a[covered] == b[covered]).mean())


def test_mesh_screenshot_matches_render(xvfb, tmp_path, shared_data):
    # A mesh without groups has face id 1 everywhere (Scene::from_mesh): fandisk is written with
    # one group per face so that the ids tell every triangle apart.
    mesh = tmp_path / "fandisk_faces.obj"
    lines, n = [], 0
    for line in (shared_data / "mesh" / "fandisk.obj").read_text().splitlines():
        if line.startswith("f "):
            lines.append(f"g f{n}")
            n += 1
        if line.startswith(("v ", "f ")):
            lines.append(line)
    mesh.write_text("\n".join(lines) + "\n")
    a, b, ca, cb = _compare_with_render(xvfb, tmp_path, mesh, (320, 240), [10, 7, 5],
                                        [2.4, 15.2, -1.3], [0, 0, 1], 35)
    covered, agree = _agreement(a, b)
    assert covered > 0.1 * a.size, covered
    assert len(np.unique(a)) > 1000, "the ids must tell the triangles apart"
    assert agree >= 0.995, f"face ids agree on {agree:.4%} of {covered} covered pixels"
    close = (np.abs(ca - cb).max(axis=-1) <= 8).mean()
    assert close >= 0.99, f"colours agree on {close:.2%} of the pixels"


def test_brep_screenshot_matches_render_with_object_cracks(xvfb, tmp_path, shared_data):
    part = shared_data / "brep" / "freecad_drilling1_body.brep"  # 58 faces
    a, b, ca, cb = _compare_with_render(
        xvfb, tmp_path, part, (240, 180), [324.47, -317.49, 343.57], [0.9, 6.07, 20.0],
        [0, 0, 1], 30, extra=("--cracks", "object"))
    covered, agree = _agreement(a, b)
    assert covered > 0.1 * a.size, covered
    assert len(np.unique(a)) > 20, np.unique(a)
    assert agree >= 0.995, f"face ids agree on {agree:.4%} of {covered} covered pixels"
    close = (np.abs(ca - cb).max(axis=-1) <= 8).mean()
    assert close >= 0.99, f"colours agree on {close:.2%} of the pixels"


# ---------------------------------------------------------------------------------------------
# 2. Compressed meshes: refinement for the camera, in the background, in one session

# fandisk Loop-subdivided twice (207 k triangles), its y = 12.6 end looked at from near and far
TARGET = [2.2, 12.61, -2.2]
NEAR_EYE = [2.5, 11.9, -1.9]
FAR_EYE = [TARGET[i] + 3 * d for i, d in enumerate([6.0, -14.61, 6.0])]  # ~50 away
MID_EYE = [TARGET[i] + d for i, d in enumerate([6.0, -14.61, 6.0])]  # ~17 away


@pytest.fixture(scope="module")
def tsc(tmp_path_factory, shared_data):
    """A .tsc of 207 k triangles in a few hundred cells (--min-cell 3000)."""
    d = tmp_path_factory.mktemp("tsc")
    run_tessd("subdivide", shared_data / "mesh" / "fandisk.obj", d / "fd2.ply", "--scheme",
              "loop", "--levels", "2", "--no-normals")
    run_tessd("compress", d / "fd2.ply", d / "fd2.tsc", "--min-cell", "3000")
    return d / "fd2.tsc"


def _tsc_stats(xvfb, tmp_path, tsc, eyes):
    """One run moving the camera through `eyes` (all looking at TARGET), the stats after each
    refinement settles."""
    script, outs = [], []
    for i, eye in enumerate(eyes):
        out = tmp_path / f"stats_{i}_{time.monotonic_ns()}.json"
        outs.append(out)
        script += [
            {"camera": {"eye": eye, "target": TARGET, "up": [0, 0, 1], "fov": 30}},
            {"wait": 1},
            {"until_idle": True},
            {"wait": 1},
            {"stats": str(out)},
        ]
    script.append({"quit": True})
    checked(run_view(xvfb, [tsc, "--size", "240x180"], script, tmp_path))
    return [json.loads(p.read_text()) for p in outs]


def _near_triangles(s):
    # the lead adds triangles_near_target (centroid within 10 % of the radius of the target);
    # until then the far camera is far enough for the plain count to tell
    return s.get("triangles_near_target", s["triangles"])


@pytest.fixture(scope="module")
def tsc_runs(xvfb, tmp_path_factory, tsc):
    d = tmp_path_factory.mktemp("tsc_runs")
    return {
        "near": _tsc_stats(xvfb, d, tsc, [NEAR_EYE])[0],
        "far": _tsc_stats(xvfb, d, tsc, [FAR_EYE])[0],
        "moving": _tsc_stats(xvfb, d, tsc, [MID_EYE, NEAR_EYE]),
    }


def test_tsc_near_camera_reads_more_and_shows_more_there(tsc_runs):
    near, far = tsc_runs["near"], tsc_runs["far"]
    assert near["views"] == far["views"] == 1
    assert near["bytes_read"] > far["bytes_read"] > 0, (near["bytes_read"], far["bytes_read"])
    assert near["cells"] > far["cells"], (near["cells"], far["cells"])
    assert _near_triangles(near) > 2 * _near_triangles(far), (near, far)


def test_tsc_frames_keep_coming_while_refining(tsc_runs):
    for s in (tsc_runs["near"], tsc_runs["far"]):
        assert not s["refining"] and s["views"] == 1
        assert s["frames_while_busy"] >= 2, s["frames_while_busy"]
        assert s["frames"] > s["frames_while_busy"]


def test_tsc_moving_camera_reuses_the_session(tsc_runs):
    first, second = tsc_runs["moving"]
    fresh_near = tsc_runs["near"]["bytes_read"]
    assert first["views"] == 1 and second["views"] >= 2, (first["views"], second["views"])
    # the second view shows what a fresh decode for the near camera shows
    assert second["cells"] == tsc_runs["near"]["cells"]
    grown = second["bytes_read"] - first["bytes_read"]
    assert 0 < grown < first["bytes_read"], (first["bytes_read"], second["bytes_read"])
    assert grown < fresh_near, f"the session re-read {grown} B, a fresh decode {fresh_near} B"
    if "sessions" not in second:
        pytest.xfail("stats field `sessions` not in this build (lead adds it)")
    assert second["sessions"] == 1


# ---------------------------------------------------------------------------------------------
# 3. Real input through xdotool

CUBE_V = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
# 1-based indices of CUBE_V: x-major order (x, y, z) = bits (4, 2, 1) of index - 1
CUBE_F = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]


def write_cube(path: Path, shift=(0.0, 0.0, 0.0)):
    """A pure-quad cage: 8 vertices, 6 outward quads."""
    v = "".join(f"v {x + shift[0]} {y + shift[1]} {z + shift[2]}\n" for x, y, z in CUBE_V)
    f = "".join("f " + " ".join(map(str, q)) + "\n" for q in CUBE_F)
    path.write_text(v + f)
    return path


def test_key_w_changes_the_f12_screenshot(viewer, tmp_path, shared_data):
    mesh = tmp_path / "spot_control_mesh.obj"
    shutil.copy(shared_data / "mesh" / "spot_control_mesh.obj", mesh)
    v = viewer([mesh, "--size", "320x240"])
    v.wait_line(r"^view: adapter ")
    time.sleep(0.5)  # a frame drawn for F12 to save
    v.key("F12")
    v.wait_line(r"^view: screenshot .*spot_control_mesh_view_001\.png$")
    v.key("w")
    v.wait_line(r"^view: mode wireframe$")
    time.sleep(0.5)  # frames drawn in wireframe before the next F12
    v.key("F12")
    v.wait_line(r"^view: screenshot .*spot_control_mesh_view_002\.png$")
    solid = read_png(tmp_path / "spot_control_mesh_view_001.png").astype(int)
    wire = read_png(tmp_path / "spot_control_mesh_view_002.png").astype(int)
    assert solid.shape == wire.shape == (240, 320, 4)
    background = solid[0, 0]
    drawn = (np.abs(solid - background).max(axis=-1) > 0).mean()
    assert drawn > 0.05, f"the solid picture covers {drawn:.1%}"
    changed = (np.abs(solid - wire).max(axis=-1) > 16).mean()
    assert changed > 0.02, f"wireframe changed {changed:.2%} of the pixels"


def test_key_plus_raises_the_subdivision_level(viewer, tmp_path):
    cube = write_cube(tmp_path / "cube.obj")
    v = viewer([cube, "--size", "240x180"])
    v.wait_line(r"^view: adapter ")
    line = r"^view: subdivision (\d+) \(([^)]*)\): (\d+) triangles$"
    v.key("plus")
    m1 = v.wait_line(line)
    v.key("plus")
    m2 = v.wait_line(line)
    assert (int(m1[1]), int(m2[1])) == (1, 2), (m1[0], m2[0])
    assert m1[2].startswith("catmull-clark"), m1[0]
    t1, t2 = int(m1[3]), int(m2[3])
    assert (t1, t2) == (48, 192), (m1[0], m2[0])  # 24 -> 96 quads
    assert t2 == 4 * t1


def test_escape_exits_zero_within_5s(viewer, tmp_path):
    v = viewer([write_cube(tmp_path / "cube.obj"), "--size", "240x180"])
    v.wait_line(r"^view: adapter ")
    t = time.monotonic()
    v.key("Escape")
    rc = v.proc.wait(timeout=5)
    assert rc == 0, v.stderr
    assert time.monotonic() - t < 5


# ---------------------------------------------------------------------------------------------
# 4. --frames: played with Space, one topology refined


def test_frames_play_with_one_subdivision_topology(xvfb, tmp_path):
    cube = write_cube(tmp_path / "cube.obj")
    frames = [write_cube(tmp_path / f"f{i}.obj", (0.2 * i, 0.0, 0.1 * i)) for i in range(1, 4)]
    outs = [tmp_path / f"s{i}.json" for i in range(6)]
    script = [{"until_idle": True}, {"key": "space"}]
    for out in outs:
        script += [{"wait": 0}, {"stats": str(out)}]
    script.append({"quit": True})
    r = checked(run_view(xvfb, [cube, "--size", "240x180", "--subdivide", "1", "--frames",
                                *frames], script, tmp_path))
    assert "view: frames playing" in r.stdout, r.stdout
    stats = [json.loads(p.read_text()) for p in outs]
    index = [s["frame_index"] for s in stats]
    assert all(s["frames_total"] == 3 for s in stats)
    assert len(set(index)) >= 2 and all(a != b for a, b in zip(index, index[1:])), index
    assert all(s["subdivision_level"] == 1 for s in stats)
    assert all(s["triangles"] == 48 for s in stats), [s["triangles"] for s in stats]
    if "subdivision_topologies" not in stats[-1]:
        pytest.xfail("stats field `subdivision_topologies` not in this build (lead adds it)")
    assert stats[-1]["subdivision_topologies"] == 1


# ---------------------------------------------------------------------------------------------
# 5-6. Errors


def test_no_display_is_an_error_and_writes_nothing(tmp_path):
    cube = write_cube(tmp_path / "cube.obj")
    shot, ids, stats = tmp_path / "a.png", tmp_path / "a_ids.png", tmp_path / "s.json"
    script = [{"wait": 1}, {"screenshot": str(shot), "face_ids": str(ids)},
              {"stats": str(stats)}, {"quit": True}]
    r = run_view(None, [cube, "--size", "240x180"], script, tmp_path, timeout=20)
    assert r.returncode != 0
    assert "DISPLAY" in r.stderr and "WAYLAND_DISPLAY" in r.stderr, r.stderr
    assert "panicked" not in r.stderr
    assert not any(p.exists() for p in (shot, ids, stats))


@pytest.mark.parametrize("kind", ["missing", "truncated_tsc", "not_a_tsc"])
def test_bad_inputs_name_the_file(xvfb, tmp_path, tsc, kind):
    if kind == "missing":
        bad = tmp_path / "nothere.obj"
    elif kind == "truncated_tsc":
        bad = tmp_path / "truncated.tsc"
        bad.write_bytes(tsc.read_bytes()[:200])
    else:
        bad = tmp_path / "garbage.tsc"
        bad.write_bytes(b"\x00not a tsc file at all" * 4)
    r = run_view(xvfb, [bad, "--size", "240x180"], timeout=20)
    assert r.returncode != 0
    assert str(bad) in r.stderr, r.stderr
    assert "panicked" not in r.stderr
    assert "view: adapter" not in r.stdout, "a window opened for a bad input"
