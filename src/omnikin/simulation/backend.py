"""The simulated wheel back-end of the runtime: the robot as built (:class:`SimBackend`).

It implements :class:`omnikin.runtime.backends.WheelBackend`: the driven (encoded) wheels
turn at the commanded speeds (ideal speed control, zero-order hold between calls) as their
motors turn them (:func:`omnikin.simulation.kinematic.wheel_motion`: a stepper the commanded
angle, a dc motor so that the true encoder's counts follow the command over the nominal scale);
the readings are the true encoders' counts converted with the nominal scale, as a driver does; each
wheel's rolling distance slips as in :class:`omnikin.simulation.error_models.NoiseModel`,
and the true robot's forward kinematics and exact SE(2) integration move the ground truth.
Steering angles move linearly from one command to the next over the following interval,
which is integrated at its middle steering angle (the discretisation the odometry uses).
"""

from __future__ import annotations

import numpy as np

from ..common.messages import shorten
from ..common.rng import make_rng
from ..errors import InputError
from ..kinematics.robot import Robot, require_same_wheels
from ..kinematics.se2 import compose, exp
from ..odometry.batch import mid_steer
from ..runtime.backends import WheelState
from ..world.collision import Collider, Contact
from .error_models import NoiseModel


class SimBackend:
    """The robot as built, simulated (module docstring). ``truth`` is its true pose; in a world
    (``collider``) it starts at ``start`` and stops at first contact, and ``contacts`` lists
    where touches began (:class:`~omnikin.world.collision.Contact`)."""

    def __init__(
        self,
        robot: Robot,
        true_robot: Robot | None = None,
        noise: NoiseModel | None = None,
        rng=None,
        start=(0.0, 0.0, 0.0),
        collider: Collider | None = None,
    ):
        self.robot = robot
        self.true_robot = true_robot or robot
        require_same_wheels(robot, self.true_robot)  # the robot as built has the robot's wheels
        self.noise = noise or NoiseModel(quantise=False)
        self.rng = make_rng(rng)
        self.encoded = robot.encoded_names
        if not self.encoded:
            raise InputError(f"robot {robot.name!r}: the simulated back-end needs encoded (driven) wheels")
        self._index = robot.rolling_index(self.encoded)
        self._radius = np.array([self.true_robot.wheel(n).radius for n in self.encoded])
        # the motors (docs/conventions.md, "Motors"): a dc motor's loop holds the counts of the true
        # encoder at the command over the nominal scale, so its wheel turns `turn` times the command
        nominal_rpt = robot.rad_per_tick(self.encoded)
        true_rpt = self.true_robot.rad_per_tick(self.encoded)
        closed = np.array([self.true_robot.wheel(n).counts_close_loop for n in self.encoded], dtype=bool)
        self._turn = np.where(closed, true_rpt / nominal_rpt, 1.0)
        self._true_rpt = np.abs(true_rpt)
        self._reading = nominal_rpt / true_rpt  # what the driver makes of the true wheel angle [rad/rad]
        self.truth = np.asarray(start, dtype=float).copy()
        self.start = self.truth.copy()  # where it started: the origin of its odometry
        self.collider = collider
        self.contacts: list[Contact] = []  # where touches began (world frame), in a world
        self.touching = False
        if collider is not None:
            collider.require_clear(self.truth)
        self.fallen = ""  # a kinematic robot cannot fall (:class:`~omnikin.simulation.engine.SimulatedBackend`)
        self.joints = None  # its wheels turn as commanded: no simulated joints
        self._angles = np.zeros(len(self.encoded))
        self._speeds = np.zeros(len(self.encoded))
        self._steer = np.zeros(len(robot.steerable)) if robot.steerable else None
        self._steer_start = None if self._steer is None else self._steer.copy()
        self._t: float | None = None
        self._first = 0.0  # the caller's time [s] of the first call
        self.writes = 0
        self.reads = 0

    def write(self, t: float, speeds, steer=None) -> None:
        speeds = np.asarray(speeds, dtype=float)
        if speeds.shape != (len(self.robot.rolling_names),) or not np.all(np.isfinite(speeds)):
            raise InputError(
                f"sim back-end: expected {len(self.robot.rolling_names)} finite wheel speeds, "
                f"got {shorten(speeds.tolist())}"
            )
        self._advance(t)
        self._speeds = speeds[self._index]
        if self._steer is not None and steer is not None:
            self._steer = np.asarray(steer, dtype=float).copy()
        self.writes += 1

    def read(self, t: float) -> WheelState:
        self._advance(t)
        self.reads += 1
        positions = self._angles.copy()
        if self.noise.quantise:
            positions = np.round(positions / self._true_rpt) * self._true_rpt
        steer = None if self._steer is None else self._steer.copy()
        return WheelState(float(t), positions * self._reading, self._speeds * self._turn * self._reading, steer)

    def _advance(self, t: float) -> None:
        if self._t is None:  # the first call starts the clock
            self._t = self._first = float(t)
            return
        dt = float(t) - self._t
        if dt <= 0:
            return
        d = self._speeds * self._turn * dt  # the true wheels' turn
        self._angles += d
        if self.noise.slip:
            sigma = self.noise.slip * np.sqrt(np.abs(d) * self._radius) / self._radius
            d = d + sigma * self.rng.standard_normal(len(d))
        steer = None
        if self._steer is not None and self._steer_start is not None:  # steering moves linearly over
            steer = mid_steer(np.stack([self._steer_start, self._steer]))[0]  # the interval: use its middle
            self._steer_start = self._steer.copy()
        f = self.true_robot.fk_matrix(steer, self.encoded)[:, : len(self.encoded)]
        inc = f @ d
        if self.noise.floor:
            inc[2] += self.noise.floor * np.sqrt(np.hypot(inc[0], inc[1])) * self.rng.standard_normal()
        if self.collider is None:
            self.truth = compose(self.truth, exp(inc))
        else:
            self.truth, touch, gone = self.collider.step(self.truth, inc)
            if touch is not None and not self.touching:
                self.contacts.append(self.collider.contact(self._t + gone * dt, self.truth))
            self.touching = touch is not None
        self._t = float(t)

    @property
    def sim_time(self) -> float:
        """Simulated time [s] since the first call (the caller's clock: this back-end never lags)."""
        return 0.0 if self._t is None else self._t - self._first

    def stats(self) -> dict:
        return {"backend": "sim", "writes": self.writes, "reads": self.reads}

    def close(self) -> None:
        pass
