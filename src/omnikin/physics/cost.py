"""What a physics run will take, before it starts: :func:`physics_run_cost`, the one estimate
``omnikin simulate --engine physics``, :func:`omnikin.simulate` and ``omnikin umbmark --engine
physics`` check against ``--max-time`` / ``max_time``.

Computing time = (time steps) x (measured seconds per step) + (samples) x
:data:`SAMPLE_SECONDS` + the model's construction, with

* the seconds per step **measured on the model itself**, on this machine, just before the run,
  as this process's CPU time (other work on the machine stretches the clock, not the count)
  (:func:`measure_step_seconds`): the robot as built is made into its MuJoCo model, set down on
  the floor, and driven for up to :data:`PROBE_STEPS` steps (at most :data:`PROBE_SECONDS` of
  wall time) through :class:`~omnikin.physics.simulator.PhysicsSim`, its servos and ramps included.
  A step's cost depends on the bodies, rollers and contacts of the model in ways no formula in
  the file's numbers captured (diff-drive 10 us a step, 12 wheels of 256 rollers 2.3 ms), so
  it is measured;
* before the model is built, a **lower bound** from its size (:func:`size_lower_bound`: bodies
  x :data:`COMPILE_SECONDS_PER_BODY` to compile it, and :data:`STEP_SECONDS_PER_BODY` per body
  and step): a model slow to build (3 000 bodies and more) so large that even this exceeds the
  budget is refused without building it (64 wheels of 256 rollers take 21 s to compile);
* the simulated time **bounded from above** (:func:`simulated_bound`): the plan's duration, plus
  :data:`~omnikin.physics.run.ALIGN_MAX` for every segment whose steering differs from the one
  before it (the run waits for the steering joints, at most that long), plus
  :data:`~omnikin.physics.run.TAIL_MAX` after the plan (the run goes on until the robot is at
  rest, at most that long); the steps are that time over the time step.

The estimate is thus on the slow side: a run takes at most about as long as estimated (the
per-step cost varies by 10-30 % as the contacts change), and runs that end early (the robot at
rest at once, steering reached quickly) take less: docs/physics.md gives estimate and actual
for several robots, steps and paths.

A MuJoCo run cannot be stopped halfway and resumed, so a run over budget is refused up front,
never cut short.

``omnikin sim`` and ``omnikin ros --backend physics`` run in real time instead: they measure the
same step cost first (:func:`real_time_factor`) and say in one line when this machine cannot
keep up with the model (``sim`` then runs slower than the clock; the ROS back-end drops
simulated time and counts it in ``/diagnostics``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import DivergedError
from ..kinematics.robot import Robot
from ..kinematics.se2 import wrap_angle
from ..motion.timing import SampledPlan
from ..simulation.kinematic import segment_rates
from .description import describe
from .mjcf import DEFAULT_STEP
from .run import ALIGN_MAX, STEER_ALIGNED, TAIL_MAX
from .simulator import PhysicsSim

PROBE_WARMUP = 20
"""Time steps driven before the measurement (the first steps of a run cost more)."""
PROBE_STEPS = 500
"""Time steps driven to measure a step's cost (after the model has settled on the floor)."""
PROBE_SECONDS = 0.3
"""Wall time [s] after which the measurement stops, however few steps it took (a model of
thousands of rollers)."""
PROBE_SPEED = 0.2
"""Speed [m/s] of the body along its x axis the wheels are commanded during the measurement
(rolling contacts cost more than resting ones)."""
COMPILE_SECONDS_PER_BODY = 1e-4
"""Least compile time [s] per body of a MuJoCo model (measured 0.2 ms per body for 3 000 bodies,
1.3 ms for 16 000, on one core of a 2-core machine)."""
STEP_SECONDS_PER_BODY = 2e-7
"""Least computing time [s] per body and time step (measured 0.27 us at rest for 16 000 bodies,
0.6-0.8 us driving for 40-3 000)."""
REAL_TIME_MARGIN = 2.0
"""A model run in real time should step at least this many times faster than the clock: the
rest of each control period goes to the controller, the window or the ROS node."""
SAMPLE_SECONDS = 2.5e-5
"""Computing time [s] per sample of a run beyond its time steps (reading the encoders and the
pose, commanding the next set-points): measured 20-21 us for tomasi-omni3 and diff-drive (line
10 at 1000 Hz against 10 Hz) on one core of a 2-core machine."""


@dataclass(frozen=True)
class PhysicsCost:
    """A physics run's estimate: ``simulated`` [s] of simulated time (upper bound), ``steps``
    time steps, ``samples`` samples, ``seconds`` [s] of computing time, of which ``step_seconds``
    [s] per time step as measured."""

    simulated: float
    steps: float
    samples: float
    seconds: float
    step_seconds: float


def model_bodies(robot: Robot) -> int:
    """Bodies of ``robot``'s MuJoCo model: the chassis, each wheel, its rollers and its steering
    fork (:func:`~omnikin.physics.description.describe`)."""
    bodies = 1
    for wheel in describe(robot).wheels:
        rollers = wheel.rollers.rows * wheel.rollers.per_row if wheel.rollers is not None else 0
        bodies += 1 + rollers + (wheel.steering is not None)
    return bodies


