r"""Statistics of a tolerance study per point, and the answer to its question.

:func:`summarize` turns the trial table (:data:`~omnikin.sweep.study.TRIAL_COLUMNS`, one row per
trial) into one row per point of the study (:data:`SUMMARY_COLUMNS`): how many trials ran and
failed, and for each phase (``before`` and ``after`` calibration) the median of ``E_max,syst``
[m], its ``study.quantile`` quantile [m], confidence intervals of both at ``study.level``, and
the share of trials below ``study.target``.

Definitions (statistics of the trials that measured a finite ``E_max,syst``; failed trials are
counted in ``failed`` and left out):

* quantile: NumPy's default, linear interpolation between order statistics (Hyndman and Fan's
  type 7, ``x_(1 + (n-1) q)``); the median is its ``q = 0.5`` case;
* confidence intervals: distribution-free, from order statistics with binomial ranks
  (:mod:`omnikin.evaluation.order_statistics`); an end the trials cannot reach is NaN: the upper
  end of the 95 % interval of the 95th percentile needs 72 trials per point, the median's 6;
* ``below``: the share of the trials with ``E_max,syst < study.target``;
* ``median_reduction``: the median of the trials' ``E_max,syst`` before / after calibration, an
  after-value below :data:`~omnikin.common.number_text.RESOLUTION` (0.01 mm, what the report resolves)
  counted as that resolution; ``reduction_bound`` says that some trial's was, so the median is
  a lower bound (the report prints it as ``at least N``; the trial table keeps each trial's own
  ratio).

:func:`answers` reads the summary along the study's axis (:attr:`~omnikin.sweep.study.Study.axis`,
e.g. ``scale``) per *series* (:func:`series_of`: a robot with one setting of every other factor)
and phase: the largest axis value at which the quantile stays below the target
(:func:`~omnikin.evaluation.threshold.threshold`) and a conservative one from the upper end of the
quantile's interval (an unbounded end counts as above the target).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..common.number_text import RESOLUTION
from ..evaluation.order_statistics import quantile_interval
from ..evaluation.threshold import BELOW, Crossing, threshold
from ..viz.sweep import AXIS_UNITS
from .points import POINT_FIELDS, TOLERANCE_FACTORS, point_key
from .study import TRIAL_COLUMNS, Study

PHASES = ("before", "after")
"""Before and after calibration (the ``e_max_syst_{phase}`` columns of the trial table)."""

STATISTICS = ("median", "median_low", "median_high", "quantile", "quantile_low", "quantile_high", "below")
"""The statistics of a phase (:func:`stat_column` names their columns)."""


def stat_column(stat: str, phase: str) -> str:
    """The summary column of statistic ``stat`` in ``phase``: ``median_low``, ``before`` -> ``median_before_low``."""
    head, _, tail = stat.partition("_")
    return f"{head}_{phase}" + (f"_{tail}" if tail else "")


SUMMARY_COLUMNS: tuple[tuple[str, str], ...] = (
    ("point", "string"),
    *((name, kind) for name, kind in TRIAL_COLUMNS if name in POINT_FIELDS),
    ("series", "string"),
    ("trials", "int64"),
    ("failed", "int64"),
    *((stat_column(stat, phase), "float64") for phase in PHASES for stat in STATISTICS),
    ("median_reduction", "float64"),
    ("reduction_bound", "bool"),
)
"""Name and Arrow type of every column of the summary, in order (module docstring): the point's
key and settings, its ``series`` (:attr:`Series.label`), ``trials`` (rows of the trial table),
``failed`` (rows with an error), per phase ``median_{phase}``, ``median_{phase}_low``/``_high``,
``quantile_{phase}``, ``quantile_{phase}_low``/``_high`` [m] and ``below_{phase}`` [share], then
``median_reduction`` and ``reduction_bound``. NaN stands for a statistic without data or an interval end the trials
cannot reach; ``noise`` and ``ticks_per_rev`` may be None."""


@dataclass(frozen=True)
class Series:
    """The points of one series (:func:`series_of`): their indices in ``study.points`` (and rows
    of its summary) sorted by the axis value; ``setting`` the factors that vary in the study
    besides the axis, with this series' values."""

    robot: str
    setting: tuple[tuple[str, object], ...]
    rows: tuple[int, ...]
    calibrate: bool

    @property
    def label(self) -> str:
        """The robot and the setting of the factors that vary besides the axis (``tomasi-omni3, noise=none``)."""
        return ", ".join([self.robot, *(f"{name}={value}" for name, value in self.setting)])


