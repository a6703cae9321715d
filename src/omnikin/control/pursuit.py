"""Regulated pure pursuit for layouts that drive along their heading: differential drives and
cars (:class:`PurePursuit`).

Pure pursuit (Coulter, "Implementation of the Pure Pursuit Path Tracking Algorithm",
CMU-RI-TR-92-01, 1992) steers towards the point of the path a lookahead distance ``L`` ahead:
with that point at ``(x_t, y_t)`` in the robot's frame (``x`` forward), the arc through it
tangent to the heading has the curvature

    kappa = 2 y_t / (x_t^2 + y_t^2),

and the command is ``(v, 0, v kappa)``. As in Macenski et al.'s regulated pure pursuit
("Regulated Pure Pursuit for Robot Path Tracking", Autonomous Robots 47, 2023) the lookahead
grows with the speed (``L = clip(LOOKAHEAD_TIME v, LOOKAHEAD_MIN, LOOKAHEAD_MAX)``) and the speed
is regulated; here by the path's own fastest timing: ``v`` is the reference's speed at the point
of the path the robot has reached (not at the clock's time, so a robot that falls behind is not
hurried on), at least :data:`CREEP_SPEED` until it is within :data:`GOAL_TOLERANCE` of the end,
where it stops. A car's curvature is held within its steering (:attr:`PurePursuit.max_curvature`,
found from its inverse kinematics). The runtime's saturation to the wheel limits scales ``v`` and
``omega`` together, so the curvature is kept.

The point reached is the nearest sample of the path within a window ahead of the last one (the
progress never goes back, and a path that crosses itself is followed on, not jumped across).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from .path import SPACING, heading_error
from .trajectory import Trajectory, control_period

LOOKAHEAD_TIME = 0.25
"""Lookahead per speed [s]: ``L = LOOKAHEAD_TIME v``, within the bounds below. A shorter one
cuts curves less (the figure-eight of 1 m by a differential drive, RMS: 5.0 mm at 0.25 s, 2.6 mm
at 0.2 s, 8.4 mm at 0.3 s, 45 mm at 0.6 s) and follows noise in the pose more."""
LOOKAHEAD_MIN = 0.06
"""Shortest lookahead [m]."""
LOOKAHEAD_MAX = 1.0
"""Longest lookahead [m]."""
CREEP_SPEED = 0.02
"""Least speed [m/s] before the end is reached (the timing's speed falls to 0 at the end)."""
GOAL_TOLERANCE = 0.005
"""Distance [m] from the path's end at which the robot stops."""


def max_curvature(robot: Robot) -> float:
    """The largest ``|omega / v|`` [1/m] ``robot`` can drive forward (a car's tightest turn; inf
    for a robot that can turn in place), by bisection on its inverse kinematics' feasibility."""
    if robot.ik([1.0, 0.0, 1e6], on_infeasible="return").feasible.all():
        return math.inf
    low, high = 0.0, 1e6
    for _ in range(200):
        mid = 0.5 * (low + high)
        left = robot.ik([1.0, 0.0, mid], on_infeasible="return").feasible.all()
        right = robot.ik([1.0, 0.0, -mid], on_infeasible="return").feasible.all()
        low, high = (mid, high) if (left and right) else (low, mid)
        if high - low <= 1e-9 * max(1.0, low):
            break
    return low


class PurePursuit:
    """Regulated pure pursuit along a timed path (module docstring).

    Parameters
    ----------
    robot : Robot
        A layout that drives along its heading: it must make the twist ``(1, 0, 0)``.
    trajectory : Trajectory
        The timed reference: its path, and its speed at each sample.
    rate : float
        Control rate [Hz].

    Attributes
    ----------
    max_curvature : float
        The largest curvature [1/m] commanded.

    Raises
    ------
    InputError
        A layout that cannot drive straight ahead, a path it cannot follow (a heading that is
        not its direction of travel), a rate out of range.
    """

    name = "pursuit"

    def __init__(self, robot: Robot, trajectory: Trajectory, *, rate: float):
        self.dt = control_period(rate)
        if not robot.ik([1.0, 0.0, 0.0], on_infeasible="return").feasible.all():
            raise InputError(f"robot {robot.name!r} cannot drive straight ahead: pure pursuit drives along the heading")
        path = trajectory.path
        moving = np.hypot(path.d1[:, 0], path.d1[:, 1]) > 1e-9
        along = np.arctan2(path.d1[:, 1], path.d1[:, 0])
        off = np.abs(heading_error(along, path.pose[:, 2]))
        bad = np.flatnonzero(moving & (off > 1e-3))
        if bad.size:
            k = int(bad[0])
            raise InputError(
                f"path {path.name!r}: at s = {path.s[k]:.6g} m its heading is not its direction of travel; "
                "pure pursuit follows paths along their tangent (heading tangent)"
            )
        self.robot = robot
        self.trajectory = trajectory
        self.max_curvature = max_curvature(robot)
        self._xy = path.pose[:, :2]
        self._s = path.s
        # the reference's travel speed [m/s] at each sample: sdot times the travel per unit of s
        self._speed = trajectory.timing.sdot * np.hypot(path.d1[:, 0], path.d1[:, 1])
        self._progress = 0
        self._top = float(np.max(self._speed)) if len(self._speed) else 0.0

    def command(self, t: float, pose) -> np.ndarray:
        """The body twist ``(v, 0, omega)`` [m/s, m/s, rad/s] to hold from ``t`` [s] for one
        period, the robot at ``pose`` ``(x, y, theta)`` [m, m, rad] (world frame)."""
        p = np.asarray(pose, dtype=float)
        xy = self._xy
        # the point reached: the nearest sample in a window ahead (never back)
        reach = max(8, int(4 * max(self._top, CREEP_SPEED) * self.dt / SPACING) + 8)
        window = slice(self._progress, min(len(xy), self._progress + reach))
        gap = np.hypot(*(xy[window] - p[:2]).T)
        self._progress += int(np.argmin(gap))
        k = self._progress
        end_gap = float(np.hypot(*(xy[-1] - p[:2])))
        if end_gap <= GOAL_TOLERANCE and k >= len(xy) - 1 - reach:
            return np.zeros(3)
        v = max(float(self._speed[k]), CREEP_SPEED)
        lookahead = min(max(LOOKAHEAD_TIME * v, LOOKAHEAD_MIN), LOOKAHEAD_MAX)
        # the target: the first sample a lookahead away, among those within three lookaheads (and
        # the robot's distance) of path ahead, not the whole rest of the path every tick
        last = int(np.searchsorted(self._s, self._s[k] + 3 * lookahead + float(gap.min()), side="right"))
        ahead = np.hypot(*(xy[k:last] - p[:2]).T)
        beyond = np.flatnonzero(ahead >= lookahead)
        target = xy[k + int(beyond[0])] if beyond.size else xy[last - 1]
        c, s = math.cos(p[2]), math.sin(p[2])
        dx, dy = target - p[:2]
        forward, left = c * dx + s * dy, -s * dx + c * dy
        distance2 = forward * forward + left * left
        if distance2 <= 1e-18:
            return np.zeros(3)
        if not beyond.size and last == len(xy):  # the end is nearer than the lookahead: slow down onto it
            v = min(v, max(CREEP_SPEED, math.sqrt(distance2) / max(self.dt, 1e-9) / 4))
        kappa = 2.0 * left / distance2
        kappa = max(-self.max_curvature, min(self.max_curvature, kappa))
        return np.array([v, 0.0, v * kappa])
