"""A cadquery part, tessellated and rendered by tessd.

Builds an L-shaped bracket (two boxes, four holes, filleted edges) with cadquery, exports its
B-Rep faces with `tessd.brep.export_shape`, and asks the daemon for a precise mesh, `part.usda`
(chordal tolerance 0.05 mm, watertight, one GeomSubset per B-Rep face, metersPerUnit 0.001 from
the part's millimetres), and an iso-view picture
of the exact surfaces, `part.png`.

Run (cadquery 2.8, the `.venv-cad` of scripts/setup.sh; the daemon from $TESSD_BIN or PATH):

    .venv-cad/bin/python examples/cadquery_part.py [OUT_DIR]     # default ./tessd-examples-out
"""

import importlib.util
import os
import shutil
import sys
import tempfile

import cadquery as cq

# Use the installed tessd package, else the one in this repository's python/ folder.
if importlib.util.find_spec("tessd") is None:
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import tessd  # noqa: E402
from tessd.brep import export_shape  # noqa: E402

out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "tessd-examples-out")
os.makedirs(out, exist_ok=True)

# The bracket, in millimetres: a base plate and an upright, two holes in each.
base = (cq.Workplane("XY").box(60, 40, 6)
        .faces(">Z").workplane().pushPoints([(-18, -6), (18, -6)]).hole(6))
upright = (cq.Workplane("XZ", origin=(0, 17, 0)).center(0, 20).box(60, 34, 6)
           .faces("<Y").workplane(centerOption="CenterOfBoundBox")
           .pushPoints([(-18, 4), (18, 4)]).hole(5))
bracket = base.union(upright).edges("|Y").fillet(2)  # round the outer corners
doc = export_shape(bracket, units="mm", source="bracket")

# A daemon of our own on a private socket, stopped at the end.
sock_dir = tempfile.mkdtemp(prefix="tessd-ex-")
sock = tessd.ensure_daemon(os.path.join(sock_dir, "d.sock"))
try:
    with tessd.Client(sock) as c:
        mesh, _ = c.call("tessellate", {"brep": doc, "tolerance": "0.05mm",
                                        "output": os.path.join(out, "part.usda")})
        # The stage's metersPerUnit follows the document's units: 0.001 for this mm part.
        print("tessellate: %d faces -> %d triangles within %g mm -> %s (metersPerUnit %g, %.1f ms)"
              % (mesh["faces"], mesh["triangles"], mesh["tolerance"], mesh["output"],
                 mesh["meters_per_unit"], mesh["time_ms"]))
        pic, _ = c.call("render", {"brep": doc, "view": "iso", "size": "1280x720",
                                   "output": os.path.join(out, "part.png")})
        print("render: %dx%d, %d of %d pixels covered -> %s (%s)"
              % (pic["width"], pic["height"], pic["covered"], pic["pixels"], pic["output"],
                 pic["adapter"]["name"]))
finally:
    tessd.stop_daemon(sock)
    shutil.rmtree(sock_dir, ignore_errors=True)
