"""Feedforward plus feedback on the SE(2) error, for layouts that translate (:class:`PoseFeedback`).

At each control tick ``t_k`` (period ``dt``), with the pose ``p`` the robot has (its odometry),
the reference ``r_k = r(t_k)`` and the next one ``r_{k+1} = r(t_k + dt)``
(:meth:`~omnikin.control.trajectory.Trajectory.at`), the command is the constant body twist that
carries ``p`` in one period to the next reference with a fraction ``1 - gain`` of today's error
left:

    e = log(r_k^{-1} p)                           (the error, in the reference's frame)
    g = r_{k+1} exp((1 - gain) e)                 (where the robot should be at t_{k+1})
    xi = log(p^{-1} g) / dt                       (the body twist [m/s, m/s, rad/s] that gets there)

With no error (``e = 0``) it is pure feedforward, the reference's own motion over the period
(``log(r_k^{-1} r_{k+1}) / dt``); ``gain`` 1 removes an error in one period (dead-beat), smaller
gains decay it geometrically by ``1 - gain`` per period. On an exact model driven at the wheels'
limits the robot is on the reference at every tick, and between ticks off it by at most the
distance between the reference and the constant-twist arc through its two ends, bounded by
``(a + v omega) dt^2 / 8`` (``a`` [m/s^2] the reference's acceleration, ``v omega`` the bend of
the arc; docs/control.md).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import compose, exp, inverse, log
from .trajectory import Trajectory, control_period


class PoseFeedback:
    """Feedforward plus feedback on the SE(2) error (module docstring).

    Parameters
    ----------
    robot : Robot
        The robot: it must be able to translate in any direction (no fixed standard wheel).
    trajectory : Trajectory
        The timed reference.
    rate : float
        Control rate [Hz]: the period ``dt`` the command is held for.
    gain : float, default 0.5
        Fraction of the error removed per period, in ``(0, 1]``.

    Raises
    ------
    InputError
        A layout that cannot translate sideways, a rate or gain out of range.
    """

    name = "feedback"

    def __init__(self, robot: Robot, trajectory: Trajectory, *, rate: float, gain: float = 0.5):
        if robot.fixed:
            raise InputError(
                f"robot {robot.name!r} cannot move sideways (fixed wheels): the feedback controller needs "
                "a layout that translates; use pure pursuit or the MPC"
            )
        if not (isinstance(gain, (int, float)) and 0 < gain <= 1):
            raise InputError(f"gain must be in (0, 1], got {gain!r}")
        self.robot = robot
        self.trajectory = trajectory
        self.dt = control_period(rate)
        self.gain = float(gain)

    def command(self, t: float, pose) -> np.ndarray:
        """The body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] to hold from ``t`` [s] for one
        period, the robot at ``pose`` ``(x, y, theta)`` [m, m, rad] (world frame)."""
        p = np.asarray(pose, dtype=float)
        ref, _, _ = self.trajectory.at(np.array([t, t + self.dt]))
        error = log(compose(inverse(ref[0]), p))
        goal = compose(ref[1], exp((1.0 - self.gain) * error))
        return log(compose(inverse(p), goal)) / self.dt
