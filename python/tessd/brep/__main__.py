"""`python -m tessd.brep export PART OUT.json [--units mm] [--source TEXT] [--sew | --no-sew]
[--sew-tolerance X]`

Reads PART (.step/.stp, .iges/.igs, .brep/.brp) through OCP and writes the `tessd-brep` v1 JSON
(docs/brep-format.md) to OUT.json (`-`: standard output). A summary goes to standard error, with
what sewing did.

Sewing: IGES surface models (and STEP faces or open shells) come unsewn, each face with its own
boundary edges, which a tessellation would then discretise per face (cracks). By default a part
with free edges is sewn (`BRepBuilderAPI_Sewing`) and a closed one is not; `--sew` / `--no-sew`
force it; `--sew-tolerance` sets the tolerance (in `--units`; default: the part's largest edge
or vertex tolerance, within 1e-6 and 1e-3 of its bounding-box diagonal)."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from typing import List, Optional


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tessd.brep", description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    ex = sub.add_parser("export", help="a CAD file → tessd-brep JSON")
    ex.add_argument("part", help="a .step/.stp, .iges/.igs or .brep/.brp file")
    ex.add_argument("out", help="the JSON file to write (- for standard output)")
    ex.add_argument("--units", default="mm", choices=["mm", "cm", "m", "in"],
                    help="length unit of the output (STEP/IGES are converted to it; default mm)")
    ex.add_argument("--source", default=None, help="the document's `source` (default: PART's name)")
    sewing = ex.add_mutually_exclusive_group()
    sewing.add_argument("--sew", dest="sew", action="store_const", const=True, default=None,
                        help="sew the faces (default: when the part has free edges, e.g. IGES surfaces)")
    sewing.add_argument("--no-sew", dest="sew", action="store_const", const=False,
                        help="export the faces as they are, unsewn")
    ex.add_argument("--sew-tolerance", type=_positive, default=None, metavar="X",
                    help="sewing tolerance in --units (default: the part's largest edge / vertex "
                         "tolerance, within 1e-6 and 1e-3 of its bounding-box diagonal)")
    args = ap.parse_args(argv)

    from . import import_ocp

    try:
        ocp = import_ocp()
    except ImportError as e:
        print(f"tessd.brep: {e}", file=sys.stderr)
        return 1

    t0 = time.perf_counter()
    try:
        # OCCT's readers print to standard output (IGES: "Total number of loaded entities"):
        # send that to standard error so `-` gets nothing but the JSON.
        sys.stdout.flush()
        saved = os.dup(1)
        os.dup2(2, 1)
        try:
            shape = ocp.read_file(args.part, units=args.units)
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
        t1 = time.perf_counter()
        doc = ocp.export_topods(shape, units=args.units,
                                source=args.source if args.source is not None else os.path.basename(args.part),
                                sew=args.sew, sew_tolerance=args.sew_tolerance)
    except (OSError, ocp.ExportError) as e:
        print(f"tessd.brep: {e}", file=sys.stderr)
        return 1
    t2 = time.perf_counter()
    text = json.dumps(doc, allow_nan=False, separators=(",", ":"))
    if args.out == "-":
        sys.stdout.write(text + "\n")
    else:
        tmp = args.out + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, args.out)
    print(f"tessd.brep: {args.part}: {len(doc['faces'])} faces, {len(doc['edges'])} edges, "
          f"{sewing_summary(doc, args.sew)} (read {1000 * (t1 - t0):.0f} ms, export "
          f"{1000 * (t2 - t1):.0f} ms) -> {args.out}", file=sys.stderr)
    return 0


def sewing_summary(doc: dict, asked: Optional[bool]) -> str:
    """What sewing did, for the summary line."""
    s = doc.get("sewing")
    if s is None:
        return "not sewn (--no-sew)" if asked is False else "not sewn (no free edges)"
    if s["sewn_edges"] == 0:
        return (f"sewing at {s['tolerance']:.3g} joined nothing ({s['free_edges_before']} free edges "
                f"kept)")
    return (f"sewn at {s['tolerance']:.3g}: {s['sewn_edges']} edges joined, free edges "
            f"{s['free_edges_before']} -> {s['free_edges_after']}")


def _positive(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (x > 0 and x != float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive length, not {text!r}")
    return x


if __name__ == "__main__":
    sys.exit(main())
