"""Helpers every benchmark report uses (bench/*/report.py): the machine line, the geometric
mean of ratios and the goal-met cell. The reports run as scripts; each puts bench/ on its path
to import this module."""

import math
import os


def machine():
    """`N cores (CPU model), M GiB RAM`, from /proc where it is readable."""
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = None
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                mem = int(line.split()[1]) / 1024 / 1024
    except OSError:
        pass
    return f"{os.cpu_count()} cores ({model})" + (f", {mem:.0f} GiB RAM" if mem else "")


def gmean(xs):
    """The geometric mean of the positive finite values of `xs` (NaN when there are none)."""
    xs = [x for x in xs if x and x > 0 and math.isfinite(x)]
    return math.exp(sum(map(math.log, xs)) / len(xs)) if xs else float("nan")


def yes(flag):
    """A goal table's *met* cell."""
    return "yes" if flag else "**no**"
