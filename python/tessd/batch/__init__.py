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

from typing import Any

from .manifest import Asset, ManifestError, Op


def run(*args: Any, **kwargs: Any) -> Any:
    """:func:`tessd.batch.runner.run` (imported on first use: it needs dask)."""
    from .runner import run as _run

    return _run(*args, **kwargs)


__all__ = ["Asset", "ManifestError", "Op", "run"]
