"""Parameters as the CLI takes them, turned into what the daemon's operations accept.

Lengths are given as numbers (millimetres, FreeCAD's unit), strings with a unit ("0.1mm",
"0.5 cm", "0.01in"), percentages ("0.5%": of the part's size, as the operation defines it) or
`FreeCAD.Units.Quantity` objects. `tessellate` reads units and percentages itself; `simplify`
reads numbers and percentages only, so units are converted here (FreeCAD's unit parser), and
the daemon sees what `tessd simplify --max-error 0.5` would send.
"""

import math
import re
from typing import Any, Sequence, Tuple, Union

import FreeCAD

_PLAIN = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")


def length(value: Any, name: str, percent: bool = False, units: bool = True) -> Union[float, str]:
    """``value`` as the daemon takes it: a number (mm), or a percentage string kept as it is
    (when ``percent``), or (``units``) a length string kept for the daemon to read
    (``"0.1mm"``). Quantities become millimetres. Raises ValueError naming ``name``."""
    if hasattr(value, "getValueAs"):  # FreeCAD.Units.Quantity
        return float(value.getValueAs("mm"))
    if isinstance(value, bool):
        raise ValueError("`%s` must be a length, got %r" % (name, value))
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        text = value.strip()
        if text.endswith("%"):
            if not percent:
                raise ValueError("`%s` takes a length (a number of mm or a length with a "
                                 "unit), not a percentage: %r" % (name, value))
            return text
        if _PLAIN.match(text):
            return float(text)
        if units:
            return text
        return millimetres(text, name)
    raise ValueError("`%s` must be a number, a length such as \"0.1mm\" or a percentage, "
                     "got %r" % (name, value))


def millimetres(text: str, name: str) -> float:
    """A length string with a unit ("0.5 cm", "2mm", "0.01in") in millimetres (FreeCAD's
    unit parser). Raises ValueError naming ``name``."""
    try:
        q = FreeCAD.Units.Quantity(text)
        mm = float(q.getValueAs("mm"))
    except Exception as e:  # ValueError / Base.FreeCADError from the parser or the unit check
        raise ValueError("`%s`: %r is not a length (%s)" % (name, text, e)) from None
    if not math.isfinite(mm):
        raise ValueError("`%s`: %r is not a finite length" % (name, text))
    return mm


def simplify_length(value: Any, name: str, percent: bool) -> Union[float, str]:
    """A `simplify` length (``cell_size``, ``max_error``): numbers and percentages as given,
    units converted to millimetres (the operation reads no units)."""
    return length(value, name, percent=percent, units=False)


def target(value: Any) -> Union[int, str]:
    """``target_vertices``: a count, or a percentage string ("20%")."""
    if isinstance(value, str):
        text = value.strip()
        if text.endswith("%"):
            return text
        if re.match(r"^\s*\d+\s*$", text):
            return int(text)
        raise ValueError("`target` must be a vertex count or a percentage such as \"20%%\", "
                         "got %r" % value)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value):
        raise ValueError("`target` must be a vertex count or a percentage such as \"20%%\", "
                         "got %r" % (value,))
    return int(value)


def image_size(size: Any) -> Tuple[int, int]:
    """``(width, height)`` from a pair or a "WxH" string."""
    if isinstance(size, str):
        m = re.match(r"^\s*(\d+)\s*[xX]\s*(\d+)\s*$", size)
        if not m:
            raise ValueError("`size` must be (width, height) or \"WxH\", got %r" % size)
        return int(m.group(1)), int(m.group(2))
    try:
        w, h = size
        return int(w), int(h)
    except (TypeError, ValueError):
        raise ValueError("`size` must be (width, height) or \"WxH\", got %r" % (size,)) from None


def levels(value: Any) -> Union[str, list]:
    """LOD goals: a comma-separated string as the CLI's ``--levels`` or a list."""
    if isinstance(value, str):
        return value
    if isinstance(value, Sequence):
        return [v if isinstance(v, (int, float, str)) else str(v) for v in value]
    raise ValueError("`levels` must be a comma-separated string such as \"50%%,20%%,5%%\" or a "
                     "list, got %r" % (value,))


__all__ = ["image_size", "length", "levels", "millimetres", "simplify_length", "target"]
