"""The UMBmark study in the physics engine (``omnikin umbmark --engine physics``).

The steps of :func:`~omnikin.evaluation.procedure.umbmark_study`, every run driven by
:func:`~omnikin.physics.run.simulate_physics` (MuJoCo, rollers and motors) on the robot as
built, one run at a time (the physics has no trial axis: ``trials`` procedures are
``trials * runs`` runs per direction, each simulated on its own):

1. UMBmark before calibration, the robot as built commanded by its nominal model
   (Borenstein and Feng, "Measurement and correction of systematic odometry errors in mobile
   robots", 1996);
2. calibration (unless switched off): every run of
   :func:`~omnikin.evaluation.calibration.recommended_runs` driven
   :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times, its true end pose the
   measurement, and the least-squares calibration
   (:func:`~omnikin.evaluation.calibration.calibrate`);
3. UMBmark after calibration, the robot commanded by its calibrated model;
4. the floor (:class:`PhysicsFloor`): UMBmark of the *nominal* robot (no systematic errors)
   commanded by its own model, ``trials`` procedures of ``runs`` runs per direction: what the
   roller contact alone gives, the least E_max,syst a calibration of the kinematic model can
   reach in this engine. It takes the place of the kinematic study's noise floor
   (:class:`~omnikin.evaluation.umbmark.NoiseFloor` of these procedures).

The physics engine has no random error model: slip comes from the wheels' contacts and the
encoders count whole ticks, so a noise model is refused
(:func:`~omnikin.physics.engines.check_physics_noise`). The
engine is deterministic; what differs from run to run, as on a built robot, is where in their
roller period the wheels start: every run starts each wheel at a **roller phase** drawn
uniformly from ``[0, 1)`` of its period (:func:`~omnikin.physics.engine.roller_period`), from
the stage's stream of the study's seed (:func:`~omnikin.evaluation.procedure.streams`: the
same seed gives the same runs, the cw and ccw runs of a stage their own child streams, so the
first procedure does not depend on ``trials``). The confidence intervals and the floor thus
carry the spread over roller phases. Borenstein's iterated correction (kinematic study,
differential drives) is not run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import CalibrationFitError
from ..kinematics.robot import Robot
from ..motion.plans import CalibrationRun, Plan, umbmark_square
from ..odometry.batch import encoded_wheels
from ..physics.engines import PhysicsEngine
from ..simulation.engine import Engine
from ..simulation.error_models import NOISE, SystematicErrors
from .calibration import RECOMMENDED_REPEATS, CalibrationResult, recommended_runs
from .calibration import calibrate as least_squares_calibration
from .procedure import Cost, UMBmarkStudy, check_settings, streams
from .run_poses import RunPoses, kept_run, stride
from .umbmark import LEVEL, NoiseFloor, UMBmarkResult, analyze, require_square

BYTES = 256 * 1024**2
"""Memory of a physics study [bytes]: MuJoCo's model and data and the kept runs, generous."""

Progress = Callable[[str], None]

PHYSICS = PhysicsEngine()
"""The physics engine at its default time step (2 ms), the default of this module's functions."""


def physics_cost(
    robot: Robot,
    *,
    side: float,
    mode: str,
    runs: int,
    rate: float,
    trials: int,
    calibrate: bool,
    engine: PhysicsEngine = PHYSICS,
    budget: float | None = None,
) -> Cost:
    """Samples, memory and computing time of :func:`physics_umbmark_study`: every run's
    estimate (:func:`omnikin.physics.cost.physics_run_cost`: its simulated time bounded, the
    waits for the steering and the tail at their limits, at the cost of a time step measured
    once on ``robot``'s model at ``engine``'s time step, the model's construction counted for
    every run). With ``budget`` [s], a model whose size alone says the study takes longer is not
    built (:func:`omnikin.physics.cost.size_lower_bound`: that bound is the estimate)."""
    from ..motion.timing import sample_plan
    from ..physics.cost import measure_step_seconds, physics_run_cost, simulated_bound, size_lower_bound

    step = engine.step
    squares = runs * trials * (3 if calibrate else 2)  # per direction: before, after, the floor
    driven = [(umbmark_square(direction, side, mode), squares) for direction in ("cw", "ccw")]
    if calibrate:
        driven += [(plan, RECOMMENDED_REPEATS) for _, plan in recommended_runs(robot, side)]
    sampled = [(sample_plan(plan, robot, rate), count) for plan, count in driven]
    bounds = [size_lower_bound(robot, simulated_bound(s, robot) / step) for s, _ in sampled]
    if budget is not None and None not in bounds:  # a model too large by its size alone is not built
        least = sum(count * bound for (_, count), bound in zip(sampled, bounds, strict=True) if bound is not None)
        if least > budget:
            samples = sum(count * simulated_bound(s, robot) * rate for s, count in sampled)
            return Cost(samples, float(BYTES), seconds_per_sample=least / max(samples, 1.0))
    measured = measure_step_seconds(robot, step, step_option=True)
    samples = seconds = 0.0
    for plan, count in sampled:
        run = physics_run_cost(plan, robot, robot, step, measured=measured)
        samples += count * run.samples
        seconds += count * run.seconds
    return Cost(samples, float(BYTES), seconds_per_sample=seconds / max(samples, 1.0))


