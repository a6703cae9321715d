"""The physics wheel back-end of the runtime: the robot as built, in MuJoCo (:class:`PhysicsBackend`).

It implements :class:`omnikin.runtime.backends.WheelBackend` as a drop-in for the kinematic
:class:`omnikin.simulation.backend.SimBackend` (same constructor shape, same ``truth``): wheel
commands go to the driven wheels' motors of :class:`~omnikin.physics.simulator.PhysicsSim`
(ramped, torque-limited; zero-order hold between calls), the model is stepped up to each call's
time, and the encoders are read from the wheel joints. Slip, wheel dynamics and roller contact
come from the physics, so there is no noise model; ``quantise`` switches the tick
quantisation off.

Readings as the runtime's driver would give them: the encoder of the robot *as built*
(``true_robot``) counts whole ticks of its wheel's angle, and the driver converts them with the
*nominal* robot's scale, ``position = ticks * rad_per_tick`` [rad] (the same scale error a
real driver makes when the file's ``ticks_per_rev`` or ``gear_ratio`` is wrong); speeds are the
joint speeds converted with the same ratio. The clock starts at the first call, as in
``SimBackend``; calls with a time not after the last one move nothing.

Wheels turn by their motors (:attr:`omnikin.kinematics.wheels.Wheel.motor`): a dc motor's speed loop counts
by the nominal robot's encoder scale (``controller`` of :class:`~omnikin.physics.simulator.PhysicsSim`).

**A robot that tips over** (:meth:`~omnikin.physics.simulator.PhysicsSim.fall`, checked at every
call) is reported, never driven on: :attr:`PhysicsBackend.fallen` holds the one line (also in
``stats()["fallen"]``, which the ROS node turns into an ERROR in ``/diagnostics`` and the viewer
into a notice), and from then on every command is replaced by zero wheel speeds.

**Real time** (``max_lag``, the ROS node's wall clock): each call steps the model up to the
time it is asked for, so a late call catches up. Where the physics runs slower than real time,
catching up fully would make every call later than the last; with ``max_lag`` [s] a call steps
at most ``max_lag`` of simulated time beyond where the model stands, and the rest of the
interval is *dropped*: the simulation clock slips behind the caller's, the robot moves as if
the dropped time had not passed (as Gazebo's real-time factor below 1 does). ``stats()``
counts it (``time_dropped`` [s], ``lag_events``) so it is never silent. ``None`` (the default)
catches up exactly, as offline runs need.
"""

from __future__ import annotations

import math

import numpy as np

from ..common.messages import shorten
from ..errors import InputError
from ..kinematics.robot import Robot, require_same_wheels
from ..kinematics.se2 import wrap_angle
from ..runtime.backends import WheelState
from ..sensors.readings import Readings, SensorStream
from ..world.collision import Contact
from ..world.model import World
from .mjcf import DEFAULT_STEP
from .simulator import PhysicsSim

SENSOR_KEEP = 10.0
"""Seconds of sensor samples the back-end holds for :meth:`PhysicsBackend.sensor_readings`:
a caller that never asks (the window, the viewer) leaves the older ones behind."""


