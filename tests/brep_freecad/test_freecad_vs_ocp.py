"""The FreeCAD exporter against the OCP one on the same files: every shared STEP / IGES / .brep
file and every built part (written by FreeCAD as .brep, then read back by both) is exported by
`.venv-cad/bin/python -m tessd.brep export` (OCP 7.9, a subprocess: the CAD venv's Python; the
built parts through the CLI's main() in one such process) and by
python/tessd/brep/freecad.py here (FreeCAD 0.20's OCCT 7.6). The two documents must agree: faces,
surface type and `reversed` per face, loops and trims per loop (with their edge ids), then every
number (frames, radii, poles, knots, bounds, trim curves and ranges, edges) within 1e-9 relative
(the two OCCT versions' converters round differently in the last digits), the edges' tolerances
and their vertices' included. OCP's side runs with `--no-sew`: FreeCAD's exporter does not sew."""

from __future__ import annotations

import json
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

import locate
from fc_checks import exported, shared_files
from fc_parts import PARTS

from tessd.brep import freecad as brep_freecad

REPO = Path(__file__).resolve().parents[2]
CAD_PYTHON = REPO / ".venv-cad" / "bin" / "python"
FILES = shared_files()
CASES = FILES + sorted(PARTS)
REL = 1e-9


@pytest.fixture(scope="module")
def ocp_docs(tmp_path_factory):
    """name → (the file both exporters read, OCP's document)."""
    if not CAD_PYTHON.exists():
        pytest.skip(f"no CAD venv ({CAD_PYTHON}): scripts/setup.sh makes it")
    d = tmp_path_factory.mktemp("ocp")
    inputs = {name: locate.shared_data() / "brep" / name for name in FILES}
    for name in PARTS:
        inputs[name] = d / f"{name}.brep"
        exported(name)[0].exportBrep(str(inputs[name]))
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))

    def run(names):
        """The CLI on each shared file; on the built parts, its main() in one process (one
        OCP start-up: they are many and small)."""
        # --no-sew: FreeCAD's exporter does not sew (tessd.brep.export_shape refuses to for
        # FreeCAD shapes), so OCP's must export the unsewn IGES faces as they are too
        jobs = [[str(inputs[n]), str(d / f"{n}.ocp.json"), "--no-sew"] for n in names]
        if len(names) == 1:
            cmd = [str(CAD_PYTHON), "-m", "tessd.brep", "export", *jobs[0]]
        else:
            cmd = [str(CAD_PYTHON), "-c", "import sys; from tessd.brep.__main__ import main; "
                   f"sys.exit(max(main(['export', *job]) for job in {jobs!r}))"]
        r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, f"{names}: OCP export failed: {r.stderr}"
        return [(n, (inputs[n], json.loads((d / f"{n}.ocp.json").read_text()))) for n in names]

    with ThreadPoolExecutor(max_workers=2) as pool:  # the machine's two cores
        batches = pool.map(run, [sorted(PARTS)] + [[n] for n in FILES])
        return dict(item for batch in batches for item in batch)


def _numbers_agree(a, b, path, worst):
    """Same structure, numbers within REL (relative to 1 + |a|); records the worst deviation."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{path}: keys {sorted(a)} vs {sorted(b)}"
        for k in a:
            _numbers_agree(a[k], b[k], f"{path}.{k}", worst)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: {len(a)} items vs {b!r:.80}"
        for i, (x, y) in enumerate(zip(a, b)):
            _numbers_agree(x, y, f"{path}[{i}]", worst)
    elif isinstance(a, (int, float)) and not isinstance(a, bool):
        assert isinstance(b, (int, float)) and not isinstance(b, bool), f"{path}: {a} vs {b!r}"
        dev = abs(a - b) / (1 + abs(a))
        if dev > worst[0]:
            worst[:] = [dev, path]
        assert dev <= REL, f"{path}: FreeCAD {a} vs OCP {b}"
    else:
        assert a == b, f"{path}: FreeCAD {a!r} vs OCP {b!r}"


@pytest.mark.parametrize("name", CASES)
def test_same_document_as_ocp(ocp_docs, name):
    path, theirs = ocp_docs[name]
    # the shared files as the other tests export them; a built part read back from its .brep
    mine = exported(name)[1] if name in FILES else brep_freecad.export_file(str(path))
    assert len(mine["faces"]) == len(theirs["faces"])
    for fm, fo in zip(mine["faces"], theirs["faces"]):
        where = f"{name} face {fm['id']}"
        assert fm["id"] == fo["id"], where
        assert fm["surface"]["type"] == fo["surface"]["type"], where
        assert fm["reversed"] == fo["reversed"], where
        assert [[t["edge"] for t in lp["edges"]] for lp in fm["loops"]] == \
            [[t["edge"] for t in lp["edges"]] for lp in fo["loops"]], f"{where}: loops / trims / edge ids"
        worst = [0.0, None]
        _numbers_agree(fm["surface"], fo["surface"], f"{where} surface", worst)
    worst = [0.0, None]
    _numbers_agree(mine, theirs, name, worst)
    print(f"{name}: {len(mine['faces'])} faces, {len(mine['edges'])} edges agree; worst relative "
          f"deviation {worst[0]:.1e}" + (f" at {worst[1]}" if worst[1] else ""))
