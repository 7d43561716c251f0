"""tessd.batch: asset-library batches on Dask distributed (docs/batch.md, docs/scale-out.md).

    python -m tessd.batch MANIFEST OUTDIR [--address SCHEDULER] [--workers N]

or from Python::

    from tessd.batch import run
    result = run("meshes/", "library/", workers=4)
    print(result.totals)

A manifest (a folder, a CSV or a JSON list; manifest.py) names the inputs and their operations
(``lod``, ``tessellate``, ``convert``, ``thumbnail``, ``turntable``); each asset is one Dask
task that runs them on its worker node's tessd daemon (cluster.py) into
``OUTDIR/assets/<name>/`` (layout.py), and the batch ends with ``OUTDIR/library.usda`` and
``summary.csv`` / ``summary.json`` (summary.py).

Dask is imported only where the cluster is used (cluster.py, runner.py): ``import tessd`` never
imports this package, and ``tessd.batch.manifest`` / ``layout`` / ``stages`` / ``summary`` need
nothing but the standard library. Dask (``dask[distributed]``) is pinned in
python/requirements-cad.txt (the CAD venv, which STEP/IGES inputs need for OCP anyway).
"""

from __future__ import annotations

import sys
from typing import Any

from .manifest import Asset, ManifestError, Op

#: Where dask comes from (pyproject's `batch` extra, the CAD venv scripts/setup.sh makes).
DASK_HINT = ("run it with the CAD venv's Python (.venv-cad/bin/python, which scripts/setup.sh "
             "makes with dask[distributed] pinned), or install dask into this one: "
             "pip install './python[batch]' from the tessd repository (dask[distributed] "
             "2026.8.0)")


def require_dask() -> None:
    """Raises an ImportError saying where dask comes from when ``dask`` or ``distributed``
    cannot be imported."""
    try:
        import dask  # noqa: F401
        import distributed  # noqa: F401
    except ImportError as e:
        raise ImportError(f"Dask distributed, which tessd.batch runs on, is not importable "
                          f"in {sys.executable} ({e}): {DASK_HINT}", name=e.name) from e


def run(*args: Any, **kwargs: Any) -> Any:
    """:func:`tessd.batch.runner.run` (imported on first use: it needs dask; an ImportError
    saying where dask comes from when it is missing)."""
    require_dask()
    from .runner import run as _run

    return _run(*args, **kwargs)


__all__ = ["Asset", "DASK_HINT", "ManifestError", "Op", "require_dask", "run"]
