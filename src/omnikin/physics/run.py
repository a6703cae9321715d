"""A plan driven in the physics engine: :func:`simulate_physics`, the physics twin of
:func:`omnikin.simulation.simulate.simulate` (``omnikin simulate --engine physics``).

The plan is timed and sampled for the commanding (nominal) robot exactly as the kinematic
engine does it (:func:`~omnikin.simulation.motion.sample_plan`, the same limits), and the
commanded wheel angles of every rolling wheel at the samples are those of
:func:`~omnikin.simulation.simulate.commanded_angles`. Sample ``k`` commands each wheel the
mean speed ``(angle_{k+1} - angle_k) / dt`` [rad/s] of its interval (and the interval's
steering), held for the interval (zero-order hold at the plan's rate, as a wheel controller
receiving set-points does); :class:`~omnikin.physics.engine.PhysicsSim` of the robot *as built*
ramps and servos the motors and steps MuJoCo up to the next sample, where the encoders are read.

Steering first: a segment whose steering differs from the angles the steering joints reached
(by more than :data:`STEER_ALIGNED`) starts with the wheels commanded to stand and the new
steering, sampled on until the joints have reached it and the robot is at rest (at most
:data:`ALIGN_MAX`), as a controller of steered wheels does: the kinematic plan turns the wheels
at once, which off-centred legs swinging under a moving robot cannot (Villasenor's robot tips
over). A robot that tips over anyway (:data:`TIPPED`) ends the run with
:class:`~omnikin.physics.engine.PhysicsError` naming the time.

After the plan the wheels are commanded to stop and the run goes on, sampled at the same rate,
until the robot is at rest (:data:`REST_SPEED`, :data:`REST_TURN`) or :data:`TAIL_MAX` has
passed: the ramps make the wheels lag the set-points while accelerating and lead them while
braking, by the same distance, so the robot ends where the plan ends only once it has stopped.

The result is a :class:`PhysicsRun`, a :class:`~omnikin.simulation.simulate.SimulatedRun` (one
trial) as the kinematic
engine gives it, so that its tick log, bag and summary are written by the same code:
``ticks`` are the whole ticks the encoders of the robot as built counted (never wrapped),
``readings`` those counts as the command robot's counters output them
(:func:`~omnikin.simulation.simulate.counter_output`), ``steer`` the steering angles the
steering joints reached [rad], ``odometry`` the command robot's odometry of the readings,
``truth`` the chassis pose (heading continuous), ``measured`` the true end pose (the physics has
no measurement noise), ``sampled`` the plan's samples with zero-progress samples for the tail.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..geometry import wrap_angle
from ..limits import MotionLimits
from ..model import Robot, require_same_wheels
from ..odometry import batch_odometry, encoded_wheels
from ..plans import Plan
from ..simulation.motion import SampledPlan, check_rate_range, require_motion, sample_plan
from ..simulation.simulate import SimulatedRun, commanded_angles, counter_output
from .description import steered_support_margin
from .engine import PhysicsError, PhysicsSim
from .mjcf import DEFAULT_STEP

REST_SPEED = 1e-4
"""Speed [m/s] of the chassis below which it is at rest after the plan."""
REST_TURN = 1e-3
"""Turn rate [rad/s] of the chassis below which it is at rest after the plan."""
TAIL_MAX = 5.0
"""Longest time [s] the run goes on after the plan while the robot comes to rest."""
STEER_ALIGNED = 0.01
"""Steering error [rad] below which a segment's steering counts as reached."""
ALIGN_MAX = 5.0
"""Longest time [s] a segment waits for its steering before it drives."""
TIPPED = 0.2
"""Tilt [rad] of the chassis beyond which the robot has tipped over (it stands level within
milliradians: the contacts sink 0.01-0.1 % of a wheel's radius)."""


@dataclass(frozen=True)
class PhysicsRun(SimulatedRun):
    """A :class:`~omnikin.simulation.simulate.SimulatedRun` driven in the physics engine;
    ``saturated`` counts the samples whose command a motor's speed limit or a steering end stop
    held at the limit (:attr:`omnikin.physics.engine.PhysicsSim.saturated`)."""

    saturated: int = 0


