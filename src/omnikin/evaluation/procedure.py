"""The UMBmark study of ``omnikin umbmark``: UMBmark, calibration, UMBmark again.

:func:`umbmark_study` is the report's use of the one study pipeline
(:mod:`omnikin.evaluation.pipeline`, which defines the stages, the floor and the seed layout):
of the robot as built (a seeded draw of an error profile applied to the nominal robot, or a
given true robot, :func:`draw_as_built`) it keeps every UMBmark procedure before and after the
calibration, the calibration runs and fit, the runs of the first procedures
(:mod:`omnikin.evaluation.run_poses`), the first run of each direction for the figures, the
floor, Borenstein's correction (differential drives in ``rotate`` mode, kinematic engine) and
the systematic part; with any engine (:class:`~omnikin.simulation.engine.Engine`: the
kinematic engine with its noise model, or the physics engine,
:mod:`omnikin.evaluation.physics_study`).

This module also checks a study's settings (:func:`check_settings`) and estimates what it will
take (:func:`estimate_cost`, :func:`check_cost`). Every stage draws its random numbers from its
own stream of ``numpy.random.SeedSequence(seed)`` (:func:`streams`, the layout
:data:`~omnikin.evaluation.pipeline.REPORT_STREAMS`), so the robot as built, the calibration
runs and the first procedure do not depend on ``trials``; the robot stream is the first child,
as for ``omnikin simulate``, so the same seed builds the same robot there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..common.messages import shorten
from ..common.resource_limits import DEFAULT_MEMORY, DEFAULT_TIME, LimitNames, require_within
from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.plans import umbmark_square
from ..motion.timing import check_rate_range, estimated_samples
from ..odometry.batch import encoded_wheels
from ..simulation.engine import Engine, KinematicEngine
from ..simulation.error_models import NOISE, NoiseModel, SystematicErrors
from .calibration import RECOMMENDED_REPEATS, CalibrationResult, recommended_runs
from .pipeline import (
    BORENSTEIN_ITERATIONS,
    FLOOR_PROCEDURES,
    REPORT,
    REPORT_STREAMS,
    Square,
    run_pipeline,
    seed_streams,
)
from .run_poses import RunPoses
from .umbmark import LEVEL, NoiseFloor, check_side, differential_pair, reduction_interval

__all__ = [
    "ARGUMENTS",
    "AS_BUILT_FROM",
    "Cost",
    "UMBmarkStudy",
    "check_cost",
    "check_settings",
    "draw_as_built",
    "estimate_cost",
    "streams",
    "umbmark_study",
]

KINEMATIC = KinematicEngine()
"""The kinematic engine, the default engine of a study."""

ARGUMENTS = LimitNames("max_memory", "max_time")
"""The limits of a study as the Python entry points name them (:func:`check_cost`)."""

SAMPLES_PER_SECOND = 1e7
"""Simulation speed used to express a sample count as a time (docs/performance.md)."""

BYTES_PER_PROCEDURE = 4096
"""Memory of one kept UMBmark procedure (its result objects and return errors), generous."""


def streams(seed: int, layout: tuple[str, ...] = REPORT_STREAMS) -> dict[str, np.random.SeedSequence]:
    """The random stream of each step of ``layout`` for ``seed``.

    Parameters
    ----------
    seed : int
        The study's or run's seed (``--seed``), a whole number >= 0.
    layout : tuple of str
        The names of the streams in the order they are spawned from ``SeedSequence(seed)``
        (:data:`~omnikin.evaluation.pipeline.REPORT_STREAMS`, the default;
        :data:`~omnikin.evaluation.pipeline.RUN_STREAMS` for one simulated run).

    Returns
    -------
    dict of str to numpy.random.SeedSequence
        The stream of each name of ``layout`` (:func:`~omnikin.evaluation.pipeline.seed_streams`).

    Raises
    ------
    InputError
        In one line, a ``seed`` that is not a whole number >= 0.
    """
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed (--seed) must be a whole number >= 0, got {seed!r}")
    return seed_streams(np.random.SeedSequence(int(seed)), layout)


def check_settings(*, runs, trials, side, rate) -> None:
    """Refuse the first bad setting of a study with one line naming it and its command-line
    option: ``runs`` and ``trials`` whole numbers >= 1, ``side`` within
    :data:`~omnikin.evaluation.umbmark.SIDE_RANGE`, ``rate`` within
    :data:`~omnikin.motion.timing.RATE_RANGE` (that of every simulated run)."""
    for name, value in (("runs", runs), ("trials", trials)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InputError(f"{name} (--{name}) must be a whole number >= 1, got {shorten(value)}")
    check_side(side)
    check_rate_range(rate, "rate (--rate)")


AS_BUILT_FROM = (
    "the errors profile (--errors) and seed (--seed)",
    "choose errors none, another seed or a larger robot",
)
"""How :func:`draw_as_built` names the draw and the way out, by default (``omnikin umbmark``)."""


def draw_as_built(robot: Robot, profile, seed, *, drawn_from: tuple[str, str] = AS_BUILT_FROM):
    """The robot as built: a draw of the error ``profile``
    (:class:`~omnikin.simulation.error_models.ErrorProfile`) from ``seed`` (a SeedSequence or
    int) applied to ``robot``. Returns the true robot and the errors drawn. A draw that takes a
    field out of its range is an InputError naming the robot, where the draw came from and the
    way out (``drawn_from``: both as words)."""
    try:
        drawn = profile.sample(robot, np.random.default_rng(seed))
        return drawn.apply(robot), drawn
    except InputError as exc:  # a drawn error took a field out of its range: say it is the draw's
        raise InputError(
            f"robot {robot.name!r} as built (its systematic errors drawn from {drawn_from[0]}) is not a valid robot: "
            f"{exc}; {drawn_from[1]}"
        ) from None


@dataclass(frozen=True)
class Cost:
    """What a study will take: ``samples`` robot-samples simulated, ``bytes`` of memory and
    ``seconds_per_sample`` [s] of computing time per sample (the kinematic engine's
    :data:`SAMPLES_PER_SECOND` by default)."""

    samples: float
    bytes: float
    seconds_per_sample: float = 1.0 / SAMPLES_PER_SECOND

    @property
    def seconds(self) -> float:
        """Computing time [s]."""
        return self.samples * self.seconds_per_sample


def estimate_cost(
    robot: Robot, *, side: float, mode: str, runs: int, rate: float, trials: int, calibrate: bool
) -> Cost:
    """Samples and memory of :func:`umbmark_study` with these settings, from the lengths of the
    square and of the calibration runs (:func:`~omnikin.motion.timing.estimated_samples`, an
    upper bound computed without sampling)."""
    square = estimated_samples(umbmark_square("cw", side, mode), robot, rate)
    procedures = trials * (2 if calibrate else 1) + FLOOR_PROCEDURES + (2 if calibrate else 1)  # + the run poses
    samples = 2.0 * runs * square * procedures + 2 * 2 * 2 * square  # + systematic part, trajectories
    if calibrate:
        samples += (
            sum(estimated_samples(plan, robot, rate) for _, plan in recommended_runs(robot, side)) * RECOMMENDED_REPEATS
        )
        if differential_pair(robot) is not None and mode == "rotate":
            samples += 2.0 * runs * square * BORENSTEIN_ITERATIONS
    memory = procedures * (BYTES_PER_PROCEDURE + 2 * runs * 3 * 8 * 4) + 4 * square * 3 * 8 * 8 + 64 * 1024**2
    return Cost(samples, memory)


def check_cost(cost: Cost, *, max_memory=DEFAULT_MEMORY, max_time=DEFAULT_TIME) -> None:
    """Refuse (:class:`~omnikin.errors.ResourceLimitError`, one line naming the limit as the
    argument ``max_memory`` or ``max_time``) a study estimated to need more than ``max_memory``
    [bytes] or ``max_time`` [s]: the check of :func:`omnikin.common.resource_limits.require_within`,
    which ``omnikin umbmark`` makes too (naming its options)."""
    require_within(
        "UMBmark study",
        memory=cost.bytes,
        seconds=cost.seconds,
        max_memory=max_memory,
        max_time=max_time,
        names=ARGUMENTS,
        hint="lower trials, runs or rate",
        size=f"{cost.samples:.3g} robot-samples",
    )


@dataclass(frozen=True, kw_only=True)
class UMBmarkStudy:
    """Everything :func:`umbmark_study` found (module docstring); lengths in metres.

    ``before``/``after``: one :class:`~omnikin.evaluation.umbmark.UMBmarkResult` per trial
    (``after`` None without calibration); ``calibration_runs``: the simulated runs with
    their measured end poses (``label`` = the path in the runs-file grammar);
    ``borenstein``: E_max,syst [m] after each iteration of Borenstein's correction (or
    None where it was not run); ``calibration`` None without calibration (or, physics, when the
    runs made the fit impossible: ``problems`` says why); ``systematic``: E_max,syst [m]
    without random errors, ``{"before", "after"}`` (physics: the first procedures');
    ``trajectories``: ``{"before"|"after": {"cw"|"ccw": SimulatedRun}}``, the first run of
    each direction with its ground truth; ``engine``: the engine every run was driven by, the
    :class:`~omnikin.simulation.engine.KinematicEngine` (this module) or the physics engine
    (:mod:`omnikin.evaluation.physics_study`, whose ``floor`` is the nominal robot's UMBmark).
    """

    robot: Robot
    true_robot: Robot
    injected: SystematicErrors | None
    side: float
    mode: str
    runs: int
    rate: float
    trials: int
    noise: NoiseModel
    before: list
    after: list | None
    calibration: CalibrationResult | None
    calibration_runs: list
    borenstein: list | None
    systematic: dict
    floor: NoiseFloor
    trajectories: dict
    level: float = LEVEL
    engine: Engine = KinematicEngine()
    problems: tuple[str, ...] = ()
    """Physics engine: one line per run that did not drive as commanded, naming the run
    (:meth:`omnikin.physics.run.PhysicsRun.problems`); its end pose is in the statistics."""
    run_poses: tuple[RunPoses, ...] = ()
    """The poses over time of every run of the first procedure before (and after) calibration,
    at a bounded rate (:mod:`omnikin.evaluation.run_poses`): the runs of the measurement files."""

    @property
    def reduction_factor(self) -> float | None:
        """E_max,syst before over after (first procedure), or None without calibration."""
        if self.after is None:
            return None
        b, a = self.before[0].e_max_syst, self.after[0].e_max_syst
        return b / a if a > 0 else math.inf

    @property
    def reduction_interval(self) -> tuple[float, float] | None:
        """Confidence interval of :attr:`reduction_factor`
        (:func:`~omnikin.evaluation.umbmark.reduction_interval`)."""
        if self.after is None:
            return None
        return reduction_interval(self.before[0], self.after[0], self.level)

    def first(self) -> dict:
        """The first procedure of each stage: ``{"before": UMBmarkResult, "after calibration": ...}``."""
        out = {"before": self.before[0]}
        if self.after is not None:
            out["after calibration"] = self.after[0]
        return out


def umbmark_study(
    robot: Robot,
    true_robot: Robot,
    *,
    injected: SystematicErrors | None = None,
    side: float,
    mode: str,
    runs: int,
    rate: float,
    trials: int,
    noise: NoiseModel | None = None,
    seed: int,
    calibrate: bool,
    engine: Engine = KINEMATIC,
    progress=None,
    level: float = LEVEL,
) -> UMBmarkStudy:
    """Run the study of the module docstring: the pipeline
    (:func:`~omnikin.evaluation.pipeline.run_pipeline`) keeping what the report shows
    (:data:`~omnikin.evaluation.pipeline.REPORT`).

    ``true_robot``: the robot as built (:func:`draw_as_built`); ``noise``: the random errors of
    an engine with a noise model (:meth:`~omnikin.simulation.engine.Engine.noise_model`; None
    for the physics engine, whose study then records no noise); ``engine``: drives every run;
    ``level``: the confidence level of the intervals; ``progress``: called with the name of each
    step as it starts (physics: of each run). The settings are checked first
    (:func:`check_settings`, the engine's :meth:`~omnikin.simulation.engine.Engine.check_rate`)."""
    check_settings(runs=runs, trials=trials, side=side, rate=rate)
    engine.check_rate(rate)
    encoded_wheels(robot)  # UMBmark measures with the encoders: refuse a robot without them now
    square = Square(side=side, mode=mode, runs=runs, rate=rate, noise=noise, trials=trials, level=level)
    found = run_pipeline(
        robot,
        true_robot,
        engine=engine,
        square=square,
        streams=streams(seed),
        calibrate=calibrate,
        keep=REPORT,
        progress=progress,
    )
    assert found.floor is not None  # the report keeps it
    return UMBmarkStudy(
        robot=robot,
        true_robot=true_robot,
        injected=injected,
        side=side,
        mode=mode,
        runs=runs,
        rate=rate,
        trials=trials,
        noise=NOISE["none"] if noise is None else noise,
        before=found.before,
        after=found.after,
        calibration=found.calibration,
        calibration_runs=found.calibration_runs,
        borenstein=found.borenstein,
        systematic=found.systematic,
        floor=found.floor,
        trajectories=found.trajectories,
        level=level,
        engine=engine,
        problems=found.problems,
        run_poses=found.poses,
    )
