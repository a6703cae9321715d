"""A plan driven in the physics engine: :func:`simulate_physics`, the physics twin of
:func:`omnikin.simulation.kinematic.simulate_kinematic` (``omnikin simulate --engine physics``).

The plan is timed and sampled for the commanding (nominal) robot exactly as the kinematic
engine does it (:func:`~omnikin.motion.timing.sample_plan`, the same limits), and the
commanded wheel angles of every rolling wheel at the samples are those of
:func:`~omnikin.simulation.kinematic.commanded_angles`. Sample ``k`` commands each wheel the
mean speed ``(angle_{k+1} - angle_k) / dt`` [rad/s] of its interval (and the interval's
steering), held for the interval (zero-order hold at the plan's rate, as a wheel controller
receiving set-points does); :class:`~omnikin.physics.simulator.PhysicsSim` of the robot *as built*
ramps and servos the motors and steps MuJoCo up to the next sample, where the encoders are read.

Steering first: a segment whose steering differs from the angles the steering joints reached
(by more than :data:`STEER_ALIGNED`) starts with the wheels commanded to stand and the new
steering, sampled on until the joints have reached it and the robot is at rest (at most
:data:`ALIGN_MAX`), as a controller of steered wheels does: the kinematic plan turns the wheels
at once, which off-centred legs swinging under a moving robot cannot (Villasenor's robot tips
over). A robot that tips over anyway (:data:`~omnikin.physics.simulator.TIPPED`,
:meth:`~omnikin.physics.simulator.PhysicsSim.fall`) ends the run with
:class:`~omnikin.errors.PhysicsError` naming the time.

After the plan the wheels are commanded to stop and the run goes on, sampled at the same rate,
until the robot is at rest (:data:`REST_SPEED`, :data:`REST_TURN`) or :data:`TAIL_MAX` has
passed: the ramps make the wheels lag the set-points while accelerating and lead them while
braking, by the same distance, so the robot ends where the plan ends only once it has stopped.

The run watches for not driving as commanded (docs/physics.md, "Runs that do not drive as
commanded"): driven wheels lagging their set-points (the engine's
:data:`~omnikin.physics.simulator.TRACK_ERROR`), slipping (:data:`SLIP_ERROR`) or ending off the
angle they were commanded to turn (:data:`END_ERROR`), steering not reached within
:data:`ALIGN_MAX`, the robot not at rest after :data:`TAIL_MAX`; :meth:`PhysicsRun.problems`
words them. Its sample ``rate`` must have a period of whole time steps (:func:`check_rate_steps`).

The result is a :class:`PhysicsRun`, a :class:`~omnikin.simulation.kinematic.SimulatedRun` (one
trial) as the kinematic
engine gives it, so that its tick log, bag and summary are written by the same code:
``ticks`` are the whole ticks the encoders of the robot as built counted (never wrapped),
``readings`` those counts as the command robot's counters output them
(:func:`~omnikin.simulation.kinematic.counter_output`), ``steer`` the steering angles the
steering joints reached [rad], ``odometry`` the command robot's odometry of the readings,
``truth`` the chassis pose (heading continuous), ``measured`` the true end pose (the physics has
no measurement noise), ``sampled`` the plan's samples with zero-progress samples for the tail.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..errors import DivergedError, InputError, OdometryInputError, PhysicsError
from ..kinematics.robot import Robot, require_same_wheels
from ..kinematics.se2 import between, wrap_angle
from ..kinematics.sensors import Imu, Lidar
from ..motion.limits import MotionLimits
from ..motion.plans import Plan
from ..motion.timing import SampledPlan, check_rate_range, require_motion, sample_plan
from ..odometry.batch import batch_odometry, encoded_wheels
from ..odometry.plausibility import QUANTISATION_SLACK, counter_rules
from ..sensors.readings import measured_readings, require_scan_room
from ..simulation.kinematic import SimulatedRun, commanded_angles, counter_output
from ..world.model import World
from .description import steered_support_margin
from .mjcf import DEFAULT_STEP, time_step
from .sensing import PhysicsSensors
from .simulator import TRACK_ERROR, TRACK_TIME, PhysicsSim

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

SLIP_TIME = 0.2
"""Window [s] of a wheel's slip: the root mean square over an exponential window of this length,
taken at the samples, of the rim speed ``r (omega - J_i xi)`` the wheel turns beyond what the
chassis' true twist ``xi`` rolls it (``J_i`` its row of the robot as built at the steering
reached), bounded by :data:`SLIP_ERROR`."""
SLIP_ERROR = 0.05
"""Bound [m/s] on a driven wheel's root mean square slip over :data:`SLIP_TIME`: beyond it the
wheel spins or skids on the floor (the soft contacts creep 21-49 mm/s for a moment while a
0.5 m/s step ramps; docs/physics.md)."""

END_ERROR = 0.005
"""Rim distance [m] a driven wheel may end off the angle it was commanded to turn (plus
:data:`END_SHARE` of that distance): the ramps make it lag while accelerating and lead while
braking by the same angle, so a wheel that followed its commands ends on them within the servo's
last error (the presets: below 1 mm on a 1 m square)."""
END_SHARE = 0.01
"""Share of a driven wheel's commanded rim distance it may end off it (:data:`END_ERROR`)."""


