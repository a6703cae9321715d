"""The base runtime: command in -> wheel commands out; wheel measurements in -> odometry out.

A plain class, free of ROS and of time sources (every call carries its time [s]):

* :meth:`BaseRuntime.command` offers a velocity command (:mod:`.command`: validation,
  timeout, acceleration limit, direction-keeping saturation);
* :meth:`BaseRuntime.step` reads the wheels, updates the odometry (the core streaming
  estimator, re-based at the first measurement) and its covariance, then sends the wheel
  commands (inverse kinematics of the filtered twist, steering angles included).

Covariance (motion-dependent, not a constant): each encoded wheel's angle increment has the
variance ``slip^2 |r dtheta| / r^2`` [rad^2] (distance-proportional slip as in
:mod:`omnikin.simulation.error_models`; it does not depend on the sample rate, and nothing grows
while the robot stands still). Encoder quantisation is not process noise: the quantisation
errors of successive increments telescope to that of the last reading, a bounded
``q / sqrt(12)`` per wheel, negligible against slip after a few centimetres; the body increment's
covariance is ``Sigma_xi = F diag(.) F^T`` (``F`` forward kinematics) and the pose covariance is
propagated through the exact SE(2) update ``x' = x + sinc(phi/2) R(theta + phi/2) (a, b)``,
``theta' = theta + phi`` with its Jacobians (:func:`omnikin.kinematics.se2.compose_exp_jacobians`):
``P' = J_out_pose P J_out_pose^T + J_out_tangent Sigma_xi J_out_tangent^T``. The twist
covariance is ``Sigma_xi / dt^2``. The forward-kinematics residual (redundant layouts) is
reported as a slip indicator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import compose_exp_jacobians
from ..motion.limits import MotionLimits
from ..odometry.batch import mid_steer
from ..odometry.streaming import Odometry
from .backends import WheelBackend, WheelState
from .command import CommandFilter


@dataclass(frozen=True)
class StepResult:
    """What one :meth:`BaseRuntime.step` measured and commanded."""

    t: float
    pose: tuple
    twist: tuple
    pose_covariance: np.ndarray
    twist_covariance: np.ndarray
    residual: list
    state: WheelState
    command: np.ndarray
    wheel_speeds: np.ndarray
    steer: np.ndarray | None


class BaseRuntime:
    """Command filtering, inverse kinematics, odometry with covariance (module docstring).

    Parameters
    ----------
    robot : Robot
        The robot driven (its nominal model: inverse kinematics and odometry).
    backend : WheelBackend
        The wheels (:class:`~omnikin.runtime.backends.WheelBackend`: serial, simulated, physics).
    limits : MotionLimits, optional
        Speed and acceleration limits of the commands (default: unlimited).
    cmd_vel_timeout : float
        Time [s] without a valid command after which the target becomes zero and the robot
        decelerates to a stop (0: never; :mod:`omnikin.runtime.command`).
    wheel_slip : float
        The slip coefficient of the covariance [sqrt(m)], finite and >= 0 (module docstring).
    method : {"exact", "midpoint", "euler"}
        The odometry's integration (:class:`~omnikin.odometry.streaming.Odometry`).
    """

    def __init__(
        self,
        robot: Robot,
        backend: WheelBackend,
        *,
        limits: MotionLimits | None = None,
        cmd_vel_timeout: float = 0.5,
        wheel_slip: float = 2e-4,
        method: str = "exact",
    ):
        if not (math.isfinite(wheel_slip) and wheel_slip >= 0):
            raise InputError(f"wheel_slip must be a finite number >= 0 [sqrt(m)], got {wheel_slip!r}")
        self.robot = robot
        self.backend = backend
        self.filter = CommandFilter(robot, limits or MotionLimits(), cmd_vel_timeout)
        self.odometry = Odometry(robot, method=method)
        self.encoded = self.odometry.wheel_names
        self._radius = np.array([robot.wheel(n).radius for n in self.encoded])
        self.wheel_slip = wheel_slip
        self._fk = None if robot.steerable else robot.fk_matrix(None, self.encoded)[:, : len(self.encoded)]
        self.pose_covariance = np.zeros((3, 3))
        self.twist_covariance = np.zeros((3, 3))
        self._last: WheelState | None = None
        self._steer_cmd = np.zeros(len(robot.steerable))
        self.steps = 0

    def command(self, twist, t: float) -> bool:
        """Offer a velocity command ``(vx, vy, omega)`` at time ``t``; False if rejected."""
        return self.filter.command(twist, t)

    def steer_to(self, angles) -> None:
        """Steer the steerable wheels (file order) to ``angles`` [rad] while the filtered twist is
        zero (a stopped robot keeps its steering); the next motion steers from there."""
        a = np.asarray(angles, dtype=float)
        if a.shape != self._steer_cmd.shape or not np.all(np.isfinite(a)):
            raise InputError(f"robot {self.robot.name!r}: expected {len(self._steer_cmd)} finite steering angles [rad]")
        self._steer_cmd = a.copy()

    def step(self, t: float) -> StepResult:
        """Measure, update odometry, then command the wheels, at time ``t`` [s]
        (:meth:`sense` then :meth:`act`)."""
        return self.act(t, self.sense(t))

    def sense(self, t: float) -> WheelState:
        """Read the wheels at time ``t`` [s] and update the odometry (:attr:`pose`), without
        commanding them: a controller that steers by the pose commands (:meth:`command`) between
        this and :meth:`act`, so that its command acts from ``t`` on."""
        state = self.backend.read(t)
        self._measure(state)
        return state

    def act(self, t: float, state: WheelState) -> StepResult:
        """Command the wheels at time ``t`` [s] with the filtered command, after :meth:`sense`
        read ``state``."""
        twist = self.filter.update(t)
        if self.robot.steerable:
            res = self.robot.ik(twist, steer_hint=self._steer_cmd, on_infeasible="return")
            if np.linalg.norm(twist) > 0:
                self._steer_cmd = res.steer_angles
            speeds, steer = res.wheel_speeds, self._steer_cmd
        else:
            speeds, steer = self.robot.ik(twist, on_infeasible="return").wheel_speeds, None
        self.backend.write(t, speeds, steer)
        self.steps += 1
        o = self.odometry
        return StepResult(
            t,
            o.pose,
            o.twist,
            self.pose_covariance.copy(),
            self.twist_covariance.copy(),
            list(o.residual),
            state,
            twist,
            speeds,
            steer,
        )

    def _measure(self, state: WheelState) -> None:
        before = self.odometry.pose
        self.odometry.update_angles(state.t, list(state.positions), state.steer)
        if self._last is not None and state.t > self._last.t:
            d = state.positions - self._last.positions
            var = (self.wheel_slip**2 * np.abs(d) * self._radius) / self._radius**2
            prev = self._last.steer
            steer = None if state.steer is None or prev is None else mid_steer(np.stack([prev, state.steer]))[0]
            f = self._fk if self._fk is not None else self.robot.fk_matrix(steer, self.encoded)[:, : len(self.encoded)]
            sigma_xi = f @ np.diag(var) @ f.T
            dt = state.t - self._last.t
            inc = np.array(self.odometry.twist) * dt  # the body increment the odometry just used
            j_pose, j_tangent = compose_exp_jacobians(before[2], inc)
            self.pose_covariance = j_pose @ self.pose_covariance @ j_pose.T + j_tangent @ sigma_xi @ j_tangent.T
            self.twist_covariance = sigma_xi / dt**2
        self._last = state

    @property
    def pose(self):
        return self.odometry.pose
