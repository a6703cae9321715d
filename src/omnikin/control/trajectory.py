"""A timed reference: a path with its fastest timing (:func:`plan_trajectory`), read at any time.

:class:`Trajectory` holds the path's samples with their times, and gives at any time ``t``
[s] the reference pose, world-frame velocity and acceleration (:meth:`Trajectory.at`): between
two samples the path acceleration is constant (as the timing assumed), so ``s(t)`` is
quadratic there and the pose is interpolated linearly in ``s`` between the samples (2 mm apart).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..motion.limits import MotionLimits
from .path import Path
from .time_optimal import Timing, WheelLimits, path_rates, time_optimal

MAX_CONTROL_RATE = 10_000.0
"""Highest control rate [Hz] a controller or a tracking run takes."""


def control_period(rate) -> float:
    """The period ``dt = 1 / rate`` [s] of a control rate ``rate`` [Hz] in ``(0, 10000]``; any
    other value (a bool, NaN, inf, text) an :class:`~omnikin.errors.InputError` in one line."""
    if isinstance(rate, bool) or not (isinstance(rate, (int, float)) and 0 < rate <= MAX_CONTROL_RATE):
        raise InputError(f"rate must be in (0, {MAX_CONTROL_RATE:g}] Hz, got {rate!r}")
    return 1.0 / float(rate)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A path and its timing (module docstring).

    Attributes
    ----------
    path : Path
        The geometric path.
    timing : Timing
        Time, path speed and acceleration at the path's samples.
    limits : WheelLimits
        The wheel limits it was timed within.
    wheel_speeds : ndarray, shape (n, n_wheels)
        Wheel speeds [rad/s] at the samples (rolling wheels, file order).
    steer : ndarray, shape (n, n_steer)
        Steering angles [rad] at the samples.
    body : MotionLimits or None
        The body's limits it was timed within too (None: none).
    """

    path: Path
    timing: Timing
    limits: WheelLimits
    wheel_speeds: np.ndarray
    steer: np.ndarray
    body: MotionLimits | None = None

    @property
    def duration(self) -> float:
        """Time [s] from start to end."""
        return self.timing.duration

    @property
    def t(self) -> np.ndarray:
        """Times [s] of the samples ``(n,)``."""
        return self.timing.t

    @property
    def velocity(self) -> np.ndarray:
        """World-frame rates ``(xdot, ydot, thetadot)`` [m/s, m/s, rad/s] at the samples ``(n, 3)``."""
        return self.path.d1 * self.timing.sdot[:, None]

    def at(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The reference at times ``t`` ``(...)`` [s] (clamped to ``[0, duration]``).

        Returns
        -------
        pose, velocity, acceleration : ndarray, shape (..., 3)
            ``(x, y, theta)`` [m, m, rad], its world-frame rates [m/s, m/s, rad/s] and their rates
            [m/s^2, m/s^2, rad/s^2].
        """
        tt = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        times = self.timing.t
        i = np.clip(np.searchsorted(times, tt, side="right") - 1, 0, len(times) - 2)
        tau = tt - times[i]
        sd, u = self.timing.sdot[i], self.timing.sddot[i]
        s = self.path.s
        ds = s[i + 1] - s[i]
        along = np.clip(sd * tau + 0.5 * u * tau**2, 0.0, ds)
        frac = (along / ds)[..., None]
        pose = self.path.pose[i] * (1 - frac) + self.path.pose[i + 1] * frac
        d1 = self.path.d1[i] * (1 - frac) + self.path.d1[i + 1] * frac
        d2 = self.path.d2[i] * (1 - frac) + self.path.d2[i + 1] * frac
        speed = (sd + u * tau)[..., None]
        return pose, d1 * speed, d2 * speed**2 + d1 * u[..., None]


def plan_trajectory(
    robot: Robot, path: Path, limits: WheelLimits | None = None, body: MotionLimits | None = None
) -> Trajectory:
    """The fastest :class:`Trajectory` of ``robot`` along ``path`` within ``limits`` and ``body``
    (:func:`~omnikin.control.time_optimal.time_optimal`).

    Parameters
    ----------
    robot : Robot
        The robot that drives the path.
    path : Path
        The path.
    limits : WheelLimits, optional
        Wheel speed, acceleration and steering-rate limits; default :class:`WheelLimits` ().
    body : MotionLimits, optional
        The body's speed, turn-rate and acceleration limits (a runtime's); default none.

    Returns
    -------
    Trajectory

    Raises
    ------
    InputError
        A path the robot cannot drive, or limits that are not :class:`WheelLimits`.
    """
    limits = WheelLimits() if limits is None else limits
    if not isinstance(limits, WheelLimits):
        raise InputError(f"limits must be WheelLimits, got {type(limits).__name__}")
    if body is not None and not isinstance(body, MotionLimits):
        raise InputError(f"body must be MotionLimits, got {type(body).__name__}")
    timing = time_optimal(robot, path, limits, body)
    rates = path_rates(robot, path)
    return Trajectory(path, timing, limits, rates.w * timing.sdot[:, None], rates.steer, body)
