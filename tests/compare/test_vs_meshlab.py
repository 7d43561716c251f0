"""Cross-check of `tessd-compare` (Metro-style surface distance) against MeshLab's Hausdorff
Distance filter (pymeshlab `get_hausdorff_distance`), on shared meshes and simplified versions
of them made by MeshLab itself.

Run with the peer-tool venv (scripts/test.sh does; pymeshlab lives there, not in the main test
venv):

    /work/main/.venv-bench/bin/python -m pytest tests/compare -q -s

Both tools read the very same files (PLY written by pymeshlab, unreferenced vertices removed)
and sample them the same way: every vertex plus N area-weighted face samples, each measured
to the exact closest point of the other surface. MeshLab's `max`, `mean` and `RMS` are the
plain max, mean and sqrt(mean of squares) over its samples (vcg HausdorffSampler; samples
farther than `maxdist` are dropped, so `maxdist` is set well beyond the bounding-box diagonal),
which is exactly how `Distance` defines them, so the numbers compare like with like. Face
samples differ (MeshLab: independent Monte Carlo; ours: stratified), so only statistical
agreement is expected; the maxima usually coincide exactly because a vertex sample carries
them.

Set TESSD_COMPARE_SAMPLES to change N (default 1 000 000) and TESSD_COMPARE_JSON to use a
prebuilt `compare_json` binary instead of building it.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path

import pytest

from locate import REPO, shared_data

import pymeshlab  # noqa: E402  (the peer tool itself: missing means failing, never skipping)

SAMPLES = int(os.environ.get("TESSD_COMPARE_SAMPLES", "1000000"))
TOLERANCE = 0.05  # relative agreement required on max and RMS, each direction

# (name, source mesh, how MeshLab simplifies it)
PAIRS = [
    (
        "bunny / quadric 10 %",
        "mesh/bun_zipper.ply",
        lambda ms: ms.meshing_decimation_quadric_edge_collapse(targetperc=0.1),
    ),
    (
        "fandisk / clustering 2 %",
        "mesh/fandisk.obj",
        lambda ms: ms.meshing_decimation_clustering(threshold=pymeshlab.PercentageValue(2.0)),
    ),
    (
        "spot / quadric 2 %",
        "mesh/spot_triangulated.obj",
        lambda ms: ms.meshing_decimation_quadric_edge_collapse(targetperc=0.02),
    ),
]

RESULTS: list[dict] = []


@pytest.fixture(scope="session")
def compare_json() -> Path:
    """The `compare_json` example binary (release build)."""
    if os.environ.get("TESSD_COMPARE_JSON"):
        return Path(os.environ["TESSD_COMPARE_JSON"])
    subprocess.run(
        ["cargo", "build", "--release", "-q", "-p", "tessd-compare", "--example", "compare_json"],
        cwd=REPO,
        check=True,
    )
    target = Path(os.environ.get("CARGO_TARGET_DIR") or REPO / "target")
    return target / "release" / "examples" / "compare_json"


def _save(ms, path: Path) -> None:
    ms.meshing_remove_unreferenced_vertices()
    ms.save_current_mesh(str(path), binary=True, save_vertex_normal=False, save_vertex_color=False,
                         save_vertex_quality=False, save_face_color=False, save_face_quality=False)


def _prepare(src: Path, simplify, tmp: Path) -> tuple[Path, Path]:
    """Writes the source mesh and its MeshLab simplification as PLY files."""
    a, b = tmp / "a.ply", tmp / "b.ply"
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(src))
    _save(ms, a)
    simplify(ms)
    _save(ms, b)
    return a, b


def _meshlab(a: Path, b: Path) -> dict:
    """MeshLab's Hausdorff filter both ways on the files, with timings."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(a))
    ms.load_new_mesh(str(b))
    diag = max(ms.mesh(0).bounding_box().diagonal(), ms.mesh(1).bounding_box().diagonal())
    out = {}
    for key, (s, t) in {"a_to_b": (0, 1), "b_to_a": (1, 0)}.items():
        t0 = time.perf_counter()
        r = ms.get_hausdorff_distance(
            sampledmesh=s,
            targetmesh=t,
            samplevert=True,
            sampleedge=False,
            sampleface=True,
            samplenum=SAMPLES,
            maxdist=pymeshlab.PureValue(4.0 * diag),
        )
        r["time_s"] = time.perf_counter() - t0
        out[key] = r
    out["faces"] = (ms.mesh(0).face_number(), ms.mesh(1).face_number())
    return out


