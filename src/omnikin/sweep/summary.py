r"""Statistics of a tolerance study per point, and the answer to its question.

:func:`summarize` turns the trial table (:data:`~omnikin.sweep.study.TRIAL_COLUMNS`, one row per
trial) into one row per point of the study (:data:`SUMMARY_COLUMNS`): how many trials ran and
failed, and for each phase (``before`` and ``after`` calibration) the median of ``E_max,syst``
[m], its ``study.quantile`` quantile [m], distribution-free confidence intervals of both, and
the share of trials below ``study.target``.

Definitions (the statistics use the trials that measured a finite ``E_max,syst``; failed trials
are counted in ``failed`` and left out):

* quantile: NumPy's default (linear interpolation between order statistics, Hyndman and Fan's
  type 7: ``x_(1 + (n-1) q)``), the median its ``q = 0.5`` case;
* confidence interval of the ``q`` quantile at ``study.level`` from order statistics (David and
  Nagaraja, "Order Statistics", section 7.1): the number ``B`` of trials below the true quantile
  is binomial ``(n, q)``, so ``[x_(l), x_(u)]`` covers it with probability
  ``P(l <= B <= u - 1)``. The ranks are equal-tailed: ``l`` the largest rank with
  ``P(B <= l - 1) <= alpha/2``, ``u`` the smallest with ``P(B >= u) <= alpha/2``
  (``alpha = 1 - level``), so the coverage is at least ``level`` (:func:`order_statistic_ranks`).
  With too few trials no rank reaches the level and that end is NaN (unbounded): the upper end
  of the 95 % interval of the 95th percentile needs ``0.95^n <= 0.025``, 72 trials
  (:func:`trials_for_bound`); the median's ends need 6;
* ``below``: the share of the trials with ``E_max,syst < study.target``;
* ``median_reduction``: the median of the trials' ``E_max,syst`` before / after calibration.

:func:`answers` reads the summary along the study's axis (:attr:`~omnikin.sweep.study.Study.axis`,
e.g. ``scale``) for every *series* (:func:`series_of`: a robot with one setting of every other
factor) and phase: the largest axis value at which the quantile stays below the target
(:class:`Answer`, rule in :func:`threshold`), and a conservative one from the upper end of the
quantile's confidence interval.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import binom

from .points import POINT_FIELDS, TOLERANCE_FACTORS, Point, point_key
from .study import TRIAL_COLUMNS, Study

PHASES = ("before", "after")
"""Before and after calibration (the ``e_max_syst_{phase}`` columns of the trial table)."""

_STATS = ("median", "median_low", "median_high", "quantile", "quantile_low", "quantile_high", "below")


def stat_column(stat: str, phase: str) -> str:
    """The summary column of statistic ``stat`` (``median_low``) in ``phase``: ``median_before_low``."""
    head, _, tail = stat.partition("_")
    return f"{head}_{phase}" + (f"_{tail}" if tail else "")


SUMMARY_COLUMNS: tuple[tuple[str, str], ...] = (
    ("point", "string"),
    *((name, kind) for name, kind in TRIAL_COLUMNS if name in POINT_FIELDS),
    ("trials", "int64"),
    ("failed", "int64"),
    *((stat_column(stat, phase), "float64") for phase in PHASES for stat in _STATS),
    ("median_reduction", "float64"),
)
"""Name and Arrow type of every column of the summary, in order (module docstring): the point's
key and settings, ``trials`` (rows of the trial table), ``failed`` (rows with an error), per phase
``median_{phase}``, ``median_{phase}_low``/``_high``, ``quantile_{phase}``,
``quantile_{phase}_low``/``_high`` [m] and ``below_{phase}`` [share], then ``median_reduction``.
NaN stands for a statistic without data or an interval end the trials cannot reach."""

STATUS_BELOW = "below over the whole grid"
STATUS_ABOVE = "above over the whole grid"
STATUS_CROSSES = "crosses"
STATUS_ABOVE_FIRST = "above at the smallest value"
"""The statuses of an :class:`Answer` (:func:`threshold`); the last for a curve above the target
at the smallest axis value that comes below it further on (not monotone)."""

AXIS_UNITS = {"scale": ("scale [-]", 1.0), "radius": ("radius [%]", 100.0), "hub": ("hub [mm]", 1000.0)}
AXIS_UNITS["drive_deg"] = ("drive [deg]", 1.0)
"""Label and factor from a tolerance factor's unit to the unit shown (radius: relative -> %, hub: m -> mm)."""


