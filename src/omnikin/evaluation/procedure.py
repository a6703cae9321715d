"""The UMBmark study of ``omnikin umbmark``: UMBmark, calibration, UMBmark again.

One procedure for every robot (:func:`umbmark_study`):

1. the robot as built: a seeded draw of an error profile applied to the nominal robot
   (or a given true robot);
2. UMBmark before calibration: ``trials`` procedures of ``runs`` runs per direction, the
   robot commanded by its nominal model (Borenstein and Feng, "Measurement and correction
   of systematic odometry errors in mobile robots", 1996);
3. calibration (unless switched off): every run of
   :func:`~omnikin.evaluation.calibration.recommended_runs` driven
   :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times by the nominal model, its
   end pose "measured" with the noise model's measurement error, and the least-squares
   calibration (:func:`~omnikin.evaluation.calibration.calibrate`) weighted exactly as
   ``omnikin calibrate`` weights the same runs read from a file; for a differential drive
   in ``rotate`` mode Borenstein's iterated correction too, for comparison;
4. UMBmark after calibration, the robot commanded by its calibrated model;
5. the noise floor (:class:`~omnikin.evaluation.umbmark.NoiseFloor`): the same UMBmark of
   the robot as built commanded by its own exact model, :data:`FLOOR_PROCEDURES` times;
6. the systematic part alone: UMBmark without random errors, before and after.

Every step draws its random numbers from its own stream of ``numpy.random.SeedSequence(seed)``
(:data:`STREAMS`), so the robot as built, the calibration runs and the first procedure do
not depend on ``trials``; the robot stream is the first child, as for ``omnikin simulate``,
so the same seed builds the same robot there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..common.messages import shorten
from ..common.resource_limits import DEFAULT_MEMORY, DEFAULT_TIME, LimitNames, require_within
from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.plans import CalibrationRun, umbmark_square
from ..motion.timing import check_rate_range, estimated_samples
from ..odometry.batch import encoded_wheels
from ..simulation.engine import Engine, KinematicEngine
from ..simulation.error_models import NOISE, NoiseModel, SystematicErrors
from ..simulation.simulate import simulate
from .calibration import RECOMMENDED_REPEATS, CalibrationResult, borenstein_calibrate, recommended_runs
from .calibration import calibrate as least_squares_calibration
from .run_poses import DIRECTIONS, RunPoses, kept_run, stride
from .umbmark import (
    LEVEL,
    NoiseFloor,
    UMBmarkResult,
    check_side,
    differential_pair,
    noise_floor,
    procedure_generators,
    reduction_interval,
    run_umbmark,
)

STREAMS = ("robot", "before", "trajectories", "calibration", "borenstein", "after", "floor")
"""Random streams, in the order of the children of ``SeedSequence(seed)``."""

FLOOR_PROCEDURES = 400
"""UMBmark procedures of the perfectly calibrated robot that make the noise floor."""

BORENSTEIN_ITERATIONS = 3
"""Iterations of Borenstein's correction in the comparison (differential drives)."""

ARGUMENTS = LimitNames("max_memory", "max_time")
"""The limits of a study as the Python entry points name them (:func:`check_cost`)."""

SAMPLES_PER_SECOND = 1e7
"""Simulation speed used to express a sample count as a time (docs/performance.md)."""

BYTES_PER_PROCEDURE = 4096
"""Memory of one kept UMBmark procedure (its result objects and return errors), generous."""


def streams(seed: int) -> dict:
    """The random stream of each step (:data:`STREAMS`) for ``seed``."""
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed (--seed) must be a whole number >= 0, got {seed!r}")
    return dict(zip(STREAMS, np.random.SeedSequence(int(seed)).spawn(len(STREAMS)), strict=True))


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