@dataclass(frozen=True)
class WheelTrouble:
    """A driven wheel that did not do what it was commanded for ``seconds`` [s] of the run, first
    at ``start`` [s]; ``worst`` [m/s] its largest root mean square rim speed error (``kind``
    "lagged": behind or around its set-points, :data:`~omnikin.physics.simulator.TRACK_ERROR`;
    "slipped": spinning or skidding on the floor, :data:`SLIP_ERROR`)."""

    wheel: str
    kind: str
    seconds: float
    start: float
    worst: float

    def text(self) -> str:
        bound, window = (TRACK_ERROR, TRACK_TIME) if self.kind == "lagged" else (SLIP_ERROR, SLIP_TIME)
        what = "did not follow its set-points" if self.kind == "lagged" else "slipped on the floor"
        return (
            f"wheel {self.wheel!r} {what} for {self.seconds:.3g} s from t = {self.start:.4g} s (rim speed error up "
            f"to {self.worst:.3g} m/s root mean square over {window:g} s, bound {bound:g} m/s)"
        )


@dataclass(frozen=True)
class PhysicsRun(SimulatedRun):
    """A :class:`~omnikin.simulation.kinematic.SimulatedRun` driven in the physics engine;
    ``saturated`` counts the samples whose command a motor's speed limit or a steering end stop
    held at the limit (:attr:`omnikin.physics.simulator.PhysicsSim.saturated`); ``wheels`` the
    driven wheels that lagged their set-points or slipped (:class:`WheelTrouble`);
    ``steering_not_reached`` the segments (1-based) that drove after :data:`ALIGN_MAX` without
    their steering; ``at_rest`` False when the robot still moved :data:`TAIL_MAX` after the plan;
    ``short`` the driven wheels that ended off the angle they were commanded to turn
    (:data:`END_ERROR`): ``(wheel, rim distance short [m], rim distance commanded [m])``."""

    saturated: int = 0
    wheels: tuple[WheelTrouble, ...] = ()
    steering_not_reached: tuple[int, ...] = ()
    at_rest: bool = True
    short: tuple[tuple[str, float, float], ...] = ()

    @property
    def troubled(self) -> bool:
        """True when the run did not drive as commanded (:meth:`problems` is not empty)."""
        return bool(self.problems())

    def problems(self) -> list[str]:
        """One phrase per way the run did not drive as commanded (a wheel lagging or slipping,
        steering not reached, not at rest at the end); empty for a clean run. Saturated commands
        are not among them: the limit is the robot's, the run drove what it could."""
        out = [w.text() for w in self.wheels]
        for name, off, total in self.short:
            where = "short of" if off * total >= 0 else "beyond"
            out.append(
                f"wheel {name!r} ended {1000.0 * abs(off):.4g} mm of rim {where} the {1000.0 * abs(total):.4g} mm it "
                f"was commanded to turn"
            )
        if self.steering_not_reached:
            segments = ", ".join(str(k) for k in self.steering_not_reached[:10])
            more = f" and {len(self.steering_not_reached) - 10} more" if len(self.steering_not_reached) > 10 else ""
            out.append(
                f"the steering of segment {segments}{more} was not reached within {ALIGN_MAX:g} s (driven anyway)"
            )
        if not self.at_rest:
            out.append(f"the robot was still moving {TAIL_MAX:g} s after the plan ended (its end pose is not final)")
        return out

    def summary(self) -> dict:
        """The counts of :meth:`problems` for a JSON summary (``saturated_commands`` too)."""
        return {
            "saturated_commands": self.saturated,
            "lagging_wheels": {w.wheel: w.seconds for w in self.wheels if w.kind == "lagged"},
            "slipping_wheels": {w.wheel: w.seconds for w in self.wheels if w.kind == "slipped"},
            # rim [m] short of the commanded turn (negative: beyond it), whichever way it turned
            "wheels_off_command": {name: math.copysign(off, off * total) for name, off, total in self.short},
            "steering_not_reached": list(self.steering_not_reached),
            "at_rest": self.at_rest,
        }


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
    world: World | None = None,
    sensor_rng=None,
) -> PhysicsRun:
    """``plan`` commanded by ``command_robot`` and driven by ``true_robot`` in MuJoCo at time step
    ``step`` [s] (module docstring); ``rate`` [Hz] as for the kinematic engine. ``progress``, if
    given, is called now and then with the simulated time and the plan's duration [s].
    ``roller_phase``: where in its roller period each wheel of ``true_robot`` starts, a fraction
    in ``[0, 1)`` for every wheel or one per rolling wheel
    (:func:`~omnikin.physics.simulator.roller_offsets`); the encoders start at zero. In a
    ``world`` the robot starts at its start pose among its bodies; the run's ``truth`` stays in
    the frame where it started (as the kinematic engine's) and ``contacts`` lists where touches
    began. The IMUs and lidars of ``true_robot`` read as the run goes
    (:mod:`omnikin.physics.sensing`), their errors drawn from ``sensor_rng`` (None: exact), into
    the run's ``sensing``."""
    rate = check_rate_range(plan.rate if isinstance(plan, SampledPlan) else rate, "rate")
    check_rate_steps(rate, step)
    require_same_wheels(command_robot, true_robot)
    sampled = plan if isinstance(plan, SampledPlan) else sample_plan(plan, command_robot, rate, limits)
    require_motion(sampled)
    names = [w.name for w in encoded_wheels(command_robot)]
    if [w.name for w in true_robot.encoded] != names:
        raise InputError(f"true robot {true_robot.name!r}: its encoded wheels must be {names}")
    sensed = any(isinstance(s, (Imu, Lidar)) for s in true_robot.sensors)
    if sensed:
        require_scan_room(true_robot, float(sampled.t[-1] - sampled.t[0]) + TAIL_MAX)
    try:
        run, sensors = _drive(sampled, true_robot, command_robot, names, step, progress, roller_phase, world, sensed)
    except DivergedError as exc:
        raise exc.explained(step_option=True) from None
    if sensors is None:
        return run
    return replace(run, sensing=measured_readings(true_robot, sensors.truths(), sensor_rng))


