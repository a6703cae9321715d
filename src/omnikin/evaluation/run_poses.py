"""The poses of the UMBmark runs over time, as a report keeps them (``run_poses.csv``).

A :class:`RunPoses` is one run of the first UMBmark procedure of a stage (``phase`` before or
after calibration, ``direction`` cw or ccw, ``run`` 1, 2, ...): its times [s] from the run's
start, the true pose and the odometry pose ``(x, y, theta)`` [m, m, rad] in the start frame
(first leg along +x, ``docs/conventions.md``). These are the runs whose end points the
measurement files hold (``measurements_before.csv``: ``x_abs - x_calc`` is the true end minus
the odometry end of each run).

A run is kept at a bounded rate (:func:`decimated`): every ``k``-th sample of the simulation,
``k`` the least that gives at most :data:`MAX_RATE` and at most :data:`MAX_ROWS` samples per
phase and direction, and always the run's last sample (its end pose, unchanged). So a report
stays a few MB whatever ``--rate`` and ``--runs``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PHASES = ("before", "after")
"""The stages of a study: UMBmark before and after calibration."""
DIRECTIONS = ("cw", "ccw")
MAX_RATE = 20.0
"""Highest rate [Hz] the poses of a run are kept at."""
MAX_ROWS = 25_000
"""Most samples kept per phase and direction (all its runs together)."""


@dataclass(frozen=True)
class RunPoses:
    """One run (module docstring): ``t`` ``(n,)`` [s] increasing, ``truth`` and ``odometry``
    ``(n, 3)`` [m, m, rad]; ``run`` counts from 1."""

    phase: str
    direction: str
    run: int
    t: np.ndarray
    truth: np.ndarray
    odometry: np.ndarray

    @property
    def name(self) -> str:
        """``before cw run 1``."""
        return f"{self.phase} {self.direction} run {self.run}"


def stride(samples: int, rate: float, runs: int, max_rate: float = MAX_RATE, max_rows: int = MAX_ROWS) -> int:
    """The least ``k >= 1`` such that every ``k``-th of ``samples`` samples per run at ``rate``
    [Hz] is at most ``max_rate`` and ``runs`` runs keep at most ``max_rows`` samples."""
    by_rate = math.ceil(rate / max_rate - 1e-9)
    per_run = max(1, max_rows // max(runs, 1) - 1)  # one more for the last sample
    by_rows = math.ceil(samples / per_run)
    return max(1, by_rate, by_rows)


def decimated(t, truth, odometry, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every ``k``-th sample from the first, and the last sample."""
    keep = np.arange(0, len(t), k)
    if keep[-1] != len(t) - 1:
        keep = np.append(keep, len(t) - 1)
    return (
        np.asarray(t, dtype=float)[keep],
        np.asarray(truth, dtype=float)[keep],
        np.asarray(odometry, dtype=float)[keep],
    )


def kept_run(phase: str, direction: str, run: int, t, truth, odometry, k: int) -> RunPoses:
    """A :class:`RunPoses` of a simulated run's full series, every ``k``-th sample kept."""
    tt, tr, od = decimated(t, truth, odometry, k)
    return RunPoses(phase, direction, run, tt, tr, od)
