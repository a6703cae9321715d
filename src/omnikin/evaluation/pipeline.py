"""The one study pipeline: UMBmark, calibration, UMBmark again, and its floor.

Every UMBmark study of omnikin is this pipeline (:func:`run_pipeline`); its users differ only in
what they keep (:class:`Keep`): the report of ``omnikin umbmark``
(:func:`omnikin.evaluation.procedure.umbmark_study`) keeps the run poses, the trajectories, the
floor and Borenstein's correction; a sweep's trial
(:func:`omnikin.evaluation.tolerance_trial.tolerance_trial`) keeps E_max,syst and the
systematic part. The stages, in order:

1. **before**: UMBmark of the robot as built commanded by its nominal model, ``trials``
   procedures of ``runs`` runs per direction (Borenstein and Feng, "Measurement and correction
   of systematic odometry errors in mobile robots", 1996);
2. **calibration**: every run of :func:`~omnikin.evaluation.calibration.recommended_runs` driven
   :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times by the nominal model, its
   end pose measured, and the least-squares calibration
   (:func:`~omnikin.evaluation.calibration.least_squares_calibration`); for a differential drive in ``rotate``
   mode with an engine that has a noise model, Borenstein's iterated correction too
   (:data:`BORENSTEIN_ITERATIONS`), for comparison;
3. **after**: UMBmark again, the robot commanded by its calibrated model;
4. **floor**: what UMBmark shows when the calibration cannot do better. With a noise model
   (kinematic engine) the :class:`~omnikin.evaluation.umbmark.NoiseFloor`: the robot as built
   commanded by its own exact model, :data:`FLOOR_PROCEDURES` procedures. Without one (physics
   engine) the :class:`~omnikin.evaluation.umbmark.PhysicsFloor`: the *nominal* robot commanded
   by itself, ``trials`` procedures (what the roller contact alone gives);
5. **systematic**: E_max,syst without random errors (one run per direction, noise none), before
   and after; an engine without a noise model cannot tell it apart (:attr:`Keep.systematic`).

The engine (an :class:`~omnikin.simulation.engine.Engine` object, never a name) drives every
run. How its runs make a stage is the engine's (:func:`stage_runs`): the kinematic engine,
whose runs are one vectorised computation with a noise model, runs all of a stage's trials at
once (:func:`~omnikin.evaluation.umbmark.simulate_umbmark`); the physics engine drives one run at a
time, each wheel starting at a roller phase drawn from the stage's stream, and names the runs
that did not drive as commanded.

Seed layout
-----------
Every stage draws from its own stream: a child of one :class:`numpy.random.SeedSequence`,
spawned in the fixed order of a layout (:func:`seed_streams`), so a stage's draws do not depend
on the other stages nor on ``trials`` (procedure ``k`` of a stage draws from the ``k``-th child
of its stream, :func:`~omnikin.evaluation.umbmark.procedure_generators`; a physics stage's cw
and ccw runs from its two spawned children). Three layouts, each fixed because its numbers are
published:

- :data:`REPORT_STREAMS` ``robot, before, trajectories, calibration, borenstein, after, floor``
  from ``SeedSequence(--seed)`` (``omnikin umbmark``; the robot stream is the first child, as
  for ``omnikin simulate``, so the same seed builds the same robot there);
- :data:`TRIAL_STREAMS` ``robot, before, calibration, after`` from a trial's own SeedSequence
  (``omnikin sweep``: a trial keeps no trajectories, Borenstein nor floor);
- :data:`RUN_STREAMS` ``robot, run`` from ``SeedSequence(--seed)``: one simulated run
  (``omnikin simulate``) and the robot as built of ``omnikin sim`` and ``omnikin ros``, the
  robot drawn from the first child as in the report.

A stage a layout does not name is not run.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from ..errors import CalibrationFitError
from ..kinematics.robot import Robot
from ..motion.plans import CalibrationRun, Plan, umbmark_square
from ..simulation.engine import Engine
from ..simulation.error_models import NOISE, NoiseModel
from ..simulation.kinematic import simulate_kinematic
from .calibration import (
    RECOMMENDED_REPEATS,
    CalibrationResult,
    borenstein_calibrate,
    least_squares_calibration,
    recommended_runs,
)
from .run_poses import DIRECTIONS, RunPoses, kept_run, stride
from .umbmark import (
    LEVEL,
    NoiseFloor,
    PhysicsFloor,
    UMBmarkResult,
    analyze,
    differential_pair,
    noise_floor,
    procedure_generators,
    require_square,
    simulate_umbmark,
)

REPORT_STREAMS = ("robot", "before", "trajectories", "calibration", "borenstein", "after", "floor")
"""The streams of the report's study (``omnikin umbmark``), in the order of the children of
``SeedSequence(seed)`` (module docstring)."""

TRIAL_STREAMS = ("robot", "before", "calibration", "after")
"""The streams of a sweep's trial, spawned in this order from the trial's SeedSequence."""

RUN_STREAMS = ("robot", "run", "sensors")
"""The streams of one simulated run (``omnikin simulate``; the robot as built of ``omnikin sim``
and of ``omnikin ros``'s simulated back-ends), spawned in this order from ``SeedSequence(seed)``:
the robot stream is the first child, as in :data:`REPORT_STREAMS`, so the same seed builds the
same robot as built in every command; the run draws its random errors from the second, the
robot's IMUs and lidars theirs from the third (spawned last: the first two stay what they were
before sensors existed)."""

FLOOR_PROCEDURES = 400
"""UMBmark procedures of the perfectly calibrated robot that make the noise floor."""

BORENSTEIN_ITERATIONS = 3
"""Iterations of Borenstein's correction in the comparison (differential drives)."""

