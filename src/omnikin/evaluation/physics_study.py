"""The UMBmark study in the physics engine (``omnikin umbmark --engine physics``).

The study pipeline (:mod:`omnikin.evaluation.pipeline`, whose docstring lists the stages) with
the physics engine: every run driven by :func:`~omnikin.physics.run.simulate_physics` (MuJoCo,
rollers and motors) on the robot as built, one run at a time (the physics has no trial axis:
``trials`` procedures are ``trials * runs`` runs per direction, each simulated on its own). Its
floor is the :class:`~omnikin.evaluation.umbmark.PhysicsFloor`: UMBmark of the *nominal* robot
commanded by its own model, what the roller contact alone gives, the least E_max,syst a
calibration of the kinematic model can reach in this engine (in place of the kinematic study's
:class:`~omnikin.evaluation.umbmark.NoiseFloor`).

This module keeps the physics study's cost estimate (:func:`physics_cost`); the study itself is
:func:`~omnikin.evaluation.procedure.umbmark_study` with ``engine=PHYSICS``.

The physics engine has no random error model: slip comes from the wheels' contacts and the
encoders count whole ticks, so a noise model is refused
(:func:`~omnikin.physics.engines.check_physics_noise`). The
engine is deterministic; what differs from run to run, as on a built robot, is where in their
roller period the wheels start: every run starts each wheel at a **roller phase** drawn
uniformly from ``[0, 1)`` of its period (:func:`~omnikin.physics.simulator.roller_period`), from
the stage's stream of the study's seed (:func:`~omnikin.evaluation.procedure.streams`: the
same seed gives the same runs, the cw and ccw runs of a stage their own child streams, so the
first procedure does not depend on ``trials``). The confidence intervals and the floor thus
carry the spread over roller phases. Borenstein's iterated correction (kinematic study,
differential drives) is not run.
"""

from __future__ import annotations

from ..kinematics.robot import Robot
from ..motion.plans import umbmark_square
from ..physics.engines import PhysicsEngine
from .calibration import RECOMMENDED_REPEATS, recommended_runs
from .procedure import Cost

__all__ = ["BYTES", "PHYSICS", "physics_cost"]

BYTES = 256 * 1024**2
"""Memory of a physics study [bytes]: MuJoCo's model and data and the kept runs, generous."""

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
    """Samples, memory and computing time of the physics study
    (:func:`~omnikin.evaluation.procedure.umbmark_study` with a physics engine): every run's
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
