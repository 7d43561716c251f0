"""Parts built with FreeCAD's Part API for the workbench's tests (console and GUI), and the
shared STEP / BREP files: a filleted box with holes (planes, cylinders, fillets), a revolved
part (planes, cone, cylinder, a spline revolved), a loft (B-spline surfaces)."""

import os
import sys
from pathlib import Path

import FreeCAD
import Part

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tests" / "brep_freecad"))
import fc_parts  # noqa: E402

V = FreeCAD.Vector


def filleted_box_with_holes():
    """A 40 x 30 x 12 block, its vertical edges filleted (r 3), two through holes."""
    box = Part.makeBox(40, 30, 12)
    vertical = [e for e in box.Edges if abs(e.tangentAt(e.FirstParameter).z) > 0.99]
    body = box.makeFillet(3, vertical)
    for x in (12, 28):
        body = body.cut(Part.makeCylinder(4, 12, V(x, 15, 0)))
    return body


# The revolved part and the loft are the FreeCAD exporter's test parts (tests/brep_freecad).
revolved = fc_parts.revolved_profile
loft = fc_parts.lofted


BUILT = {"FilletedBox": filleted_box_with_holes, "Revolved": revolved, "Loft": loft}


def add_part(doc, label, shape, placement=None):
    """A Part::Feature holding ``shape`` (optionally placed)."""
    obj = doc.addObject("Part::Feature", label)
    obj.Label = label
    obj.Shape = shape
    if placement is not None:
        obj.Placement = placement
    return obj


def shared_data():
    """$TESSD_SHARED_DATA, else ../shared/data beside the repository (must exist)."""
    path = Path(os.environ.get("TESSD_SHARED_DATA", REPO.parent / "shared" / "data"))
    if not (path / "brep").is_dir():
        raise FileNotFoundError("shared test data not found at %s (set TESSD_SHARED_DATA)" % path)
    return path


def shared_files():
    """The shared B-Rep files FreeCAD reads: *.brep and *.step of shared/data/brep."""
    brep = shared_data() / "brep"
    return sorted(list(brep.glob("*.brep")) + list(brep.glob("*.step")))