Progress = Callable[[str], None]
"""Called with the name of each stage as it starts (physics: of each run)."""


def seed_streams(seed: np.random.SeedSequence, layout: tuple[str, ...]) -> dict[str, np.random.SeedSequence]:
    """The stream of each stage of ``layout`` (:data:`REPORT_STREAMS`, :data:`TRIAL_STREAMS`,
    :data:`RUN_STREAMS`):
    the children of ``seed`` spawned in the layout's order (module docstring)."""
    return dict(zip(layout, seed.spawn(len(layout)), strict=True))


@dataclass(frozen=True, kw_only=True)
class Keep:
    """What a user of :func:`run_pipeline` keeps beyond the UMBmark results and the calibration.

    ``poses``: every run of the first procedure before (and after) calibration at a bounded
    rate (:mod:`omnikin.evaluation.run_poses`); ``trajectories``: the first run of each
    direction with its ground truth; ``floor``: the floor (module docstring);
    ``borenstein``: Borenstein's correction where it applies; ``systematic``: E_max,syst
    without random errors (True: measured where the engine can tell it apart, NaN where it
    cannot; False: the first procedure's E_max,syst stands for it where the engine cannot);
    ``problems``: name the runs that did not drive as commanded (and end the study without an
    ``after`` when they make the calibration impossible, instead of raising)."""

    poses: bool = False
    trajectories: bool = False
    floor: bool = False
    borenstein: bool = False
    systematic: bool = True
    problems: bool = False


REPORT = Keep(poses=True, trajectories=True, floor=True, borenstein=True, systematic=False, problems=True)
"""What the report keeps."""

TRIAL = Keep(systematic=True)
"""What a sweep's trial keeps."""


@dataclass(frozen=True, kw_only=True)
class PipelineResult:
    """What :func:`run_pipeline` found; lengths in metres.

    ``before``/``after``: one :class:`~omnikin.evaluation.umbmark.UMBmarkResult` per procedure
    (``after`` None without calibration); ``calibration`` the least-squares fit (None without
    calibration, or when the runs made it impossible and ``problems`` says so);
    ``calibration_runs`` the runs with their measured end poses; ``borenstein`` E_max,syst [m]
    after each iteration of Borenstein's correction (None where not run); ``systematic``
    ``{"before", "after"}`` E_max,syst [m] without random errors; ``floor`` (None unless kept);
    ``trajectories`` ``{"before"|"after": {"cw"|"ccw": SimulatedRun}}``; ``poses`` the
    :class:`~omnikin.evaluation.run_poses.RunPoses` of the first procedures; ``problems`` one
    line per run that did not drive as commanded."""

    before: list[UMBmarkResult]
    after: list[UMBmarkResult] | None = None
    calibration: CalibrationResult | None = None
    calibration_runs: list[CalibrationRun]
    borenstein: list[float] | None = None
    systematic: dict[str, float]
    floor: NoiseFloor | None = None
    trajectories: dict
    poses: tuple[RunPoses, ...] = ()
    problems: tuple[str, ...] = ()


@dataclass(frozen=True, kw_only=True)
class Square:
    """The UMBmark settings of a study: square ``side`` [m], ``mode``, ``runs`` per direction,
    sample ``rate`` [Hz], ``noise`` (None for an engine without a noise model), ``trials``
    procedures, the confidence ``level`` of the floor's interval."""

    side: float
    mode: str
    runs: int
    rate: float
    noise: NoiseModel | None
    trials: int = 1
    level: float = LEVEL