def size_lower_bound(robot: Robot, steps: float) -> float | None:
    """Least computing time [s] of ``steps`` time steps of ``robot``'s model, building it
    included, from its size alone (:func:`model_bodies`; module docstring); None for a model
    quick to build (less than :data:`PROBE_SECONDS` by this bound), whose measured cost is the
    better estimate."""
    bodies = model_bodies(robot)
    if bodies * COMPILE_SECONDS_PER_BODY < PROBE_SECONDS:
        return None
    return bodies * (COMPILE_SECONDS_PER_BODY + steps * STEP_SECONDS_PER_BODY)


def measure_step_seconds(robot: Robot, step: float, *, step_option: bool = False) -> tuple[float, float]:
    """Seconds of computing time per time step of ``robot``'s physics model at time step
    ``step`` [s], driven at :data:`PROBE_SPEED` (module docstring), and the seconds its
    construction took (model, settling). Bad robots are refused as the run would refuse them.
    Computing time is this process's CPU time (``time.process_time``): other work on the
    machine slows the clock, not the count, so the estimate does not depend on the moment it
    was measured. A model that diverges while measured is refused as the run would be
    (:class:`~omnikin.errors.DivergedError`, saying when; with the ``--step`` advice for
    callers that have the option, ``step_option``)."""
    try:
        return _measure(robot, step)
    except DivergedError as exc:
        note = f" (while its computing time was measured, driven straight at {PROBE_SPEED:g} m/s before the run)"
        raise exc.explained(note, step_option=step_option) from None


def _measure(robot: Robot, step: float) -> tuple[float, float]:
    cpu = time.process_time()
    sim = PhysicsSim(robot, step=step)
    built = time.process_time() - cpu
    rows = np.asarray(robot.jacobian(), dtype=float)
    sim.command(rows @ np.array([PROBE_SPEED, 0.0, 0.0]), np.zeros(len(robot.steer_names)) if robot.steerable else None)
    sim.step(PROBE_WARMUP)
    steps, chunk = 0, 20
    cpu, start = time.process_time(), time.perf_counter()
    while steps < PROBE_STEPS and time.perf_counter() - start < PROBE_SECONDS:
        sim.step(chunk)
        steps += chunk
    return (time.process_time() - cpu) / steps, built


def steering_waits(sampled: SampledPlan, robot: Robot) -> int:
    """How many segments of ``sampled`` start with steering of ``robot`` that differs (by more
    than :data:`~omnikin.physics.run.STEER_ALIGNED`) from the steering before them (the
    mounting, zero, for the first): each may wait up to :data:`~omnikin.physics.run.ALIGN_MAX`."""
    if not robot.steerable:
        return 0
    _, steer = segment_rates(sampled.xi, robot, robot.rolling_names)
    used = np.unique(sampled.segment)
    angles = np.vstack([np.zeros(steer.shape[1]), np.asarray(steer)[used]])
    change = np.max(np.abs(wrap_angle(np.diff(angles, axis=0))), axis=1)
    return int(np.sum(change > STEER_ALIGNED))


def simulated_bound(sampled: SampledPlan, robot: Robot) -> float:
    """Upper bound [s] of the simulated time of ``sampled`` driven by ``robot`` in
    :func:`~omnikin.physics.run.simulate_physics`: the plan, the steering waits at their
    limit, the tail at its limit (module docstring)."""
    return float(sampled.t[-1]) + ALIGN_MAX * steering_waits(sampled, robot) + TAIL_MAX


def physics_run_cost(
    sampled: SampledPlan,
    true_robot: Robot,
    command_robot: Robot,
    step: float,
    *,
    measured: tuple[float, float] | None = None,
    budget: float | None = None,
) -> PhysicsCost:
    """The estimate of the module docstring for ``sampled`` commanded by ``command_robot``,
    driven by ``true_robot`` at time step ``step`` [s]. ``measured``: what
    :func:`measure_step_seconds` gave for ``true_robot`` at ``step`` (for many runs of one
    model); None: measured now, unless the model's size alone says it takes more than
    ``budget`` [s] (:func:`size_lower_bound`; then that bound is the estimate)."""
    simulated = simulated_bound(sampled, command_robot)
    steps = math.ceil(simulated / step)
    samples = simulated * sampled.rate
    if measured is None and budget is not None:
        least = size_lower_bound(true_robot, steps)
        if least is not None and least > budget:
            return PhysicsCost(simulated, steps, samples, least, least / steps)
    step_seconds, built = measured if measured is not None else measure_step_seconds(true_robot, step, step_option=True)
    seconds = built + steps * step_seconds + samples * SAMPLE_SECONDS
    return PhysicsCost(simulated, steps, samples, seconds, step_seconds)


def real_time_factor(robot: Robot, step: float = DEFAULT_STEP) -> float:
    """How many times faster than the clock ``robot``'s model steps on this machine at time step
    ``step`` [s] (:func:`measure_step_seconds`; below 1 it cannot run in real time)."""
    seconds, _ = measure_step_seconds(robot, step)
    return step / seconds


def real_time_shortfall(robot: Robot, consequence: str) -> str | None:
    """One line saying that ``robot``'s model steps too slowly for real time on this machine
    (less than :data:`REAL_TIME_MARGIN` times the clock) and what follows (``consequence``), or
    None when it keeps up."""
    factor = real_time_factor(robot)
    if factor >= REAL_TIME_MARGIN:
        return None
    return (
        f"robot {robot.name!r} steps at about {factor:.2g} x real time on this machine (physics alone, "
        f"{REAL_TIME_MARGIN:g} x wanted): {consequence}"
    )
