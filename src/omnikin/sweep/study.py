"""A tolerance study as ``omnikin sweep`` runs it, and the columns of its tables.

:class:`Study` is what a study file (:mod:`omnikin.sweep.spec`) becomes: the points to run
(:class:`~omnikin.sweep.points.Point`), the nominal robots they name, trials per point, the
study's seed and the question it asks: the tolerances for which the ``quantile`` (95 %) of
``E_max,syst`` stays below ``target`` [m] (10 mm), with and without calibration.

The trial table (:data:`TRIAL_COLUMNS`, one row per trial, Parquet) is tidy: a point's
settings, its key, the trial's index, what the trial measured [m] and, for a trial that
failed, the one-line reason (``error``; its numbers are NaN). ``seconds`` is the trial's
computing time, the only column that differs between two runs of the same study.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from ..kinematics.robot import Robot
from .points import POINT_FIELDS, TOLERANCE_FACTORS, Point

DESIGNS = ("grid", "random")

RESULT_COLUMNS = (
    "e_max_syst_before",
    "e_max_syst_after",
    "systematic_before",
    "systematic_after",
    "reduction",
)
"""What a trial measured (:class:`~omnikin.evaluation.tolerance_trial.TrialResult`) [m; reduction: ratio]."""

_POINT_TYPES = {
    "robot": "string",
    "robot_hash": "string",
    "scale": "float64",
    "radius": "float64",
    "hub": "float64",
    "drive_deg": "float64",
    "noise": "string",
    "ticks_per_rev": "int64",
    "rate": "float64",
    "calibrate": "bool",
    "engine": "string",
    "side": "float64",
    "mode": "string",
    "runs": "int64",
}

TRIAL_COLUMNS: tuple[tuple[str, str], ...] = (
    ("point", "string"),
    *((name, _POINT_TYPES[name]) for name in POINT_FIELDS),
    ("trial", "int64"),
    *((name, "float64") for name in RESULT_COLUMNS),
    ("error", "string"),
    ("seconds", "float64"),
)
"""Name and Arrow type of every column of the trial table, in order (module docstring); ``noise``,
``ticks_per_rev`` and ``error`` may be null."""


@dataclass(frozen=True)
class Study:
    """A study ready to run (module docstring). ``robots`` maps each point's ``robot`` to the
    nominal robot; ``digest`` is a hash of everything that decides the results (points, robots'
    content, trials, seed), so that a rerun can tell whether a folder holds this study."""

    source: str
    name: str
    seed: int
    trials: int
    design: str
    points: tuple[Point, ...]
    robots: Mapping[str, Robot]
    target: float = 0.010
    quantile: float = 0.95
    level: float = 0.95
    digest: str = ""

    @property
    def axis(self) -> str:
        """The tolerance factor drawn along the x axis of the figures: the first of
        :data:`~omnikin.sweep.points.TOLERANCE_FACTORS` that takes more than one value, else ``scale``."""
        for name in TOLERANCE_FACTORS:
            if len({getattr(p, name) for p in self.points}) > 1:
                return name
        return "scale"
