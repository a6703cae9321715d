"""One trial of a tolerance study: a robot built within given tolerances, its UMBmark, its
calibration and its UMBmark again (the unit of work of ``omnikin sweep``).

A trial draws one robot as built from the tolerance profile (standard deviations of the
systematic errors, :class:`~omnikin.simulation.error_models.ErrorProfile`: wheel radius,
radial and tangential hub position, drive direction, ...), runs one UMBmark procedure
(Borenstein and Feng's square, ``runs`` runs per direction, :func:`~omnikin.evaluation.umbmark.simulate_umbmark`),
and, with ``calibrate``, the recommended calibration runs, the least-squares calibration
(:func:`~omnikin.evaluation.calibration.least_squares_calibration`) and the UMBmark procedure again with the
calibrated robot. Beside the measured ``E_max,syst`` it reports the systematic part alone: the
same procedures without random errors (one run per direction), before and after.

A trial is the study pipeline (:mod:`omnikin.evaluation.pipeline`) keeping only these numbers.
With an engine without a noise model (the physics engine,
:class:`~omnikin.physics.engines.PhysicsEngine`) every run is driven in MuJoCo (rollers and
motors; the runs' randomness is the wheels' roller phases, no noise model): the systematic
parts are then NaN (the physics has no noise to leave out).

Unlike :func:`~omnikin.evaluation.procedure.umbmark_study` (one robot as built, its report with
figures and a noise floor), a trial is cheap (about 0.15 s for tomasi-omni3 at the defaults, one
core) and its randomness comes from one :class:`numpy.random.SeedSequence`, split into the
streams :data:`~omnikin.evaluation.pipeline.TRIAL_STREAMS` in a fixed order: the same seed gives
the same trial on any machine, in any order of trials.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..common.messages import shorten
from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.plans import UMBMARK_SIDE
from ..simulation.engine import Engine, KinematicEngine
from ..simulation.error_models import NOISE, ErrorProfile, NoiseModel
from .pipeline import TRIAL, TRIAL_STREAMS, Square, run_pipeline, seed_streams
from .procedure import check_settings, draw_as_built

AS_BUILT = ("the tolerances and the trial's seed", "lower the tolerances")
"""How a trial's invalid robot as built is named (:func:`~omnikin.evaluation.procedure.draw_as_built`)."""


@dataclass(frozen=True)
class TrialSettings:
    """How a trial runs UMBmark: square ``side`` [m], ``mode`` (rotate or translate), ``runs``
    per direction, sample ``rate`` [Hz], random errors ``noise``, whether it calibrates, and the
    ``engine`` its runs are driven by (an :class:`~omnikin.simulation.engine.Engine`; a point
    of a study makes it from the name it stores, :attr:`omnikin.sweep.points.Point.settings`)."""

    side: float = UMBMARK_SIDE
    mode: str = "rotate"
    runs: int = 5
    rate: float = 100.0
    noise: NoiseModel = field(default_factory=lambda: NOISE["typical"])
    calibrate: bool = True
    engine: Engine = KinematicEngine()

    def __post_init__(self):
        check_settings(runs=self.runs, trials=1, side=self.side, rate=self.rate)
        if not isinstance(self.engine, Engine):
            raise InputError(
                "engine must be an Engine object (omnikin.engine_named makes one from a name), "
                f"got {shorten(self.engine)}"
            )


@dataclass(frozen=True, kw_only=True)
class TrialResult:
    """What one trial measured [m]: ``e_max_syst_before``/``after`` (UMBmark's measure of the
    procedure, with the random errors), ``systematic_before``/``after`` (the same without
    random errors); the ``after`` values are NaN without calibration."""

    e_max_syst_before: float
    e_max_syst_after: float
    systematic_before: float
    systematic_after: float

    @property
    def reduction(self) -> float:
        """``e_max_syst_before / e_max_syst_after`` (NaN without calibration)."""
        return self.e_max_syst_before / self.e_max_syst_after if self.e_max_syst_after > 0 else math.nan

    def as_dict(self) -> dict[str, float]:
        return {
            "e_max_syst_before": self.e_max_syst_before,
            "e_max_syst_after": self.e_max_syst_after,
            "systematic_before": self.systematic_before,
            "systematic_after": self.systematic_after,
        }


def trial_streams(seed: np.random.SeedSequence) -> dict[str, np.random.SeedSequence]:
    """The streams of :data:`TRIAL_STREAMS` spawned from ``seed``
    (:func:`~omnikin.evaluation.pipeline.seed_streams`)."""
    return seed_streams(seed, TRIAL_STREAMS)


def tolerance_trial(
    robot: Robot, tolerances: ErrorProfile, settings: TrialSettings, seed: np.random.SeedSequence
) -> TrialResult:
    """One trial (module docstring) of ``robot`` built within ``tolerances``: the study pipeline
    (:func:`~omnikin.evaluation.pipeline.run_pipeline`) keeping E_max,syst of the first procedure
    before and after, and the systematic part (:data:`~omnikin.evaluation.pipeline.TRIAL`)."""
    streams = trial_streams(seed)
    true_robot, _ = draw_as_built(robot, tolerances, streams["robot"], drawn_from=AS_BUILT)
    engine = settings.engine
    square = Square(
        side=settings.side,
        mode=settings.mode,
        runs=settings.runs,
        rate=settings.rate,
        noise=settings.noise,  # the physics engine's runs take none (its randomness: roller phases)
    )
    found = run_pipeline(
        robot, true_robot, engine=engine, square=square, streams=streams, calibrate=settings.calibrate, keep=TRIAL
    )
    return TrialResult(
        e_max_syst_before=found.before[0].e_max_syst,
        e_max_syst_after=found.after[0].e_max_syst if found.after is not None else math.nan,
        systematic_before=found.systematic["before"],
        systematic_after=found.systematic.get("after", math.nan),
    )
