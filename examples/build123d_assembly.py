"""A build123d assembly, tessellated per part, with a chain of levels of detail per part.

Builds a plate, a hex bolt through its hole and a nut (build123d), exports each part's B-Rep
faces with `tessd.brep.export_shape`, tessellates each with the daemon (0.01 mm), welds the
mesh (the tessellator gives each face its own copy of the edge vertices it shares), and has the
daemon's `lod` op simplify it to 50 %, 20 % and 5 % of its vertices into `<part>.usda` (a `LOD`
variant set, LOD0 the precise mesh). `assembly.usda` references the three parts: one USD for
the whole assembly, each part with its own LOD switch.

Run (build123d 0.13, the `.venv-b123d` of scripts/setup.sh; the daemon from $TESSD_BIN or PATH):

    .venv-b123d/bin/python examples/build123d_assembly.py [OUT_DIR]   # default ./tessd-examples-out
"""

import importlib.util
import os
import shutil
import sys
import tempfile

import numpy as np
from build123d import Box, Cylinder, Pos, RegularPolygon, extrude

# Use the installed tessd package, else the one in this repository's python/ folder.
if importlib.util.find_spec("tessd") is None:
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import tessd  # noqa: E402
from tessd.brep import export_shape  # noqa: E402

out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "tessd-examples-out")
os.makedirs(out, exist_ok=True)

# The parts, in millimetres and already in place: the plate spans z = -4..4.
hexagon = RegularPolygon(radius=5.5, side_count=6)
parts = {
    "plate": Box(60, 40, 8) - Pos(15, 0, 0) * Cylinder(radius=3.2, height=8),
    "bolt": Pos(15, 0, 4) * extrude(hexagon, 4) + Pos(15, 0, -5) * Cylinder(radius=3, height=18),
    "nut": Pos(15, 0, -10) * (extrude(hexagon, 4) - Cylinder(radius=3, height=8)),
}

sock_dir = tempfile.mkdtemp(prefix="tessd-ex-")
sock = tessd.ensure_daemon(os.path.join(sock_dir, "d.sock"))  # a private daemon, stopped below
try:
    with tessd.Client(sock) as c:
        for name, part in parts.items():
            doc = export_shape(part, units="mm", source=name)
            mesh, arrays = c.call("tessellate", {"brep": doc, "tolerance": "0.01mm"})
            # Weld equal positions, so that the LODs simplify one connected surface.
            points, index = np.unique(arrays["positions"], axis=0, return_inverse=True)
            welded = dict(arrays, positions=points,
                          face_indices=index.reshape(-1)[arrays["face_indices"]].astype(np.uint32))
            lods, _ = c.call("lod", {"levels": "50%,20%,5%", "name": name,
                                     "group_names": mesh["groups"],  # a GeomSubset per face
                                     "output": os.path.join(out, name + ".usda"),
                                     "up_axis": "Z", "meters_per_unit": 0.001}, welded)
            print("%-5s: %2d faces, %4d triangles; LOD0..3 vertices %s -> %s.usda" % (
                name, mesh["faces"], mesh["triangles"],
                [lods["lod0"]["points"]] + [lv["output_vertices"] for lv in lods["levels"]], name))
finally:
    tessd.stop_daemon(sock)
    shutil.rmtree(sock_dir, ignore_errors=True)

# One stage for the assembly: each part's stage referenced under /Assembly.
parts_usda = "".join('    def "%s" (prepend references = @./%s.usda@) {}\n' % (n, n) for n in parts)
with open(os.path.join(out, "assembly.usda"), "w") as f:
    f.write("""#usda 1.0
(
    defaultPrim = "Assembly"
    metersPerUnit = 0.001
    upAxis = "Z"
)

def Xform "Assembly" (kind = "assembly")
{
%s}
""" % parts_usda)
print("assembly.usda: %s" % ", ".join(parts))