def check_rate_steps(rate: float, step: float) -> None:
    """Refuse a sample ``rate`` [Hz] whose period is not a whole number of time steps ``step``
    [s] (one line, naming the nearest rates that are): the engine reads the encoders after whole
    steps, so a stamp between two steps would name a time the reading was not taken at (the
    kinematic engine's tick log holds the readings at its stamps); 300 Hz at 2 ms alternated
    2- and 1-step intervals stamped 3.33 ms apart."""
    step = time_step(step, "step (--step)")
    steps = 1.0 / (rate * step)
    if round(steps) >= 1 and abs(steps - round(steps)) <= 1e-6 * steps:
        return
    below = max(1, math.ceil(steps))
    near = sorted({1.0 / (n * step) for n in (below, max(1, math.floor(steps)))}, reverse=True)
    options = " or ".join(f"{r:.9g}" for r in near)  # to 5e-9: within the 1e-6 a rate is accepted
    raise InputError(
        f"rate (--rate) {rate:g} Hz: its period {1000.0 / rate:.4g} ms is not a whole number of physics time "
        f"steps ({step:g} s), so the encoders could not be read at the stamped times; choose --rate {options} "
        f"(1 / (n x step)), or a --step that divides the period"
    )


def _drive(
    sampled: SampledPlan,
    true_robot: Robot,
    command_robot: Robot,
    names: list[str],
    step: float,
    progress: Callable[[float, float], None] | None,
    roller_phase,
    world: World | None,
    sensed: bool,
) -> tuple[PhysicsRun, PhysicsSensors | None]:
    """:func:`simulate_physics` after its checks: the run without its readings, and what its
    sensors read (``sensed``; else None)."""
    angles, steer_cmd = commanded_angles(sampled, command_robot, command_robot.rolling)
    dt = np.diff(sampled.t)
    speeds = np.diff(angles, axis=0) / dt[:, None]
    start = (0.0, 0.0, 0.0) if world is None else world.start
    sim = PhysicsSim(
        true_robot,
        start=start,
        step=step,
        roller_phase=roller_phase,
        controller=command_robot,
        world=world,
        sensors=sensed,
    )
    steerable = bool(command_robot.steerable)
    samples = len(dt)
    duration = float(sampled.t[-1])
    times, poses, counts, steers = [0.0], [sim.pose], [sim.encoder_counts()], [sim.steer_angles]
    progress_of: list[float] = []
    segment_of: list[int] = []
    report = max(1, samples // 200)
    stop = np.zeros(speeds.shape[1])
    period = 1.0 / sampled.rate
    slip = _SlipWatch(sim, true_robot, period)

    def sample(wheels, steer, t_next: float, done: float, segment: int) -> None:
        sim.command(wheels, steer)
        sim.advance(t_next)
        slip.update()
        fell = sim.fall()
        if fell:
            raise PhysicsError(fell)
        times.append(t_next)
        poses.append(sim.pose)
        counts.append(sim.encoder_counts())
        steers.append(sim.steer_angles)
        progress_of.append(done)
        segment_of.append(segment)

    behind = 0.0  # time [s] the run is behind the plan's clock (samples waiting for the steering)
    not_reached: list[int] = []
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
            if np.max(np.abs(wrap_angle(steer_k - sim.steer_angles))) >= STEER_ALIGNED:
                not_reached.append(segment + 1)
        sample(speeds[k], steer_k, float(sampled.t[k + 1]) + behind, float(sampled.progress[k]), segment)
        if progress is not None and (k + 1) % report == 0:
            progress(float(sampled.t[k + 1]), duration)
    last_steer = steer_cmd[-1] if steer_cmd is not None else None
    end = times[-1]
    while not (_at_rest(sim) or times[-1] - end >= TAIL_MAX):
        sample(stop, last_steer, times[-1] + period, 0.0, int(sampled.segment[-1]))
    at_rest = _at_rest(sim)
    driven = command_robot.rolling_index(sim.driven_names)
    radius = np.array([true_robot.wheel(n).radius for n in sim.driven_names])
    commanded = (angles[-1] - angles[0])[driven] * sim.loop_turn * radius  # as the motors turn a command
    turned = sim.wheel_angles[driven] * radius
    short = tuple(
        (name, float(commanded[i] - turned[i]), float(commanded[i]))
        for i, name in enumerate(sim.driven_names)
        if abs(commanded[i] - turned[i]) > END_ERROR + END_SHARE * abs(commanded[i])
    )
    if progress is not None:
        progress(duration, duration)
    t = np.array(times)
    extended = SampledPlan(sampled.plan, sampled.rate, t, np.array(progress_of), np.array(segment_of), sampled.xi)
    ticks = np.array(counts, dtype=np.int64)
    readings = counter_output(ticks, [command_robot.wheel(n).encoder.counter_bits for n in names])  # type: ignore[union-attr]
    steer = np.array(steers) if steerable else None
    _require_plausible_wheels(command_robot, true_robot, t, ticks)
    try:
        odometry = batch_odometry(command_robot, t, readings, steer=steer, max_wheel_accel=math.inf).poses
    except OdometryInputError as exc:  # the simulated wheels, not the input, broke the odometry's checks
        at = f" at t = {t[exc.sample]:.4g} s" if exc.sample is not None and 0 <= exc.sample < len(t) else ""
        raise PhysicsError(
            f"robot {true_robot.name!r}: the simulated wheels turned implausibly{at} ({exc.detail}): a failure of "
            f"the physics simulation (the wheels spun or the model was unstable), not of the robot file's encoders"
        ) from None
    truth = np.array(poses)[None]
    if world is not None:  # in the frame where the robot started, as the kinematic engine's
        truth[0] = between(np.asarray(start), truth[0])
    truth[..., 2] = wrap_angle(truth[..., 2])  # headings in [-pi, pi), as the kinematic engine's truth
    measured = truth[:, -1, :].copy()
    troubles = [
        WheelTrouble(name, "lagged", float(sim.lag_time[i]), float(sim.lag_start[i]), float(sim.lag_worst[i]))
        for i, name in enumerate(sim.driven_names)
        if sim.lag_time[i] > 0.0
    ] + slip.troubles()
    run = PhysicsRun(
        extended,
        t,
        ticks,
        steer,
        odometry,
        truth,
        measured,
        readings,
        saturated=sim.saturated,
        wheels=tuple(troubles),
        steering_not_reached=tuple(not_reached),
        at_rest=at_rest,
        short=short,
        contacts=(tuple(sim.contacts),) if world is not None else (),
        start=start,
    )
    return run, sim.sensors


def _require_plausible_wheels(robot: Robot, true_robot: Robot, t: np.ndarray, ticks: np.ndarray) -> None:
    """Refuse (:class:`~omnikin.errors.PhysicsError`, one line naming the wheel and the
    time) simulated encoders of ``true_robot`` that turned faster than the odometry of ``robot``
    accepts (:func:`~omnikin.odometry.plausibility.counter_rules`, the speed bound of each encoded wheel): the
    wheel spun in the simulation (the model was unstable or it lost its grip), where the odometry
    would blame the input and suggest a counter width. ``ticks``: never wrapped, one column per
    encoded wheel, at the times ``t`` [s]."""
    if len(t) < 2:
        return
    dt = np.diff(t)
    rules = counter_rules(encoded_wheels(robot))
    rates = np.array([rule.rate for rule in rules])
    beyond = np.abs(np.diff(ticks, axis=0)) > rates * dt[:, None] + QUANTISATION_SLACK
    if not beyond.any():
        return
    k, i = (int(v) for v in np.argwhere(beyond)[0])  # the earliest interval, its first wheel
    rule = rules[i]
    speed = abs(int(ticks[k + 1, i]) - int(ticks[k, i])) * abs(rule.rad_per_tick) / dt[k]
    raise PhysicsError(
        f"robot {true_robot.name!r}: the simulated wheel {rule.wheel!r} spun at {speed:.4g} rad/s between "
        f"t = {t[k]:.4g} and {t[k + 1]:.4g} s, faster than {rule.speed:.4g} rad/s ({rule.source}): the physics "
        f"simulation failed (the model was unstable or the wheel lost its grip), not the encoders"
    )


class _SlipWatch:
    """The slip of each driven wheel of ``sim`` at the samples (:data:`SLIP_TIME`,
    :data:`SLIP_ERROR`), ``period`` [s] apart."""

    def __init__(self, sim: PhysicsSim, robot: Robot, period: float):
        self.sim, self.robot = sim, robot
        self.names = sim.driven_names
        self.index = robot.rolling_index(self.names)
        self.radius = np.array([robot.wheel(n).radius for n in self.names])
        bodies = {w.name: w for w in sim.description.wheels}
        # rows side by side: the contact lies up to this far [m] along the axle from the mid-plane
        # the rows J_i describe, where the body's turn omega moves the floor by omega d along the
        # drive direction: rolling, not slip (docs/physics.md, "Rows side by side")
        self.offset = np.array(
            [max(map(abs, r.offsets)) if (r := bodies[n].rollers) is not None else 0.0 for n in self.names]
        )
        self.alpha = min(1.0, period / SLIP_TIME)
        self.period = period
        self.ms = np.zeros(len(self.names))
        self.seconds = np.zeros(len(self.names))
        self.start = np.full(len(self.names), math.nan)
        self.worst = np.zeros(len(self.names))
        self.last_steer: np.ndarray | None = None

    def update(self) -> None:
        """Take the sample; one across which the steering moved (more than :data:`STEER_ALIGNED`)
        is left out: off-centred wheels steered carry the chassis without rolling
        (docs/physics.md, known limits), which the steady-steering rows count as slip."""
        sim = self.sim
        steer = sim.steer_angles if self.robot.steerable else None
        if steer is not None:
            moved = self.last_steer is not None and np.max(np.abs(wrap_angle(steer - self.last_steer))) > STEER_ALIGNED
            self.last_steer = steer
            if moved:
                return
        rolled = self.robot.jacobian(steer) @ sim.twist
        rim = np.abs((sim.wheel_speeds - rolled)[self.index] * self.radius)
        rim = np.maximum(rim - abs(sim.twist[2]) * self.offset, 0.0)
        self.ms += (rim * rim - self.ms) * self.alpha
        beyond = self.ms > SLIP_ERROR * SLIP_ERROR
        if beyond.any():
            self.seconds += beyond * self.period
            self.start[beyond & np.isnan(self.start)] = sim.time
            np.maximum(self.worst, np.sqrt(self.ms), out=self.worst)

    def troubles(self) -> list[WheelTrouble]:
        return [
            WheelTrouble(n, "slipped", float(self.seconds[i]), float(self.start[i]), float(self.worst[i]))
            for i, n in enumerate(self.names)
            if self.seconds[i] > 0.0
        ]


def _require_support(sim: PhysicsSim, steer: np.ndarray, segment: int) -> None:
    """Refuse, before steering, a segment whose steering puts the contacts of the robot's wheels
    (off-centred wheels swing theirs round the steering axes) where they do not surround its
    centre of mass: it would tip over (:class:`~omnikin.errors.PhysicsError`)."""
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