class PhysicsBackend:
    """The robot as built (``true_robot``, default ``robot``), simulated in MuJoCo from ``start``
    ``(x, y, theta)`` at time step ``step`` [s], in ``world`` (None: an empty floor; module
    docstring). ``truth`` is its true pose (heading wrapped to ``[-pi, pi)``, as ``SimBackend``'s);
    ``sim`` the simulation itself; ``contacts`` where it began to touch the world's bodies;
    :meth:`sensor_readings` what its IMUs and lidars read, errors drawn from ``sensor_rng``."""

    def __init__(
        self,
        robot: Robot,
        true_robot: Robot | None = None,
        *,
        start=(0.0, 0.0, 0.0),
        step: float = DEFAULT_STEP,
        quantise: bool = True,
        max_lag: float | None = None,
        world: World | None = None,
        sensor_rng: np.random.Generator | None = None,
    ):
        self.robot = robot
        self.true_robot = true_robot or robot
        require_same_wheels(robot, self.true_robot)
        self.encoded = robot.encoded_names
        if not self.encoded:
            raise InputError(f"robot {robot.name!r}: the physics back-end needs encoded (driven) wheels")
        self.sim = PhysicsSim(
            self.true_robot, start=start, step=step, controller=robot, world=world, sensors=SENSOR_KEEP
        )
        self._sensor_errors = SensorStream(self.true_robot, sensor_rng)
        self.start = np.array(start, dtype=float)  # where it started: the origin of its odometry
        self.fallen = ""
        """Empty while the robot stands; once it tipped over (:meth:`PhysicsSim.fall`), that one
        line, and every later command is replaced by zero wheel speeds (module docstring)."""
        self.quantise = bool(quantise)
        if max_lag is not None and not (math.isfinite(max_lag) and max_lag > 0.0):
            raise InputError(f"physics back-end: max_lag must be a finite time > 0 s, got {shorten(max_lag)}")
        self.max_lag = max_lag
        self.time_dropped = 0.0  # [s] of the caller's clock not simulated (real-time mode)
        self.lag_events = 0  # calls that dropped time
        true = self.true_robot
        self._order = np.array([robot.rolling_index([n])[0] for n in true.rolling_names], dtype=int)
        self._steer_order = np.array([robot.steer_names.index(n) for n in true.steer_names], dtype=int)
        self._encoded = np.array(true.rolling_index(self.encoded), dtype=int)
        true_scale = true.rad_per_tick(self.encoded)
        self._true_rpt = true_scale
        self._scale = robot.rad_per_tick(self.encoded) / true_scale
        self._steer: np.ndarray | None = np.zeros(len(robot.steerable)) if robot.steerable else None
        self._t0: float | None = None
        self.writes = 0
        self.reads = 0

    @property
    def contacts(self) -> list[Contact]:
        """Where the robot began to touch a body of the world (world frame)."""
        return self.sim.contacts

    @property
    def joints(self) -> PhysicsSim:
        """The simulated joints: :attr:`sim` (:class:`~omnikin.simulation.engine.SimulatedJoints`)."""
        return self.sim

    def sensor_readings(self) -> Readings | None:
        """What the robot's IMUs and lidars read since the previous call (their times [s] on the
        simulation's clock: :meth:`caller_time` on the caller's), with their errors (``sensor_rng``; None: exact);
        None for a robot without them."""
        sensors = self.sim.sensors
        if sensors is None:
            return None
        return self._sensor_errors.apply(sensors.drain())

    @property
    def sim_time(self) -> float:
        """Simulated time [s] since the start (behind the caller's clock by what was dropped)."""
        return self.sim.time

    def caller_time(self, t: float) -> float:
        """The caller's clock [s] (the times ``write`` and ``read`` are given) at simulated time
        ``t`` [s] (a sensor reading's), counting the time dropped so far (module docstring);
        before the first call, ``t`` itself."""
        return (self._t0 or 0.0) + float(t)

    @property
    def truth(self) -> np.ndarray:
        """True pose ``(x, y, theta)`` [m, m, rad] of the robot as built, ``theta`` wrapped."""
        pose = self.sim.pose
        pose[2] = wrap_angle(float(pose[2]))
        return pose

    def write(self, t: float, speeds, steer=None) -> None:
        speeds = np.asarray(speeds, dtype=float)
        n = len(self.robot.rolling_names)
        if speeds.shape != (n,) or not np.all(np.isfinite(speeds)):
            raise InputError(f"physics back-end: expected {n} finite wheel speeds, got {shorten(speeds.tolist())}")
        if steer is not None and self._steer is not None:
            angles = np.asarray(steer, dtype=float)
            if angles.shape != self._steer.shape or not np.all(np.isfinite(angles)):
                raise InputError(
                    f"physics back-end: expected {len(self._steer)} finite steering angles, "
                    f"got {shorten(angles.tolist())}"
                )
            self._steer = angles.copy()
        self._advance(t)
        steer_true = None if self._steer is None else self._steer[self._steer_order]
        if self.fallen:  # a robot on its side does not drive on: its wheels are stopped
            speeds = np.zeros_like(speeds)
            steer_true = None
        self.sim.command(speeds[self._order], steer_true)
        self.writes += 1

    def read(self, t: float) -> WheelState:
        self._advance(t)
        self.reads += 1
        angles = self.sim.wheel_angles[self._encoded]
        if self.quantise:
            positions = np.rint(angles / self._true_rpt) * self._true_rpt * self._scale
        else:
            positions = angles * self._scale
        speeds = self.sim.wheel_speeds[self._encoded] * self._scale
        steer = None
        if self._steer is not None:
            steer = np.empty(len(self._steer))
            steer[self._steer_order] = self.sim.steer_angles
        return WheelState(float(t), positions, speeds, steer)

    def _advance(self, t: float) -> None:
        if self._t0 is None:  # the first call starts the clock
            self._t0 = float(t)
            return
        behind = float(t) - self._t0 - self.sim.time
        if self.max_lag is not None and behind > self.max_lag:
            dropped = behind - self.max_lag
            self._t0 += dropped  # the simulation clock slips behind the caller's
            self.time_dropped += dropped
            self.lag_events += 1
        self.sim.advance(float(t) - self._t0)
        if not self.fallen:
            fell = self.sim.fall()
            if fell:
                self.fallen = fell
                self.sim.command(np.zeros(len(self.true_robot.rolling)), None)

    def stats(self) -> dict:
        return {
            "backend": "physics",
            "writes": self.writes,
            "reads": self.reads,
            "sim_time": self.sim.time,
            "saturated": self.sim.saturated,
            "wheels_lagging": ", ".join(  # wheels that did not follow their set-points, and for how long
                f"{name} {seconds:.3g} s"
                for name, seconds in zip(self.sim.driven_names, self.sim.lag_time, strict=True)
                if seconds > 0.0
            ),
            "time_dropped": self.time_dropped,
            "lag_events": self.lag_events,
            "fallen": self.fallen,
        }

    def close(self) -> None:
        pass
