"""``python -m tessd.batch MANIFEST OUTDIR [--address CLUSTER] [--workers N] [...]``

Turns every input of MANIFEST (a folder, a .csv or a .json list; see tessd/batch/manifest.py)
into an asset of the USD library OUTDIR (OUTDIR/library.usda, OUTDIR/assets/<name>/), on a Dask
cluster: the scheduler at --address, else a LocalCluster of --workers processes (one thread
each). Prints done/total while it runs and a line per failed step at the end; writes
OUTDIR/summary.csv and summary.json. Exit status: 0 when every step is ok or skipped, 1 when a
step failed, 2 for a bad manifest or arguments."""

from __future__ import annotations

import argparse
import os
import sys
from typing import List, Optional


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tessd.batch", description=__doc__.split("\n\n")[1])
    ap.add_argument("manifest", help="a folder of meshes / CAD parts, or a .csv / .json manifest")
    ap.add_argument("outdir", help="the asset library to write (created; re-runs skip what is complete)")
    ap.add_argument("--address", default=None,
                    help="a running Dask scheduler (tcp://host:8786); default: a LocalCluster")
    ap.add_argument("--workers", type=int, default=max(1, os.cpu_count() or 1),
                    help="LocalCluster worker processes, one thread each (default: one per core)")
    ap.add_argument("--daemon-scope", choices=["node", "worker"], default="node",
                    help="one tessd daemon per node, shared by its workers (default), or per worker")
    ap.add_argument("--tessd-bin", default=None,
                    help="the tessd binary on the workers (default: their $TESSD_BIN, else PATH)")
    ap.add_argument("--op-timeout", type=float, default=600.0,
                    help="seconds one daemon request may take before it is cancelled (default 600)")
    ap.add_argument("--allowed-failures", type=int, default=3,
                    help="LocalCluster: worker deaths a task survives before it is reported lost")
    ap.add_argument("--chunk", type=int, default=1,
                    help="assets per Dask task (default 1; more for many small assets on a "
                         "large cluster: keeps the scheduler's per-task cost small)")
    ap.add_argument("--quiet", action="store_true", help="no progress line")
    args = ap.parse_args(argv)
    if args.workers < 1:
        ap.error("--workers must be at least 1")

    from . import require_dask
    from .manifest import ManifestError

    try:
        require_dask()
    except ImportError as e:
        print("tessd.batch: %s" % e, file=sys.stderr)
        return 2
    from .runner import BatchError, run

    try:
        result = run(args.manifest, args.outdir, address=args.address, workers=args.workers,
                     daemon_scope=args.daemon_scope, tessd_bin=args.tessd_bin,
                     op_timeout=args.op_timeout, allowed_failures=args.allowed_failures,
                     chunk=args.chunk,
                     show_progress=not args.quiet)
    except (ManifestError, BatchError) as e:
        print("tessd.batch: %s" % e, file=sys.stderr)
        return 2
    for r in result.rows:
        if r["status"] == "error":
            print("tessd.batch: %s %s: %s" % (r["asset"], r["step"], r["error"]), file=sys.stderr)
    t = result.totals
    print("tessd.batch: %d assets (%d ok, %d with errors), steps %s, %.1fs -> %s"
          % (t["assets"], t["assets_ok"], t["assets_with_errors"],
             ", ".join("%d %s" % (n, s) for s, n in t["steps"].items()), result.seconds,
             result.library), file=sys.stderr)
    return 0 if result.ok else 1


if __name__ == "__main__":
    sys.exit(main())
