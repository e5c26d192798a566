"""Small helpers shared by the benchmark scripts (not a benchmark itself)."""

from __future__ import annotations

import math
import os


def load_average():
    """The (1, 5, 15 min) load average rounded to 0.01, or None where the system
    has none."""
    try:
        return tuple(round(x, 2) for x in os.getloadavg())
    except (AttributeError, OSError):
        return None


def fmt_seconds(s) -> str:
    """A duration for a table: ms below 1 s, two decimals below 100 s, "—" if unknown."""
    if s is None or not math.isfinite(s):
        return "—"
    if s < 1.0:
        return f"{s * 1e3:.0f} ms"
    if s < 100.0:
        return f"{s:.2f} s"
    return f"{s:.0f} s"
