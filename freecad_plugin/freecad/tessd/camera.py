"""The camera of FreeCAD's active 3D view as the `render` op's explicit camera.

`view="active"` renders what the user looks at. The view's camera comes from
`ActiveView.getCamera()`, Coin's own text of the camera node (position, orientation as axis and
angle, focal distance, and the height angle of a perspective camera or the height of an
orthographic one, FreeCAD's default), so no pivy object needs reading. The render op has a
perspective camera only (docs/protocol.md, "render", Camera): a perspective view keeps its
field of view; an orthographic one becomes a 30° perspective whose eye is as far back from the
focal point as needed for the view's height to fill the picture there.

Coin's ADJUST_CAMERA mapping fits the height to the narrower side, so for a picture taller
than wide the vertical field of view is widened by the aspect ratio.
"""

import math
import re
from typing import Any, Dict, Optional

import FreeCAD

#: Field of view given to an orthographic view (the render op's default).
ORTHOGRAPHIC_FOV = 30.0

_VIEWS = ("iso", "front", "back", "left", "right", "top", "bottom")


def parse_inventor_camera(text: str) -> Dict[str, Any]:
    """The fields of an Inventor camera node's text (`OrthographicCamera { ... }` or
    `PerspectiveCamera { ... }`) as ``{"type", "position", "orientation", "focalDistance",
    "height" | "heightAngle"}``. Raises ValueError for text that is not a camera."""
    m = re.search(r"\b(Orthographic|Perspective)Camera\s*\{(.*?)\}", text, re.S)
    if not m:
        raise ValueError("not an Inventor camera: %r" % text[:80])
    out: Dict[str, Any] = {"type": m.group(1).lower()}
    for line in m.group(2).splitlines():
        words = line.split()
        if len(words) < 2:
            continue
        key, values = words[0], words[1:]
        try:
            numbers = [float(v) for v in values]
        except ValueError:
            continue  # viewportMapping ADJUST_CAMERA and the like
        out[key] = numbers if len(numbers) > 1 else numbers[0]
    for key in ("position", "orientation"):
        if key not in out:
            raise ValueError("the camera has no %s" % key)
    return out


def render_camera(camera: Dict[str, Any], aspect: float = 16 / 9) -> Dict[str, Any]:
    """``{"eye", "target", "up", "fov"}`` for the render op from a parsed camera; ``aspect`` is
    the picture's width / height."""
    ax, ay, az, angle = camera["orientation"]
    axis = FreeCAD.Vector(ax, ay, az)
    rot = FreeCAD.Rotation(axis, math.degrees(angle)) if axis.Length > 0 else FreeCAD.Rotation()
    forward = rot.multVec(FreeCAD.Vector(0, 0, -1))
    up = rot.multVec(FreeCAD.Vector(0, 1, 0))
    eye = FreeCAD.Vector(*camera["position"])
    focal = float(camera.get("focalDistance", 1.0)) or 1.0
    target = eye + forward * focal
    if camera["type"] == "perspective":
        fov = math.degrees(float(camera.get("heightAngle", math.radians(45))))
    else:
        fov = ORTHOGRAPHIC_FOV
        height = float(camera.get("height", 2.0 * focal * math.tan(math.radians(fov / 2))))
        eye = target - forward * (height / 2 / math.tan(math.radians(fov / 2)))
    if aspect < 1.0:  # ADJUST_CAMERA fits the height to the narrower side, here the width
        fov = math.degrees(2 * math.atan(math.tan(math.radians(fov / 2)) / aspect))
    fov = min(max(fov, 1e-3), 179.0)
    return {"eye": [eye.x, eye.y, eye.z], "target": [target.x, target.y, target.z],
            "up": [up.x, up.y, up.z], "fov": fov}


def active_view_camera(aspect: float = 16 / 9) -> Dict[str, Any]:
    """:func:`render_camera` of the active 3D view. Raises ValueError in console mode or
    without a 3D view (GUI thread only)."""
    if not FreeCAD.GuiUp:
        raise ValueError('view="active" takes the camera of the active 3D view, and FreeCAD '
                         'runs without its GUI here; give one of %s instead' % ", ".join(_VIEWS))
    import FreeCADGui

    gdoc = FreeCADGui.ActiveDocument
    view = getattr(gdoc, "ActiveView", None) if gdoc is not None else None
    if view is None or not hasattr(view, "getCamera"):
        raise ValueError('view="active": there is no active 3D view to take the camera from')
    return render_camera(parse_inventor_camera(view.getCamera()), aspect)


def check_view(view: Optional[str]) -> str:
    """A standard view name ("active" is handled by the caller)."""
    if view not in _VIEWS:
        raise ValueError("`view` must be \"active\" or one of %s, got %r" % (", ".join(_VIEWS), view))
    return view


__all__ = ["active_view_camera", "check_view", "parse_inventor_camera", "render_camera"]