@dataclass(frozen=True)
class UMBmarkStudy:
    """Everything :func:`umbmark_study` found (module docstring); lengths in metres.

    ``before``/``after``: one :class:`~omnikin.evaluation.umbmark.UMBmarkResult` per trial
    (``after`` None without calibration); ``calibration_runs``: the simulated runs with
    their measured end poses (``label`` = the path in the runs-file grammar);
    ``borenstein``: E_max,syst [m] after each iteration of Borenstein's correction (or
    None); ``systematic``: E_max,syst [m] without random errors, ``{"before", "after"}``;
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
    noise: NoiseModel,
    seed: int,
    calibrate: bool,
    progress=None,
) -> UMBmarkStudy:
    """Run the study of the module docstring. ``true_robot``: the robot as built
    (:func:`draw_as_built`); ``progress``: called with the name of each step as it starts.
    The settings are checked first (:func:`check_settings`)."""
    check_settings(runs=runs, trials=trials, side=side, rate=rate)
    encoded_wheels(robot)  # UMBmark measures with the encoders: refuse a robot without them now
    rng = streams(seed)
    step = progress or (lambda name: None)
    opts: dict[str, Any] = dict(side=side, mode=mode, runs=runs, noise=noise, rate=rate)
    step("UMBmark before calibration")
    before = run_umbmark(true_robot, robot, trials=trials, rng=rng["before"], **opts)
    poses = first_procedure_poses("before", true_robot, robot, rng=rng["before"], **opts)
    step("trajectories for the figures")
    traj_rng = np.random.default_rng(rng["trajectories"])
    trajectories = {"before": _trajectories(true_robot, robot, traj_rng, **opts)}
    after: list | None = None
    cal: CalibrationResult | None = None
    bor: list | None = None
    cal_runs: list[CalibrationRun] = []
    quiet: dict[str, Any] = dict(opts, runs=1, noise=NOISE["none"])
    systematic = {"before": run_umbmark(true_robot, robot, **quiet)[0].e_max_syst}
    if calibrate:
        step("calibration runs")
        cal_runs = simulate_calibration_runs(
            true_robot, robot, side=side, noise=noise, rate=rate, rng=rng["calibration"]
        )
        step("least-squares calibration")
        cal = least_squares_calibration(robot, cal_runs)
        if differential_pair(robot) is not None and mode == "rotate":
            step("Borenstein's correction (comparison)")
            bor = _borenstein(true_robot, robot, before[0], np.random.default_rng(rng["borenstein"]), opts)
        step("UMBmark after calibration")
        after = run_umbmark(true_robot, cal.robot, trials=trials, rng=rng["after"], **opts)
        poses += first_procedure_poses("after", true_robot, cal.robot, rng=rng["after"], **opts)
        trajectories["after"] = _trajectories(true_robot, cal.robot, traj_rng, **opts)
        systematic["after"] = run_umbmark(true_robot, cal.robot, **quiet)[0].e_max_syst
    step("noise floor")
    floor = noise_floor(true_robot, procedures=FLOOR_PROCEDURES, rng=rng["floor"], **opts)
    return UMBmarkStudy(
        robot,
        true_robot,
        injected,
        side,
        mode,
        runs,
        rate,
        trials,
        noise,
        before,
        after,
        cal,
        cal_runs,
        bor,
        systematic,
        floor,
        trajectories,
        run_poses=tuple(poses),
    )


def first_procedure_poses(
    phase: str, true_robot: Robot, command: Robot, *, rng, side, mode, runs, noise, rate
) -> list[RunPoses]:
    """The runs of the first procedure of :func:`~omnikin.evaluation.umbmark.run_umbmark` with
    ``rng`` (the same draws: procedure 0's generator, cw runs then ccw runs, one run after the
    other), each kept at a bounded rate (:mod:`omnikin.evaluation.run_poses`); simulated one
    run at a time, so the memory is that of one run's ground truth."""
    generator = procedure_generators(rng, 1)[0]
    out = []
    for direction in DIRECTIONS:
        plan = umbmark_square(direction, side, mode)
        k = 0
        for run in range(1, runs + 1):
            sim = simulate(plan, true_robot, command, rate=rate, noise=noise, trials=1, rng=generator)
            k = k or stride(len(sim.t), rate, runs)
            out.append(kept_run(phase, direction, run, sim.t, sim.truth[0], sim.odometry, k))
    return out


def simulate_calibration_runs(
    true_robot: Robot, robot: Robot, *, side: float, noise: NoiseModel, rate: float, rng
) -> list[CalibrationRun]:
    """The recommended calibration runs of ``robot``, each driven
    :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times by ``true_robot``
    commanded by ``robot``, with their measured end poses and the default measurement sigma
    of :class:`~omnikin.motion.plans.CalibrationRun` (as a runs file is read)."""
    rng = np.random.default_rng(rng)
    out = []
    for text, plan in recommended_runs(robot, side):
        sim = simulate(
            plan, true_robot, robot, rate=rate, noise=noise, trials=RECOMMENDED_REPEATS, rng=rng, keep_truth=False
        )
        out += [CalibrationRun(plan, tuple(m), text) for m in sim.measured]
    return out


def _trajectories(true_robot: Robot, command: Robot, rng, *, side, mode, runs, noise, rate) -> dict:
    """The first run of each direction with its ground truth, for the figures."""
    return {
        d: simulate(umbmark_square(d, side, mode), true_robot, command, rate=rate, noise=noise, trials=1, rng=rng)
        for d in ("cw", "ccw")
    }


def _borenstein(true_robot: Robot, robot: Robot, first: UMBmarkResult, rng, opts) -> list:
    """Borenstein's iterated correction: E_max,syst [m] after each iteration."""
    out, model, res = [], robot, first
    for _ in range(BORENSTEIN_ITERATIONS):
        model = borenstein_calibrate(model, res)
        res = run_umbmark(true_robot, model, rng=rng, **opts)[0]
        out.append(res.e_max_syst)
    return out