class StageRuns(Protocol):
    """How an engine's runs make the stages of the pipeline (:func:`stage_runs`)."""

    def umbmark(
        self, true_robot: Robot, command: Robot, seed, *, trials: int, label: str, phase: str, keep: Keep, out: _Out
    ) -> tuple[list[UMBmarkResult], dict | None]: ...

    def calibration_runs(self, true_robot: Robot, robot: Robot, seed, out: _Out) -> list[CalibrationRun]: ...

    def fit(self, robot: Robot, runs: list[CalibrationRun], keep: Keep, out: _Out) -> CalibrationResult | None: ...

    def systematic(self, true_robot: Robot, command: Robot, first: UMBmarkResult, keep: Keep) -> float: ...

    def trajectories(
        self, true_robot: Robot, command: Robot, first: dict | None, rng: np.random.Generator, phase: str, out: _Out
    ) -> dict: ...

    def borenstein(
        self, true_robot: Robot, robot: Robot, first: UMBmarkResult, seed, out: _Out
    ) -> list[float] | None: ...

    def floor(self, true_robot: Robot, robot: Robot, seed, out: _Out) -> NoiseFloor: ...


@dataclass
class _Out:
    """What the stages collect as they run: poses, problems, the progress callback."""

    progress: Progress
    poses: list[RunPoses]
    problems: list[str] | None


@dataclass(frozen=True)
class _VectorisedRuns:
    """The stages of an engine with a noise model whose runs are one vectorised computation
    (the kinematic engine): all of a stage's trials at once
    (:func:`~omnikin.evaluation.umbmark.simulate_umbmark`), the run poses simulated again from the
    first procedure's stream one run at a time (:func:`first_procedure_poses`), the
    trajectories from their own stream, the measured end poses with the noise model's
    measurement error."""

    engine: Engine
    square: Square

    def _opts(self) -> dict[str, Any]:
        s = self.square
        return dict(side=s.side, mode=s.mode, runs=s.runs, noise=s.noise, rate=s.rate)

    def umbmark(self, true_robot, command, seed, *, trials, label, phase, keep, out):
        out.progress(label)
        results = simulate_umbmark(true_robot, command, trials=trials, rng=seed, **self._opts())
        if keep.poses:
            out.poses += first_procedure_poses(phase, true_robot, command, rng=seed, **self._opts())
        return results, None

    def trajectories(self, true_robot, command, first, rng, phase, out):
        if phase == "before":
            out.progress("trajectories for the figures")
        s = self.square
        return {
            d: self.engine.drive(
                umbmark_square(d, s.side, s.mode), true_robot, command, rate=s.rate, noise=s.noise, rng=rng
            )
            for d in DIRECTIONS
        }

    def calibration_runs(self, true_robot, robot, seed, out):
        out.progress("calibration runs")
        s = self.square
        return simulate_calibration_runs(true_robot, robot, side=s.side, noise=s.noise, rate=s.rate, rng=seed)

    def fit(self, robot, runs, keep, out):
        out.progress("least-squares calibration")
        return least_squares_calibration(robot, runs)

    def systematic(self, true_robot, command, first, keep):
        quiet = dict(self._opts(), runs=1, noise=NOISE["none"])
        return simulate_umbmark(true_robot, command, **quiet)[0].e_max_syst

    def borenstein(self, true_robot, robot, first, seed, out):
        if differential_pair(robot) is None or self.square.mode != "rotate":
            return None
        out.progress("Borenstein's correction (comparison)")
        return borenstein_iterations(true_robot, robot, first, np.random.default_rng(seed), self._opts())

    def floor(self, true_robot, robot, seed, out):
        out.progress("noise floor")
        return noise_floor(true_robot, procedures=FLOOR_PROCEDURES, rng=seed, **self._opts())