@dataclass(frozen=True)
class PhysicsFloor(NoiseFloor):
    """The floor of the physics study: ``values`` E_max,syst [m] of the nominal robot's
    procedures (module docstring) and ``interval`` the confidence interval [m] of the first
    one's E_max,syst from the spread of its runs over roller phases
    (:meth:`~omnikin.evaluation.umbmark.UMBmarkResult.e_max_interval`; None with fewer than 3
    runs per direction). :attr:`limit`, the largest E_max,syst that cannot be told from the
    nominal robot's, is the larger of the 95th percentile of ``values`` and the interval's upper
    end."""

    interval: tuple[float, float] | None = None

    @property
    def p95(self) -> float:
        """95th percentile of ``values`` [m]."""
        return float(np.percentile(self.values, 95))

    @property
    def limit(self) -> float:
        """The larger of :attr:`p95` and the interval's upper end [m]."""
        return max(self.p95, self.interval[1]) if self.interval is not None else self.p95

    def as_dict(self) -> dict:
        return {
            **NoiseFloor.as_dict(self),
            "e_max_syst_p95": self.p95,
            "e_max_syst_limit": self.limit,
            "e_max_syst_interval": list(self.interval) if self.interval is not None else None,
        }


def _drive(
    plan: Plan,
    true_robot: Robot,
    command: Robot,
    rate: float,
    engine: Engine,
    rng: np.random.Generator,
    name: str,
    problems: list[str] | None,
):
    """``plan`` driven by ``engine``, each wheel of ``true_robot`` started at a roller phase
    drawn uniformly from ``[0, 1)`` by ``rng`` (module docstring; :meth:`PhysicsEngine.drive`).
    A run that did not drive as commanded (:meth:`~omnikin.physics.run.PhysicsRun.problems`: a
    wheel lagging, slipping or off its commanded turn, steering or rest not reached) is added to
    ``problems`` as one line naming it as ``name``: its end pose enters the statistics as an
    odometry error, and the report must say which runs it should not trust."""
    run = engine.drive(plan, true_robot, command, rate=rate, rng=rng)
    found = engine.problems(run)
    if found and problems is not None:
        more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
        problems.append(f"{name}: {found[0]}{more}")
    return run


def physics_umbmark(
    true_robot: Robot,
    command: Robot,
    *,
    side: float,
    mode: str,
    runs: int,
    rate: float,
    seed: np.random.SeedSequence,
    trials: int = 1,
    engine: Engine = PHYSICS,
    progress: Progress | None = None,
    label: str = "UMBmark",
    problems: list[str] | None = None,
    poses: list[RunPoses] | None = None,
    phase: str = "before",
) -> tuple[list[UMBmarkResult], dict]:
    """``trials`` UMBmark procedures of ``runs`` runs per direction in the physics engine,
    ``true_robot`` commanded by ``command``, the roller phases of each direction's runs drawn
    from its own child of ``seed`` (module docstring), driven by ``engine``. Returns one
    :class:`~omnikin.evaluation.umbmark.UMBmarkResult` per procedure and the first run of each
    direction (``{"cw"|"ccw": PhysicsRun}``, with its ground truth). ``progress`` is called with
    ``label`` and the run's number before each run; runs that did not drive as commanded are
    added to ``problems`` (:func:`_drive`); the runs of the first procedure are added to
    ``poses`` as :class:`~omnikin.evaluation.run_poses.RunPoses` of ``phase``."""
    require_square(command, side, mode)
    total = 2 * trials * runs
    eps: dict[str, list] = {"cw": [], "ccw": []}
    first: dict = {}
    for direction, child in zip(("cw", "ccw"), seed.spawn(2), strict=True):
        plan = umbmark_square(direction, side, mode)
        rng = np.random.default_rng(child)
        k = 0
        for index in range(trials * runs):
            if progress is not None:
                progress(f"{label}: run {len(eps['cw']) + len(eps['ccw']) + 1} of {total}")
            number = len(eps["cw"]) + len(eps["ccw"]) + 1
            name = f"{label}, run {number} of {total} ({direction})"
            run = _drive(plan, true_robot, command, rate, engine, rng, name, problems)
            first.setdefault(direction, run)
            eps[direction].append(run.epsilon[0])
            if poses is not None and index < runs:
                k = k or stride(len(run.t), rate, runs)
                poses.append(kept_run(phase, direction, index + 1, run.t, run.truth[0], run.odometry, k))
    results = [
        analyze(
            np.array(eps["cw"][k * runs : (k + 1) * runs]),
            np.array(eps["ccw"][k * runs : (k + 1) * runs]),
            side,
            command,
            mode,
        )
        for k in range(trials)
    ]
    return results, first


