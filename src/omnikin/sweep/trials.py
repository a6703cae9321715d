"""The task of a study: trials ``first`` to ``stop - 1`` of one point, as the rows of the trial table.

:func:`run_trials` is what a Dask worker runs (it needs neither Dask nor Arrow): each trial is
:func:`~omnikin.evaluation.tolerance_trial.tolerance_trial` of the point's robot (with the
point's encoder resolution) built within the point's tolerances, seeded by
:func:`~omnikin.sweep.points.trial_seed`. A trial that omnikin refuses (an
:class:`~omnikin.errors.OmnikinError`: a robot drawn outside the valid range, a calibration
that cannot be fitted, a physics run that failed) is a row with its one-line reason in
``error`` and NaN results: the same seed gives the same refusal, so it is a result of the study.
Any other exception is a fault of the task (a bug, a worker out of memory) and propagates: the
runner retries the task and, failing again, reports its trials as failed without writing them,
so that the next run computes them again.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence

from ..common.messages import one_line
from ..errors import OmnikinError
from ..evaluation.tolerance_trial import tolerance_trial
from ..kinematics.robot import Robot
from .points import POINT_FIELDS, Point, point_key, trial_seed
from .study import RESULT_COLUMNS, TRIAL_COLUMNS


def error_rows(point: Point, trials: range, reason: str) -> dict[str, list]:
    """Rows of the trial table for ``trials`` of ``point`` that failed with ``reason`` (one line)."""
    return _rows(point, [(k, None, reason, math.nan) for k in trials])


def run_trials(robot: Robot, point: Point, seed: int, first: int, stop: int) -> dict[str, list]:
    """Trials ``first <= k < stop`` of ``point`` (``robot``: its nominal robot; ``seed``: the
    study's), as columns of :data:`~omnikin.sweep.study.TRIAL_COLUMNS` (module docstring)."""
    nominal = point.robot_for(robot)
    tolerances, settings = point.tolerances, point.settings
    done: list[tuple[int, dict[str, float] | None, str | None, float]] = []
    for k in range(first, stop):
        start = time.perf_counter()
        try:
            result = tolerance_trial(nominal, tolerances, settings, trial_seed(seed, point, k))
        except OmnikinError as exc:
            done.append((k, None, f"trial {k}: {one_line(exc)}", time.perf_counter() - start))
            continue
        done.append((k, result.as_dict() | {"reduction": result.reduction}, None, time.perf_counter() - start))
    return _rows(point, done)


def _rows(point: Point, done: Sequence[tuple[int, Mapping[str, float] | None, str | None, float]]) -> dict[str, list]:
    columns: dict[str, list] = {name: [] for name, _ in TRIAL_COLUMNS}
    settings = point.as_dict()
    key = point_key(point)
    for trial, values, error, seconds in done:
        columns["point"].append(key)
        for name in POINT_FIELDS:
            columns[name].append(settings[name])
        columns["trial"].append(trial)
        for name in RESULT_COLUMNS:
            columns[name].append(math.nan if values is None else float(values[name]))
        columns["error"].append(error)
        columns["seconds"].append(seconds)
    return columns
