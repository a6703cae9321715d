"""Velocity commands: validation, timeout, acceleration limit and saturation.

One meaning everywhere (ros2_controllers' controllers disagree on it):

* ``cmd_vel_timeout`` [s]: when no valid command arrived for this long, the target becomes
  zero and the robot decelerates to a stop within its acceleration limits; ``0`` disables
  the timeout.
* Acceleration: the twist moves towards the target by one step per update whose linear and
  angular parts stay within ``linear_accel * dt`` and ``angular_accel * dt``; the step is
  scaled as a whole, so the change keeps its direction.
* Speed: the whole twist is scaled by one factor so that the body and every wheel stay
  within their limits (:func:`omnikin.motion.limits.saturate`): direction and curvature
  are kept.
* A command with NaN, infinity or a component beyond ``reject_above`` times its limit is
  rejected and counted; the previous target stays. On a robot with fixed wheels the part of
  a command the wheels cannot make (``vy`` of a differential drive) is dropped and counted
  (``projected``), as a joystick sends it; a twist that needs steering beyond the limits
  is rejected.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..common.messages import digits_apart
from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.limits import MotionLimits, saturate


@dataclass
class CommandStats:
    """Counts of what happened to the commands."""

    accepted: int = 0
    rejected: int = 0
    timeouts: int = 0
    saturated: int = 0  # accepted commands scaled down to the limits
    projected: int = 0  # accepted commands with an infeasible part dropped
    last_reject_reason: str = ""


@dataclass
class CommandFilter:
    """Turns raw commands into the twist to drive now (module docstring)."""

    robot: Robot
    limits: MotionLimits = field(default_factory=MotionLimits)
    timeout: float = 0.5
    reject_above: float = 100.0
    stats: CommandStats = field(default_factory=CommandStats)

    def __post_init__(self):
        if not (math.isfinite(self.timeout) and self.timeout >= 0):
            raise InputError(f"cmd_vel_timeout must be a finite number >= 0 [s] (0 disables), got {self.timeout!r}")
        self.target = np.zeros(3)
        self._limited_target = np.zeros(3)  # target saturated to the speed limits ...
        self._limited_for = (self.robot, self.limits)  # ... of this robot and these limits
        self.current = np.zeros(3)
        self._last_command_t = None
        self._timed_out = True
        self._last_t = None

    def command(self, twist, t: float) -> bool:
        """Offer a new target twist at time ``t`` [s]; returns False if rejected (counted)."""
        try:
            v = np.asarray(twist, dtype=float).reshape(3)
        except (TypeError, ValueError):
            return self._reject(f"not three numbers: {twist!r}")
        if not np.all(np.isfinite(v)):
            return self._reject(f"non-finite component in {v.tolist()}")
        bounds = [self.limits.linear, self.limits.linear, self.limits.angular]
        for value, bound, name in zip(v, bounds, ("vx", "vy", "omega"), strict=True):
            if bound is not None and abs(value) > self.reject_above * bound:
                most = self.reject_above * bound
                digits = digits_apart(abs(value), most)
                return self._reject(
                    f"{name} = {value:.{digits}g} is beyond {most:.{digits}g} ({self.reject_above:g} times its "
                    f"limit {bound:g})"
                )
        if self.robot.fixed:
            n = self.robot.admissible_basis
            p = n @ (n.T @ v)
            if not np.allclose(p, v, atol=1e-12):
                self.stats.projected += 1
                v = p
        if self.robot.steerable:
            res = self.robot.ik(v, on_infeasible="return")
            if not np.all(res.feasible):
                return self._reject(f"twist {v.tolist()} needs steering beyond the limits of {self.robot.name!r}")
        limited = saturate(self.robot, v, self.limits)
        if not np.allclose(limited, v):
            self.stats.saturated += 1
        self.target = v
        self._limited_target = limited
        self._limited_for = (self.robot, self.limits)
        self._last_command_t = float(t)
        self._timed_out = False
        self.stats.accepted += 1
        return True

    def _reject(self, reason: str) -> bool:
        self.stats.rejected += 1
        self.stats.last_reject_reason = reason
        return False

    def update(self, t: float) -> np.ndarray:
        """The twist to drive at time ``t`` [s] (timeout, acceleration limit, saturation)."""
        dt = 0.0 if self._last_t is None else max(0.0, t - self._last_t)
        self._last_t = t
        if (
            self.timeout > 0
            and self._last_command_t is not None
            and not self._timed_out
            and t - self._last_command_t > self.timeout
        ):
            self._timed_out = True
            self.stats.timeouts += 1
        if self._limited_for != (self.robot, self.limits):  # limits replaced since the command
            self._limited_target = saturate(self.robot, self.target, self.limits)
            self._limited_for = (self.robot, self.limits)
        limited = np.zeros(3) if (self._timed_out or self._last_command_t is None) else self._limited_target
        self.current = self._accelerate(self.current, limited, dt)
        return self.current.copy()

    def _accelerate(self, current: np.ndarray, target: np.ndarray, dt: float) -> np.ndarray:
        step = target - current
        k = 1.0
        lin, ang = math.hypot(step[0], step[1]), abs(step[2])
        if self.limits.linear_accel is not None and lin > 0:
            k = min(k, self.limits.linear_accel * dt / lin)
        if self.limits.angular_accel is not None and ang > 0:
            k = min(k, self.limits.angular_accel * dt / ang)
        return current + k * step

    def halt(self) -> None:
        """Forget the target and the current twist (the wheels were stopped from outside, e.g.
        by a lost link): zero until a new command arrives. Not counted as a timeout."""
        self.target = np.zeros(3)
        self._limited_target = np.zeros(3)
        self.current = np.zeros(3)
        self._timed_out = True
        self._last_t = None  # the next update starts from rest: no step over the gap

    @property
    def timed_out(self) -> bool:
        return self._timed_out