@dataclass(frozen=True)
class _RunByRunRuns:
    """The stages of an engine without a noise model that drives one run at a time (the physics
    engine): a stage's ``trials * runs`` runs per direction one after the other, each wheel at
    a roller phase drawn from the direction's child of the stage's stream; the poses and
    trajectories are those runs'; the measured end pose is the true one; the floor is the
    nominal robot's; runs that did not drive as commanded are named."""

    engine: Engine
    square: Square

    def _drive(self, plan: Plan, true_robot: Robot, command: Robot, rng, name: str, out: _Out):
        """``plan`` driven by the engine, each wheel of ``true_robot`` started at a roller phase
        drawn uniformly from ``[0, 1)`` by ``rng``. A run that did not drive as commanded
        (:meth:`~omnikin.physics.run.PhysicsRun.problems`) is added to the problems as one line
        naming it as ``name``: its end pose enters the statistics, the report says which runs
        it should not trust."""
        run = self.engine.drive(plan, true_robot, command, rate=self.square.rate, rng=rng)
        found = self.engine.problems(run)
        if found and out.problems is not None:
            more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
            out.problems.append(f"{name}: {found[0]}{more}")
        return run

    def umbmark(self, true_robot, command, seed, *, trials, label, phase, keep, out):
        s = self.square
        runs = s.runs
        require_square(command, s.side, s.mode)
        total = 2 * trials * runs
        eps: dict[str, list] = {"cw": [], "ccw": []}
        first: dict = {}
        for direction, child in zip(DIRECTIONS, seed.spawn(2), strict=True):
            plan = umbmark_square(direction, s.side, s.mode)
            rng = np.random.default_rng(child)
            k = 0
            for index in range(trials * runs):
                number = len(eps["cw"]) + len(eps["ccw"]) + 1
                out.progress(f"{label}: run {number} of {total}")
                run = self._drive(
                    plan, true_robot, command, rng, f"{label}, run {number} of {total} ({direction})", out
                )
                first.setdefault(direction, run)
                eps[direction].append(run.epsilon[0])
                if keep.poses and index < runs:
                    k = k or stride(len(run.t), s.rate, runs)
                    out.poses.append(kept_run(phase, direction, index + 1, run.t, run.truth[0], run.odometry, k))
        results = [
            analyze(
                np.array(eps["cw"][k * runs : (k + 1) * runs]),
                np.array(eps["ccw"][k * runs : (k + 1) * runs]),
                s.side,
                command,
                s.mode,
            )
            for k in range(trials)
        ]
        return results, first

    def calibration_runs(self, true_robot, robot, seed, out):
        rng = np.random.default_rng(seed)
        plans = recommended_runs(robot, self.square.side)
        total = len(plans) * RECOMMENDED_REPEATS
        runs: list[CalibrationRun] = []
        for text, plan in plans:
            for _ in range(RECOMMENDED_REPEATS):
                out.progress(f"calibration runs: run {len(runs) + 1} of {total}")
                name = f"calibration run {len(runs) + 1} of {total} ({text})"
                run = self._drive(plan, true_robot, robot, rng, name, out)
                runs.append(CalibrationRun(plan, tuple(run.measured[0]), text))
        return runs

    def fit(self, robot, runs, keep, out):
        out.progress("least-squares calibration")
        if not keep.problems:
            return least_squares_calibration(robot, runs)
        try:
            return least_squares_calibration(robot, runs)
        except CalibrationFitError as e:  # runs that did not drive as commanded: no after, the report says why
            assert out.problems is not None
            out.problems.append(str(e))
            return None

    def systematic(self, true_robot, command, first, keep):
        return math.nan if keep.systematic else first.e_max_syst

    def trajectories(self, true_robot, command, first, rng, phase, out):
        return first

    def borenstein(self, true_robot, robot, first, seed, out):
        return None

    def floor(self, true_robot, robot, seed, out):
        nominal, _ = self.umbmark(
            robot,
            robot,
            seed,
            trials=self.square.trials,
            label="floor (nominal robot)",
            phase="floor",
            keep=Keep(),
            out=out,
        )
        return PhysicsFloor(
            values=np.array([r.e_max_syst for r in nominal]), interval=nominal[0].e_max_interval(self.square.level)
        )


def stage_runs(engine: Engine, square: Square) -> _VectorisedRuns | _RunByRunRuns:
    """How ``engine``'s runs make the stages (module docstring): vectorised with its noise model
    (:attr:`~omnikin.simulation.engine.Engine.has_noise_model`, the kinematic engine), else
    one run at a time (the physics engine)."""
    return (_VectorisedRuns if engine.has_noise_model else _RunByRunRuns)(engine, square)