def order_statistic_ranks(n: int, q: float, level: float) -> tuple[int | None, int | None]:
    """The 1-based ranks ``(l, u)`` of the order statistics bounding the ``q`` quantile of ``n``
    independent trials at confidence ``level`` (module docstring); None for an end that no rank
    reaches (``P(B <= 0) > alpha/2`` for the lower, ``P(B >= n) > alpha/2`` for the upper)."""
    if n < 1:
        return None, None
    half = (1.0 - level) / 2.0
    cdf = binom.cdf(np.arange(n + 1), n, q)  # cdf[k] = P(B <= k)
    lower = [k for k in range(1, n + 1) if cdf[k - 1] <= half]
    upper = [k for k in range(1, n + 1) if 1.0 - cdf[k - 1] <= half]
    return (max(lower) if lower else None), (min(upper) if upper else None)


def trials_for_bound(q: float, level: float, end: str = "upper") -> int:
    """The fewest trials whose order statistics bound the ``q`` quantile at ``level`` at ``end``
    (``upper``: ``q^n <= alpha/2``; ``lower``: ``(1 - q)^n <= alpha/2``)."""
    p = q if end == "upper" else 1.0 - q
    return max(1, math.ceil(math.log((1.0 - level) / 2.0) / math.log(p)))


def _statistics(values: np.ndarray, study: Study) -> dict[str, float]:
    """Median, quantile, their intervals and the share below target of finite ``values`` [m]."""
    x = np.sort(values[np.isfinite(values)])
    n = len(x)
    if n == 0:
        return dict.fromkeys(_STATS, math.nan)
    out = {"below": float(np.mean(x < study.target))}
    for name, q in (("median", 0.5), ("quantile", study.quantile)):
        low, high = order_statistic_ranks(n, q, study.level)
        out[name] = float(np.quantile(x, q))
        out[f"{name}_low"] = float(x[low - 1]) if low is not None else math.nan
        out[f"{name}_high"] = float(x[high - 1]) if high is not None else math.nan
    return out


def _column(values: list, kind: str) -> np.ndarray:
    """``values`` as the array of an Arrow type: strings and columns with nulls as objects."""
    if kind == "string" or any(v is None for v in values):
        return np.array(values, dtype=object)
    return np.array(values, dtype={"float64": float, "int64": np.int64, "bool": bool}[kind])


def summarize(trials: Mapping[str, np.ndarray], study: Study) -> dict[str, np.ndarray]:
    """One row per point of ``study.points``, in that order (:data:`SUMMARY_COLUMNS`), from the
    trial table ``trials`` (:data:`~omnikin.sweep.study.TRIAL_COLUMNS`; strings as object arrays,
    null as None). A point without rows has ``trials`` 0 and NaN statistics; rows of points not in
    the study (a folder of a larger grid) are not read."""
    keys = np.asarray(trials["point"], dtype=object) if len(trials.get("point", ())) else np.array([], dtype=object)
    errors = np.asarray(trials["error"], dtype=object) if len(keys) else keys
    rows: dict[str, list] = {name: [] for name, _ in SUMMARY_COLUMNS}
    for point in study.points:
        key = point_key(point)
        mine = keys == key
        failed = mine & np.array([e is not None for e in errors], dtype=bool)
        ok = mine & ~failed
        rows["point"].append(key)
        for name in POINT_FIELDS:
            rows[name].append(getattr(point, name))
        rows["trials"].append(int(mine.sum()))
        rows["failed"].append(int(failed.sum()))
        for phase in PHASES:
            values = np.asarray(trials[f"e_max_syst_{phase}"], dtype=float)[ok] if len(keys) else np.empty(0)
            for stat, value in _statistics(values, study).items():
                rows[stat_column(stat, phase)].append(value)
        reduction = np.asarray(trials["reduction"], dtype=float)[ok] if len(keys) else np.empty(0)
        reduction = reduction[np.isfinite(reduction)]
        rows["median_reduction"].append(float(np.median(reduction)) if len(reduction) else math.nan)
    return {name: _column(rows[name], kind) for name, kind in SUMMARY_COLUMNS}