def physics_calibration_runs(
    true_robot: Robot,
    robot: Robot,
    *,
    side: float,
    rate: float,
    seed: np.random.SeedSequence,
    engine: Engine = PHYSICS,
    progress: Progress | None = None,
    problems: list[str] | None = None,
) -> list[CalibrationRun]:
    """The recommended calibration runs of ``robot``, each driven
    :data:`~omnikin.evaluation.calibration.RECOMMENDED_REPEATS` times in the physics engine by
    ``true_robot`` commanded by ``robot`` driven by ``engine``, roller phases drawn from
    ``seed``; the measured end
    pose is the true one (the default measurement sigma of
    :class:`~omnikin.motion.plans.CalibrationRun`, as a runs file is read)."""
    rng = np.random.default_rng(seed)
    plans = recommended_runs(robot, side)
    total = len(plans) * RECOMMENDED_REPEATS
    out: list[CalibrationRun] = []
    for text, plan in plans:
        for _ in range(RECOMMENDED_REPEATS):
            if progress is not None:
                progress(f"calibration runs: run {len(out) + 1} of {total}")
            name = f"calibration run {len(out) + 1} of {total} ({text})"
            run = _drive(plan, true_robot, robot, rate, engine, rng, name, problems)
            out.append(CalibrationRun(plan, tuple(run.measured[0]), text))
    return out


def physics_umbmark_study(
    robot: Robot,
    true_robot: Robot,
    *,
    injected: SystematicErrors | None = None,
    side: float,
    mode: str,
    runs: int,
    rate: float,
    trials: int,
    calibrate: bool,
    seed: int,
    engine: Engine = PHYSICS,
    progress: Progress | None = None,
    level: float = LEVEL,
) -> UMBmarkStudy:
    """The study of the module docstring, as a :class:`~omnikin.evaluation.procedure.UMBmarkStudy`
    (``engine`` the physics engine, ``noise`` none, ``floor`` the nominal robot's :class:`PhysicsFloor`
    with its interval at ``level``, ``systematic`` the first procedures, no Borenstein
    comparison); roller phases from ``seed``, every run driven by ``engine``."""
    check_settings(runs=runs, trials=trials, side=side, rate=rate)
    engine.check_rate(rate)
    encoded_wheels(robot)
    rng = streams(seed)
    problems: list[str] = []
    poses: list[RunPoses] = []
    opts: dict[str, Any] = dict(
        side=side, mode=mode, runs=runs, rate=rate, trials=trials, engine=engine, progress=progress, problems=problems
    )
    before, first = physics_umbmark(
        true_robot, robot, seed=rng["before"], label="UMBmark before calibration", poses=poses, **opts
    )
    trajectories = {"before": first}
    systematic = {"before": before[0].e_max_syst}
    after: list | None = None
    cal: CalibrationResult | None = None
    cal_runs: list[CalibrationRun] = []
    if calibrate:
        cal_runs = physics_calibration_runs(
            true_robot,
            robot,
            side=side,
            rate=rate,
            seed=rng["calibration"],
            engine=engine,
            progress=progress,
            problems=problems,
        )
        if progress is not None:
            progress("least-squares calibration")
        try:
            cal = least_squares_calibration(robot, cal_runs)
        except CalibrationFitError as e:  # runs that did not drive as commanded: no after, the report says why
            problems.append(str(e))
        if cal is not None:
            after, trajectories["after"] = physics_umbmark(
                true_robot,
                cal.robot,
                seed=rng["after"],
                label="UMBmark after calibration",
                poses=poses,
                phase="after",
                **opts,
            )
            systematic["after"] = after[0].e_max_syst
    nominal, _ = physics_umbmark(robot, robot, seed=rng["floor"], label="floor (nominal robot)", **opts)
    floor = PhysicsFloor(np.array([r.e_max_syst for r in nominal]), nominal[0].e_max_interval(level))
    return UMBmarkStudy(
        robot,
        true_robot,
        injected,
        side,
        mode,
        runs,
        rate,
        trials,
        NOISE["none"],
        before,
        after,
        cal,
        cal_runs,
        None,
        systematic,
        floor,
        trajectories,
        level=level,
        engine=engine,
        problems=tuple(problems),
        run_poses=tuple(poses),
    )