def run_pipeline(
    robot: Robot,
    true_robot: Robot,
    *,
    engine: Engine,
    square: Square,
    streams: dict[str, np.random.SeedSequence],
    calibrate: bool,
    keep: Keep,
    progress: Progress | None = None,
) -> PipelineResult:
    """The pipeline of the module docstring: ``true_robot`` (the robot as built) measured with
    UMBmark commanded by ``robot`` (its nominal model), calibrated and measured again, every run
    driven by ``engine``, each stage drawing from its stream of ``streams``
    (:func:`seed_streams`); ``keep`` says what beyond the UMBmark results is kept."""
    stages = stage_runs(engine, square)
    out = _Out(progress or (lambda name: None), [], [] if keep.problems else None)
    trials = square.trials
    before, first = stages.umbmark(
        true_robot,
        robot,
        streams["before"],
        trials=trials,
        label="UMBmark before calibration",
        phase="before",
        keep=keep,
        out=out,
    )
    trajectories: dict = {}
    if keep.trajectories:
        traj_rng = np.random.default_rng(streams["trajectories"])
        trajectories["before"] = stages.trajectories(true_robot, robot, first, traj_rng, "before", out)
    systematic = {"before": stages.systematic(true_robot, robot, before[0], keep)}
    after: list[UMBmarkResult] | None = None
    cal: CalibrationResult | None = None
    bor: list[float] | None = None
    cal_runs: list[CalibrationRun] = []
    if calibrate:
        cal_runs = stages.calibration_runs(true_robot, robot, streams["calibration"], out)
        cal = stages.fit(robot, cal_runs, keep, out)
        if keep.borenstein:
            bor = stages.borenstein(true_robot, robot, before[0], streams["borenstein"], out)
        if cal is not None:
            after, first = stages.umbmark(
                true_robot,
                cal.robot,
                streams["after"],
                trials=trials,
                label="UMBmark after calibration",
                phase="after",
                keep=keep,
                out=out,
            )
            if keep.trajectories:
                trajectories["after"] = stages.trajectories(true_robot, cal.robot, first, traj_rng, "after", out)
            systematic["after"] = stages.systematic(true_robot, cal.robot, after[0], keep)
    floor = stages.floor(true_robot, robot, streams["floor"], out) if keep.floor else None
    return PipelineResult(
        before=before,
        after=after,
        calibration=cal,
        calibration_runs=cal_runs,
        borenstein=bor,
        systematic=systematic,
        floor=floor,
        trajectories=trajectories,
        poses=tuple(out.poses),
        problems=tuple(out.problems or ()),
    )


def first_procedure_poses(
    phase: str, true_robot: Robot, command: Robot, *, rng, side, mode, runs, noise, rate
) -> list[RunPoses]:
    """The runs of the first procedure of :func:`~omnikin.evaluation.umbmark.simulate_umbmark` with
    ``rng`` (the same draws: procedure 0's generator, cw runs then ccw runs, one run after the
    other), each kept at a bounded rate (:mod:`omnikin.evaluation.run_poses`); simulated one
    run at a time, so the memory is that of one run's ground truth."""
    generator = procedure_generators(rng, 1)[0]
    out = []
    for direction in DIRECTIONS:
        plan = umbmark_square(direction, side, mode)
        k = 0
        for run in range(1, runs + 1):
            sim = simulate_kinematic(plan, true_robot, command, rate=rate, noise=noise, trials=1, rng=generator)
            k = k or stride(len(sim.t), rate, runs)
            out.append(kept_run(phase, direction, run, sim.t, sim.truth[0], sim.odometry, k))
    return out


def simulate_calibration_runs(
    true_robot: Robot, robot: Robot, *, side: float, noise: NoiseModel | None, rate: float, rng
) -> list[CalibrationRun]:
    """The recommended calibration runs of ``robot``, each driven
    :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times by ``true_robot``
    commanded by ``robot`` (the kinematic engine, all repeats of a run at once), with their
    measured end poses (the noise model's measurement error) and the default measurement sigma
    of :class:`~omnikin.motion.plans.CalibrationRun` (as a runs file is read)."""
    rng = np.random.default_rng(rng)
    out = []
    for text, plan in recommended_runs(robot, side):
        sim = simulate_kinematic(
            plan, true_robot, robot, rate=rate, noise=noise, trials=RECOMMENDED_REPEATS, rng=rng, keep_truth=False
        )
        out += [CalibrationRun(plan, tuple(m), text) for m in sim.measured]
    return out


def borenstein_iterations(true_robot: Robot, robot: Robot, first: UMBmarkResult, rng, opts: dict) -> list[float]:
    """Borenstein's iterated correction (:func:`~omnikin.evaluation.calibration.borenstein_calibrate`)
    from the first procedure ``first``: E_max,syst [m] after each of :data:`BORENSTEIN_ITERATIONS`
    iterations, each measured by one UMBmark procedure drawn from ``rng``."""
    out, model, res = [], robot, first
    for _ in range(BORENSTEIN_ITERATIONS):
        model = borenstein_calibrate(model, res)
        res = simulate_umbmark(true_robot, model, rng=rng, **opts)[0]
        out.append(res.e_max_syst)
    return out