def series_of(study: Study) -> list[Series]:
    """The series of ``study`` in the order of their first point: a robot with one setting of
    every point field but the axis (and the robot's hash), its points sorted by the axis value.
    In a random design every tolerance factor is left out of the setting (they vary from point to
    point): a series holds the points that share every other factor, and its answer is approximate."""
    left_out = set(TOLERANCE_FACTORS) if study.design == "random" else {study.axis}
    names = tuple(n for n in POINT_FIELDS if n not in left_out | {"robot_hash"})
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
                calibrate=bool(setting["calibrate"]),
            )
        )
    return out


def _column(values: list, kind: str) -> np.ndarray:
    """``values`` as the array of an Arrow type: strings and columns holding None as objects."""
    if kind == "string" or any(v is None for v in values):
        return np.array(values, dtype=object)
    return np.array(values, dtype={"float64": float, "int64": np.int64, "bool": bool}[kind])


def _statistics(values: np.ndarray, study: Study) -> dict[str, float]:
    """The :data:`STATISTICS` of the finite ``values`` [m] (module docstring)."""
    finite = values[np.isfinite(values)]
    if len(finite) == 0:
        return dict.fromkeys(STATISTICS, math.nan)
    out = {"below": float(np.mean(finite < study.target))}
    for name, q in (("median", 0.5), ("quantile", study.quantile)):
        out[name], out[f"{name}_low"], out[f"{name}_high"] = quantile_interval(finite, q, study.level)
    return out


def summarize(trials: Mapping[str, np.ndarray], study: Study) -> dict[str, np.ndarray]:
    """One row per point of ``study.points``, in that order (:data:`SUMMARY_COLUMNS`), from the
    trial table ``trials`` (:data:`~omnikin.sweep.study.TRIAL_COLUMNS`; strings as object arrays,
    null as None). A point without rows has ``trials`` 0 and NaN statistics; rows of points not
    in the study (a folder that also holds another grid's points) are not read."""
    keys = np.asarray(trials["point"], dtype=object)
    failed_rows = np.array([e is not None for e in trials["error"]], dtype=bool).reshape(len(keys))
    label = {i: s.label for s in series_of(study) for i in s.rows}
    rows: dict[str, list] = {name: [] for name, _ in SUMMARY_COLUMNS}
    for i, point in enumerate(study.points):
        key = point_key(point)
        mine = keys == key
        ok = mine & ~failed_rows
        rows["point"].append(key)
        for name in POINT_FIELDS:
            rows[name].append(getattr(point, name))
        rows["series"].append(label[i])
        rows["trials"].append(int(mine.sum()))
        rows["failed"].append(int((mine & failed_rows).sum()))
        for phase in PHASES:
            values = np.asarray(trials[f"e_max_syst_{phase}"], dtype=float)[ok]
            for stat, value in _statistics(values, study).items():
                rows[stat_column(stat, phase)].append(value)
        before = np.asarray(trials["e_max_syst_before"], dtype=float)[ok]
        after = np.asarray(trials["e_max_syst_after"], dtype=float)[ok]
        both = np.isfinite(before) & np.isfinite(after)
        before, after = before[both], after[both]
        reduction = before / np.maximum(after, RESOLUTION)
        rows["median_reduction"].append(float(np.median(reduction)) if len(reduction) else math.nan)
        rows["reduction_bound"].append(bool(np.any(after < RESOLUTION)))
    return {name: _column(rows[name], kind) for name, kind in SUMMARY_COLUMNS}