@dataclass(frozen=True)
class Series:
    """The points of one series (:func:`series_of`): their rows in the study (and its summary),
    sorted by the axis value; ``setting`` the factors that vary in the study besides the axis,
    with this series' values."""

    robot: str
    setting: tuple[tuple[str, object], ...]
    rows: tuple[int, ...]
    calibrate: bool

    @property
    def label(self) -> str:
        """The robot and the setting of the factors that vary besides the axis (``tomasi-omni3, noise=none``)."""
        return ", ".join([self.robot, *(f"{name}={value}" for name, value in self.setting)])


def _series_fields(study: Study) -> tuple[str, ...]:
    """The factors that split a study into series: every point field but the axis (random design:
    but every tolerance factor, which vary from point to point) and the robot's hash."""
    left_out = set(TOLERANCE_FACTORS) if study.design == "random" else {study.axis}
    return tuple(name for name in POINT_FIELDS if name not in left_out | {"robot_hash"})


def series_of(study: Study) -> list[Series]:
    """The series of ``study`` in the order of their first point: a robot and one setting of every
    other factor, its points sorted by the axis (stable: a random design's ties keep their order).
    In a grid a series is a line along the axis; in a random design it holds the points that share
    every factor but the tolerances, so its answer is approximate (:func:`answers`)."""
    names = _series_fields(study)
    groups: dict[tuple, list[int]] = {}
    for i, point in enumerate(study.points):
        groups.setdefault(tuple(getattr(point, n) for n in names), []).append(i)
    varying = [n for n in names if n != "robot" and len({getattr(p, n) for p in study.points}) > 1]
    out = []
    for key, rows in groups.items():
        setting = dict(zip(names, key, strict=True))
        rows.sort(key=lambda i: getattr(study.points[i], study.axis))
        out.append(
            Series(
                robot=str(setting["robot"]),
                setting=tuple((n, setting[n]) for n in varying),
                rows=tuple(rows),
                calibrate=bool(setting.get("calibrate", study.points[rows[0]].calibrate)),
            )
        )
    return out


@dataclass(frozen=True)
class Crossing:
    """Where a curve (axis values, quantiles [m]) meets the target (:func:`threshold`): ``value``
    the largest axis value at which it stays below (None when above at the smallest value),
    ``status``, the smallest axis value and its quantile (``first``), how the value was
    interpolated (``log-log``, ``linear`` or ``none``) and a note."""

    value: float | None
    status: str
    first: tuple[float, float]
    interpolation: str
    note: str = ""