@pytest.mark.parametrize("name,src,simplify", PAIRS, ids=[p[0] for p in PAIRS])
def test_agrees_with_meshlab(name, src, simplify, compare_json, tmp_path):
    src = shared_data() / src
    assert src.exists(), f"shared data missing: {src}"
    a, b = _prepare(src, simplify, tmp_path)
    ml = _meshlab(a, b)
    proc = subprocess.run(
        [str(compare_json), str(a), str(b), "--samples", str(SAMPLES)],
        check=True,
        capture_output=True,
        text=True,
    )
    ours = json.loads(proc.stdout)
    assert (ours["triangles_a"], ours["triangles_b"]) == ml["faces"]

    row = {"pair": name, "faces": ml["faces"], "threads": ours["threads"]}
    print(f"\n{name}: {ml['faces'][0]} vs {ml['faces'][1]} triangles, {SAMPLES} face samples")
    print(f"  {'':8} {'':9} {'ours':>12} {'MeshLab':>12} {'rel.diff':>9}")
    failures = []
    for key in ("a_to_b", "b_to_a"):
        o, m = ours[key], ml[key]
        row[key] = {
            "ours": {k: o[k] for k in ("max", "mean", "rms", "samples")},
            "meshlab": {"max": m["max"], "mean": m["mean"], "rms": m["RMS"],
                        "samples": m["n_samples"]},
            "time_ours_s": ours["time_s"][key],
            "time_meshlab_s": m["time_s"],
        }
        for metric, mk in (("max", "max"), ("mean", "mean"), ("rms", "RMS")):
            rel = abs(o[metric] - m[mk]) / m[mk]
            print(f"  {key:8} {metric:9} {o[metric]:12.6g} {m[mk]:12.6g} {rel:9.2%}")
            if metric != "mean" and rel > TOLERANCE:
                failures.append(f"{key} {metric}: ours {o[metric]:.6g} vs MeshLab {m[mk]:.6g}")
        print(f"  {key:8} {'samples':9} {o['samples']:12d} {m['n_samples']:12d}")
        print(f"  {key:8} {'time (s)':9} {ours['time_s'][key]:12.3f} {m['time_s']:12.3f}"
              f"   (ours on {ours['threads']} threads, MeshLab on 1)")
        # Same sampling plan: every vertex plus SAMPLES face samples.
        assert o["samples"] == m["n_samples"]
    RESULTS.append(row)
    if os.environ.get("TESSD_COMPARE_REPORT"):
        Path(os.environ["TESSD_COMPARE_REPORT"]).write_text(json.dumps(RESULTS, indent=1))
    assert not failures, "; ".join(failures)


# ------------------------------------------------------------------------------------------
# The quality goal's guarantee, measured by MeshLab: `tessd simplify --method quality
# --max-error X` leaves the two surfaces within X of each other (symmetric Hausdorff distance).

def _shared_meshes() -> list[Path]:
    folder = shared_data() / "mesh"
    return sorted(p for p in folder.iterdir() if p.suffix.lower() in (".obj", ".ply", ".off"))


GUARANTEE_SAMPLES = 200_000


@pytest.mark.parametrize("fraction", ["5%", "1%", "0.5%", "0.1%"])
@pytest.mark.parametrize("mesh", _shared_meshes(), ids=lambda p: p.name)
def test_quality_guarantee_holds_by_meshlab(mesh, fraction, tmp_path):
    from locate import tessd_bin

    a = tmp_path / "a.ply"
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(mesh))
    _save(ms, a)  # the input as MeshLab reads it (polygons split by MeshLab, as we split them)
    b = tmp_path / "b.ply"
    run = subprocess.run([str(tessd_bin()), "simplify", str(a), str(b), "--method", "quality",
                          "--max-error", fraction, "--json"], check=True, capture_output=True, text=True)
    r = json.loads(run.stdout)
    tol = r["tolerance"]
    ml = pymeshlab.MeshSet()
    ml.load_new_mesh(str(a))
    ml.load_new_mesh(str(b))
    diag = ml.mesh(0).bounding_box().diagonal()
    worst = 0.0
    for s, t in ((0, 1), (1, 0)):
        h = ml.get_hausdorff_distance(sampledmesh=s, targetmesh=t, samplevert=True, sampleedge=True,
                                      sampleface=True, samplenum=GUARANTEE_SAMPLES,
                                      maxdist=pymeshlab.PureValue(4.0 * diag))
        worst = max(worst, h["max"])
    print(f"\n{mesh.name} {fraction}: tolerance {tol:.6g}, MeshLab Hausdorff {worst:.6g} "
          f"({worst / tol:.3f} tol), tessd bound {r['surface_error']:.6g}, "
          f"{r['output_vertices']} vertices, {r['refinement_rounds']} rounds")
    # MeshLab measures in single precision: identical surfaces read ~5e-8 of the diagonal apart.
    assert worst <= tol * 1.001, (worst, r)
    assert worst <= r["surface_error"] * 1.001 + 1e-6 * diag, (worst, r)