@dataclass(frozen=True)
class Answer:
    """The answer for one :class:`Series` in one phase: ``estimate`` from the quantile,
    ``conservative`` from the upper end of its interval (an unbounded end counts as above the
    target), both :class:`~omnikin.evaluation.threshold.Crossing` along ``axis`` in the factor's
    own unit (scale [-], radius [relative], hub [m], drive_deg [deg]). ``tolerances_at`` holds the
    series' other tolerance factors (None if they differ between its points); ``approximate`` for
    a random design, whose points differ in more than the axis."""

    series: Series
    phase: str
    axis: str
    estimate: Crossing
    conservative: Crossing
    tolerances_at: Mapping[str, float] | None
    approximate: bool = False

    def tolerances(self, value: float | None) -> tuple[float, float, float] | None:
        """The build tolerances at axis ``value`` as (radius [%], hub [mm], drive [deg]): scale
        times the series' radius, hub and drive_deg with the axis factor set to ``value``; None
        for a None ``value`` or when :attr:`tolerances_at` is None."""
        if value is None or self.tolerances_at is None:
            return None
        f = {**self.tolerances_at, self.axis: value}
        return (f["scale"] * f["radius"] * 100.0, f["scale"] * f["hub"] * 1000.0, f["scale"] * f["drive_deg"])

    @property
    def phase_text(self) -> str:
        """The phase in words: ``before calibration`` and ``after calibration`` for a series that
        calibrates, ``without calibration`` for one that does not (it describes no calibration)."""
        return phase_text(self.phase, self.series.calibrate)

    @property
    def text(self) -> str:
        """The answer in one line: ``omni3, before calibration: scale up to 1.25 (radius 0.625 %,
        hub 1.25 mm, drive 0.625 deg; crosses); conservative: 1.1``."""
        phase = self.phase_text
        found = crossing_text(self, self.estimate)
        triple = tolerances_text(self, self.estimate.value)
        detail = self.estimate.status + ("" if triple == "-" else f"; {triple}")
        return (
            f"{' '.join(self.series.label.split())[:120]}, {phase}: {AXIS_UNITS[self.axis][0]} {found} ({detail}); "
            f"conservative: {crossing_text(self, self.conservative)}" + (" (approximate)" if self.approximate else "")
        )


def phase_text(phase: str, calibrates: bool) -> str:
    """``before calibration``/``after calibration``, or ``without calibration`` for the one phase
    of points that do not calibrate."""
    if not calibrates:
        return "without calibration"
    return "before calibration" if phase == "before" else "after calibration"


def axis_text(axis: str, value: float) -> str:
    """A value of tolerance factor ``axis`` in the unit shown: ``1.25`` (scale), ``0.5 %``
    (radius), ``1 mm`` (hub), ``0.5 deg`` (drive_deg)."""
    label, factor = AXIS_UNITS[axis]
    unit = label.split("[")[1].rstrip("]")
    return f"{value * factor:.3g}" + ("" if unit == "-" else f" {unit}")


def tolerances_text(answer: Answer, value: float | None) -> str:
    """:meth:`Answer.tolerances` at ``value`` in words: ``radius 0.5 %, hub 1.25 mm, drive 0.375
    deg``; ``-`` for none."""
    triple = answer.tolerances(value)
    if triple is None:
        return "-"
    radius, hub, drive = triple
    return f"radius {radius:.3g} %, hub {hub:.3g} mm, drive {drive:.3g} deg"


def crossing_text(answer: Answer, crossing: Crossing) -> str:
    """A tolerance found in words: ``1.25``, ``at least 8`` (below over the whole grid), ``none``."""
    if crossing.value is None:
        return "none"
    text = axis_text(answer.axis, crossing.value)
    return f"at least {text}" if crossing.status == BELOW else text


def answers(summary: Mapping[str, np.ndarray], study: Study) -> list[Answer]:
    """Per series (:func:`series_of`) and phase (``before``; ``after`` when the series
    calibrates): the largest axis value at which ``summary``'s ``quantile_{phase}`` stays below
    ``study.target``, and the conservative one from ``quantile_{phase}_high`` (module docstring;
    rule: :func:`~omnikin.evaluation.threshold.threshold`). A random design's series are read the
    same way, points sorted by the axis (approximate: they differ in more than the axis)."""
    out = []
    for s in series_of(study):
        rows = list(s.rows)
        points = [study.points[i] for i in rows]
        x = [float(getattr(p, study.axis)) for p in points]
        others = {n: {float(getattr(p, n)) for p in points} for n in TOLERANCE_FACTORS if n != study.axis}
        at = {n: next(iter(v)) for n, v in others.items()} if all(len(v) == 1 for v in others.values()) else None
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
