"""Where a curve measured on a grid (a statistic against a factor) meets a target.

:func:`threshold` answers "up to which factor value does the statistic stay below the target?"
for values on a grid, sorted by the factor: the largest value before the first crossing from
the small end, interpolated between the two grid points around it (log-log for positive values,
exact for a power law; else linear).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

BELOW = "below over the whole grid"
ABOVE = "above over the whole grid"
CROSSES = "crosses"
ABOVE_FIRST = "above at the smallest value"
"""The statuses of a :class:`Crossing`; the last for a curve at or above the target at the
smallest factor value that comes below it further on (not monotone)."""


@dataclass(frozen=True)
class Crossing:
    """Where a curve meets the target (:func:`threshold`): ``value`` the largest factor value at
    which it stays below (None when it is not below at the smallest value), ``status``, the
    smallest factor value and the curve there (``first``), how ``value`` was interpolated
    (``log-log``, ``linear`` or ``none``) and a note (points skipped, not monotone)."""

    value: float | None
    status: str
    first: tuple[float, float]
    interpolation: str
    note: str = ""


def threshold(factor: ArrayLike, curve: ArrayLike, target: float) -> Crossing:
    """The largest ``factor`` value at which ``curve`` stays below ``target``, walking from the
    small end (``factor`` sorted ascending).

    The first pair of adjacent points with the first below and the second at or above the target
    is interpolated: log-log when every factor value and every finite curve value is > 0
    (``log y`` linear in ``log x``, exact for a power law ``y = c x^k``), else linearly. An infinite
    curve value (an unbounded interval end) gives the point before it. A curve below at every point
    gives the largest factor value (status :data:`BELOW`: the answer is at least that), one at or
    above at every point None (:data:`ABOVE`), one at or above at the smallest point that comes
    below later None (:data:`ABOVE_FIRST`). A curve that is not monotone is cut at its first
    crossing (said in the note); NaN points (no data) are skipped (said in the note).
    """
    x = np.asarray(factor, dtype=float)
    y = np.asarray(curve, dtype=float)
    keep = ~np.isnan(y)
    skipped = int((~keep).sum())
    x, y = x[keep], y[keep]
    notes = [f"{skipped} point(s) without data skipped"] if skipped else []
    if len(x) == 0:
        return Crossing(None, ABOVE, (math.nan, math.nan), "none", "no point has data")
    first = (float(x[0]), float(y[0]))
    log = bool(np.all(x > 0) and np.all(y[np.isfinite(y)] > 0))
    below = y < target
    if not below.any():
        return Crossing(None, ABOVE, first, "none", "; ".join(notes))
    if not below[0]:
        notes.append(f"not monotone: below the target again from {float(x[np.argmax(below)]):.4g}")
        return Crossing(None, ABOVE_FIRST, first, "none", "; ".join(notes))
    if below.all():
        return Crossing(float(x[-1]), BELOW, first, "none", "; ".join(notes))
    i = int(np.argmin(below)) - 1  # the last point below before the first at or above
    if below[i + 1 :].any():
        notes.append("not monotone: the first crossing from the small end is given")
    x0, x1, y0, y1 = float(x[i]), float(x[i + 1]), float(y[i]), float(y[i + 1])
    if not math.isfinite(y1) or x0 == x1:
        value = x0
    elif log:
        t = (math.log(target) - math.log(y0)) / (math.log(y1) - math.log(y0))
        value = math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0)))
    else:
        value = x0 + (target - y0) / (y1 - y0) * (x1 - x0)
    return Crossing(value, CROSSES, first, "log-log" if log else "linear", "; ".join(notes))