def simulate_physics(
    plan: Plan | SampledPlan,
    true_robot: Robot,
    command_robot: Robot,
    *,
    rate: float = 100.0,
    limits: MotionLimits | None = None,
    step: float = DEFAULT_STEP,
    progress: Callable[[float, float], None] | None = None,
    roller_phase=0.0,
) -> PhysicsRun:
    """``plan`` commanded by ``command_robot`` and driven by ``true_robot`` in MuJoCo at time step
    ``step`` [s] (module docstring); ``rate`` [Hz] as for the kinematic engine. ``progress``, if
    given, is called now and then with the simulated time and the plan's duration [s].
    ``roller_phase``: where in its roller period each wheel of ``true_robot`` starts, a fraction
    in ``[0, 1)`` for every wheel or one per rolling wheel
    (:func:`~omnikin.physics.engine.roller_offsets`); the encoders start at zero."""
    check_rate_range(plan.rate if isinstance(plan, SampledPlan) else rate, "rate")
    require_same_wheels(command_robot, true_robot)
    sampled = plan if isinstance(plan, SampledPlan) else sample_plan(plan, command_robot, rate, limits)
    require_motion(sampled)
    names = [w.name for w in encoded_wheels(command_robot)]
    if [w.name for w in true_robot.encoded] != names:
        raise InputError(f"true robot {true_robot.name!r}: its encoded wheels must be {names}")
    angles, steer_cmd = commanded_angles(sampled, command_robot, command_robot.rolling)
    dt = np.diff(sampled.t)
    speeds = np.diff(angles, axis=0) / dt[:, None]
    sim = PhysicsSim(true_robot, step=step, roller_phase=roller_phase)
    steerable = bool(command_robot.steerable)
    samples = len(dt)
    duration = float(sampled.t[-1])
    times, poses, counts, steers = [0.0], [sim.pose], [sim.encoder_counts()], [sim.steer_angles]
    progress_of: list[float] = []
    segment_of: list[int] = []
    report = max(1, samples // 200)
    stop = np.zeros(speeds.shape[1])
    period = 1.0 / sampled.rate

    def sample(wheels, steer, t_next: float, done: float, segment: int) -> None:
        sim.command(wheels, steer)
        sim.advance(t_next)
        if sim.tilt > TIPPED:
            raise PhysicsError(
                f"robot {true_robot.name!r} tipped over at t = {t_next:.4g} s (chassis tilted "
                f"{math.degrees(sim.tilt):.3g} deg): its contacts left the support of its weight"
            )
        times.append(t_next)
        poses.append(sim.pose)
        counts.append(sim.encoder_counts())
        steers.append(sim.steer_angles)
        progress_of.append(done)
        segment_of.append(segment)

    behind = 0.0  # time [s] the run is behind the plan's clock (samples waiting for the steering)
    for k in range(samples):
        segment = int(sampled.segment[k])
        steer_k = steer_cmd[k] if steer_cmd is not None else None
        if steer_k is not None and (k == 0 or segment != sampled.segment[k - 1]):
            _require_support(sim, steer_k, segment)
            waited = 0.0
            while waited < ALIGN_MAX and not (
                np.max(np.abs(wrap_angle(steer_k - sim.steer_angles))) < STEER_ALIGNED and _at_rest(sim)
            ):
                behind += period
                waited += period
                sample(stop, steer_k, times[-1] + period, 0.0, segment)
        sample(speeds[k], steer_k, float(sampled.t[k + 1]) + behind, float(sampled.progress[k]), segment)
        if progress is not None and (k + 1) % report == 0:
            progress(float(sampled.t[k + 1]), duration)
    last_steer = steer_cmd[-1] if steer_cmd is not None else None
    end = times[-1]
    while not (_at_rest(sim) or times[-1] - end >= TAIL_MAX):
        sample(stop, last_steer, times[-1] + period, 0.0, int(sampled.segment[-1]))
    if progress is not None:
        progress(duration, duration)
    t = np.array(times)
    extended = SampledPlan(sampled.plan, sampled.rate, t, np.array(progress_of), np.array(segment_of), sampled.xi)
    ticks = np.array(counts, dtype=np.int64)
    readings = counter_output(ticks, [command_robot.wheel(n).encoder.counter_bits for n in names])  # type: ignore[union-attr]
    steer = np.array(steers) if steerable else None
    odometry = batch_odometry(command_robot, t, readings, steer=steer, max_wheel_accel=math.inf).poses
    truth = np.array(poses)[None]
    truth[..., 2] = wrap_angle(truth[..., 2])  # headings in [-pi, pi), as the kinematic engine's truth
    measured = truth[:, -1, :].copy()
    return PhysicsRun(extended, t, ticks, steer, odometry, truth, measured, readings, saturated=sim.saturated)


def _require_support(sim: PhysicsSim, steer: np.ndarray, segment: int) -> None:
    """Refuse, before steering, a segment whose steering puts the contacts of the robot's wheels
    (off-centred wheels swing theirs round the steering axes) where they do not surround its
    centre of mass: it would tip over (:class:`~omnikin.physics.engine.PhysicsError`)."""
    margin = steered_support_margin(sim.robot, sim.description.com, steer)
    if margin <= 0.0:
        degrees = ", ".join(f"{math.degrees(a):.4g}" for a in steer)
        raise PhysicsError(
            f"robot {sim.robot.name!r} cannot stand with the steering of segment {segment + 1} of the path "
            f"({degrees} deg): its off-centred wheels' contacts would leave its centre of mass "
            f"{-1000.0 * margin:.3g} mm outside their support, and it would tip over"
        )


def _at_rest(sim: PhysicsSim) -> bool:
    twist = sim.twist
    return not sim.ramping and math.hypot(twist[0], twist[1]) < REST_SPEED and abs(twist[2]) < REST_TURN