def threshold(axis: Sequence[float], quantile: Sequence[float], target: float) -> Crossing:
    """The largest axis value at which ``quantile`` stays below ``target``, walking from the small
    end of ``axis`` (sorted ascending): the first pair of adjacent points with the first below and
    the second at or above the target is interpolated, log-log when every axis value and every
    quantile is > 0 (``log q`` linear in ``log x``, exact for a power law ``q = c x^k``), else
    linearly; an infinite quantile (an interval end no rank reaches) gives the point below it.
    A curve below at every point gives the largest axis value (a lower bound of the answer); one
    at or above at the smallest gives None. A non-finite NaN quantile (a point without data) is
    skipped. A curve that is not monotone is cut at its first crossing (said in the note)."""
    x = np.asarray(axis, dtype=float)
    y = np.asarray(quantile, dtype=float)
    keep = ~np.isnan(y)
    skipped = int((~keep).sum())
    x, y = x[keep], y[keep]
    notes = [f"{skipped} point(s) without data skipped"] if skipped else []
    if len(x) == 0:
        return Crossing(None, STATUS_ABOVE, (math.nan, math.nan), "none", "no point has data")
    first = (float(x[0]), float(y[0]))
    finite = y[np.isfinite(y)]
    log = bool(np.all(x > 0) and np.all(finite > 0))
    interpolation = "log-log" if log else "linear"
    below = y < target
    if not below.any():
        return Crossing(None, STATUS_ABOVE, first, "none", "; ".join(notes))
    if not below[0]:
        later = float(x[np.argmax(below)])
        notes.append(f"not monotone: below the target again from {later:.4g}")
        return Crossing(None, STATUS_ABOVE_FIRST, first, "none", "; ".join(notes))
    if below.all():
        return Crossing(float(x[-1]), STATUS_BELOW, first, "none", "; ".join(notes))
    i = int(np.argmin(below)) - 1  # last point below before the first at or above
    if below[i + 1 :].any():
        notes.append("not monotone: the first crossing from the small end is given")
    x0, x1, y0, y1 = x[i], x[i + 1], y[i], y[i + 1]
    if not math.isfinite(y1) or x0 == x1:
        value = float(x0)
    elif log:
        t = (math.log(target) - math.log(y0)) / (math.log(y1) - math.log(y0))
        value = math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0)))
    else:
        value = float(x0 + (target - y0) / (y1 - y0) * (x1 - x0))
    return Crossing(value, STATUS_CROSSES, first, interpolation, "; ".join(notes))


@dataclass(frozen=True)
class Answer:
    """The answer of one series (:class:`Series`) in one phase: ``estimate`` from the quantile,
    ``conservative`` from the upper end of its confidence interval (NaN ends taken as unbounded),
    both :class:`Crossing` along ``axis`` (in the factor's own unit: scale [-], radius [relative],
    hub [m], drive_deg [deg]). ``approximate`` for a random design (points of one series differ in
    more than the axis)."""

    series: Series
    phase: str
    axis: str
    estimate: Crossing
    conservative: Crossing
    tolerances_at: Mapping[str, float] | None
    approximate: bool = False

    def tolerances(self, value: float | None) -> tuple[float, float, float] | None:
        """The build tolerances at axis ``value``: radius [%], hub [mm], drive [deg], i.e. scale
        times the series' radius, hub and drive_deg, with the axis factor set to ``value``; None
        when ``value`` is None or the series' other tolerance factors differ between its points."""
        if value is None or self.tolerances_at is None:
            return None
        f = dict(self.tolerances_at, **{self.axis: value})
        return (f["scale"] * f["radius"] * 100.0, f["scale"] * f["hub"] * 1000.0, f["scale"] * f["drive_deg"])


def answers(summary: Mapping[str, np.ndarray], study: Study) -> list[Answer]:
    """For every series (:func:`series_of`) and phase (``before``; ``after`` when the series
    calibrates): the largest axis value at which ``summary``'s ``quantile_{phase}`` stays below
    ``study.target`` and the conservative one from ``quantile_{phase}_high`` (:func:`threshold`).
    A random design's series are read the same way, points sorted by the axis: approximate, as
    its points differ in more than the axis."""
    out = []
    for s in series_of(study):
        rows = list(s.rows)
        points: list[Point] = [study.points[i] for i in rows]
        x = [float(getattr(p, study.axis)) for p in points]
        others = {n: {getattr(p, n) for p in points} for n in TOLERANCE_FACTORS if n != study.axis}
        at = {n: float(next(iter(v))) for n, v in others.items()} if all(len(v) == 1 for v in others.values()) else None
        for phase in PHASES if s.calibrate else PHASES[:1]:
            q = np.asarray(summary[f"quantile_{phase}"], dtype=float)[rows]
            high = np.asarray(summary[f"quantile_{phase}_high"], dtype=float)[rows]
            high = np.where(np.isnan(high) & ~np.isnan(q), math.inf, high)
            out.append(
                Answer(
                    series=s,
                    phase=phase,
                    axis=study.axis,
                    estimate=threshold(x, q, study.target),
                    conservative=threshold(x, high, study.target),
                    tolerances_at=at,
                    approximate=study.design == "random",
                )
            )
    return out
