"""Drive to a goal pose: the twist to command at each control step, along a path the robot's
wheels can make.

:class:`GoalSeeker` looks at what the layout can do (its inverse kinematics' feasibility,
:meth:`omnikin.kinematics.robot.Robot.ik`) and picks one of three paths (world frame, ``docs/conventions.md``):

- ``straight`` (the robot translates in any direction: omni, mecanum, steered legs, synchro):
  along the segment to the goal, turning to the goal's heading on the way when the robot can
  turn in place (else the heading stays: Villasenor et al.'s legs cannot spin on the spot);
  the commanded body velocity is the world direction to the goal turned into the body frame, so
  the path stays on the segment while the robot turns;
- ``turn-drive-turn`` (fixed wheels on one axle, a differential drive): turn on the spot to face
  the goal, drive straight with the heading held on it, turn to the goal's heading;
- ``arc-line`` (no turning on the spot, no sideways motion: a car): forward on the tightest arc
  the steering allows (:attr:`GoalSeeker.curvature`) towards the goal until it is ahead, then
  straight; the goal's heading is not controlled (a path ending at a given heading needs
  manoeuvres, Dubins 1957). When the goal lies inside the tightest circle on its side, the
  robot turns the other way and comes round.

Speeds: each motion runs at ``speed`` [m/s] or ``turn`` [rad/s] and slows down to stop at its
end within the deceleration ``accel``/``angular_accel`` (the profile ``v = sqrt(2 a d)`` with a
margin), so the command filter's acceleration limits never make it overshoot. The pose the
seeker steers by is the caller's (the robot's odometry, as on a real robot). Arrived: within
``tolerance`` [m] of the goal's position and, where the heading is controlled,
``heading_tolerance`` [rad] of its heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..common.messages import shorten
from ..errors import InputError
from ..kinematics.robot import Robot
from ..kinematics.se2 import wrap_angle

STRATEGIES = ("straight", "turn-drive-turn", "arc-line")
PROBE = 0.1
"""Speed [m/s] (and turn rate [rad/s]) of the twists that probe what the layout can do."""
BRAKING_MARGIN = 0.8
"""Fraction of the deceleration limit the speed profiles plan with."""
FACING = math.radians(2.0)
"""Bearing error [rad] below which turn-drive-turn and arc-line drive straight."""


def feasible(robot: Robot, twist) -> bool:
    """True when ``robot``'s wheels can make ``twist`` (steering within limits, no side slip)."""
    res = robot.ik(np.asarray(twist, dtype=float), on_infeasible="return")
    if not np.all(res.feasible):
        return False
    return res.violation.size == 0 or bool(np.all(np.abs(res.violation) < 1e-9))


def tightest_curvature(robot: Robot) -> float:
    """The largest curvature [1/m] of a forward arc ``(v, 0, kappa v)`` the robot can drive
    (bisection on feasibility; 0 when it cannot turn while driving)."""
    if not feasible(robot, (PROBE, 0.0, PROBE * 1e-3)):
        return 0.0
    low, high = 1e-3, 1e3
    if feasible(robot, (PROBE, 0.0, PROBE * high)):
        return high
    for _ in range(60):
        mid = math.sqrt(low * high)
        if feasible(robot, (PROBE, 0.0, PROBE * mid)):
            low = mid
        else:
            high = mid
    return low


def strategy_for(robot: Robot) -> str:
    """The path :class:`GoalSeeker` takes for this layout (module docstring)."""
    translates = all(feasible(robot, (PROBE * math.cos(a), PROBE * math.sin(a), 0.0)) for a in (0.0, 1.0, 2.0, 4.0))
    if translates:
        return "straight"
    if feasible(robot, (0.0, 0.0, PROBE)) and feasible(robot, (PROBE, 0.0, 0.0)):
        return "turn-drive-turn"
    if tightest_curvature(robot) > 0:
        return "arc-line"
    raise InputError(f"robot {robot.name!r} can neither translate, turn on the spot nor drive an arc")


FINAL_APPROACH = 0.15
"""Time constant [s] of the last millimetres: the speed is at most ``remaining / FINAL_APPROACH``, so
that a control loop that sees the pose a step or two late (the command acts over the next step,
the odometry reads it after) creeps in instead of overshooting."""


def braking_speed(top: float, accel: float | None, remaining: float) -> float:
    """The speed that stops within ``remaining`` (distance or angle) at ``BRAKING_MARGIN accel``
    and creeps in over the last of it (:data:`FINAL_APPROACH`), at most ``top``."""
    remaining = max(remaining, 0.0)
    creep = remaining / FINAL_APPROACH
    if accel is None:
        return min(top, creep)
    return min(top, creep, math.sqrt(2.0 * BRAKING_MARGIN * accel * remaining))


@dataclass
class GoalSeeker:
    """Twists that take ``robot`` to ``goal`` ``(x, y, theta)`` [m, m, rad] (module docstring)."""

    robot: Robot
    goal: tuple[float, float, float]
    speed: float = 0.2
    turn: float = 0.5
    accel: float | None = 0.5
    angular_accel: float | None = 2.0
    tolerance: float = 0.001
    heading_tolerance: float = math.radians(0.5)
    strategy: str = ""
    curvature: float = 0.0
    spins: bool = False
    phase: str = field(default="", init=False)
    _previous: tuple[float, float, float] | None = field(default=None, init=False, repr=False)
    _moving: bool = field(default=True, init=False, repr=False)
    _omega: float = field(default=0.0, init=False, repr=False)  # the turn rate last commanded [rad/s]

    def __post_init__(self):
        try:
            goal = tuple(float(v) for v in self.goal)
        except (TypeError, ValueError):
            goal = ()
        if len(goal) != 3 or not all(math.isfinite(v) for v in goal):
            raise InputError(f"a goal is three finite numbers (x [m], y [m], theta [rad]), got {shorten(self.goal)}")
        self.goal = (goal[0], goal[1], goal[2])
        self.strategy = self.strategy or strategy_for(self.robot)
        if self.strategy not in STRATEGIES:
            raise InputError(f"strategy must be one of {', '.join(STRATEGIES)}, got {self.strategy!r}")
        self.spins = feasible(self.robot, (0.0, 0.0, PROBE))
        if self.strategy == "arc-line" and not self.curvature:
            self.curvature = 0.95 * tightest_curvature(self.robot)  # inside the steering limits
        self.phase = "start"

    @property
    def controls_heading(self) -> bool:
        """Whether the robot ends at the goal's heading (module docstring)."""
        return self.spins and self.strategy != "arc-line"

    def twist(self, pose, lead: float = 0.0) -> np.ndarray | None:
        """The body twist ``(vx, vy, omega)`` to command at ``pose``; None once arrived.
        ``lead`` [s]: from the time of ``pose`` to the middle of the interval the twist will act
        over (a runtime that reads the pose, then commands for the next step: 1.5 steps); a
        turning robot's body-frame velocity is aimed with the heading it will have then, so that
        the path stays straight while it turns."""
        x, y, theta = (float(v) for v in pose)
        theta_ahead = theta + self._omega * lead
        gx, gy, gth = self.goal
        dx, dy = gx - x, gy - y
        distance = math.hypot(dx, dy)
        heading_error = float(wrap_angle(gth - theta))
        previous, self._previous = self._previous, (x, y, theta)
        self._moving = previous is None or (
            math.hypot(x - previous[0], y - previous[1]) > 0.1 * self.tolerance
            or abs(float(wrap_angle(theta - previous[2]))) > 0.1 * self.heading_tolerance
        )
        placed = distance <= self.tolerance or (self.phase == "turn" and distance <= 3 * self.tolerance)
        if placed and (not self.controls_heading or abs(heading_error) <= self.heading_tolerance):
            # there; arrived once the robot has stopped (it may still coast by the command filter's
            # deceleration: then hold still and correct what it coasted)
            if self._moving:
                self._omega = 0.0
                return np.zeros(3)  # settling: the phase stays
            self.phase = "arrived"
            return None
        bearing_error = float(wrap_angle(math.atan2(dy, dx) - theta)) if distance > self.tolerance else 0.0
        if self.strategy == "straight":
            twist = self._straight(theta_ahead, dx, dy, distance, heading_error)
        elif self.strategy == "turn-drive-turn":
            twist = self._turn_drive_turn(distance, bearing_error, heading_error)
        else:
            twist = self._arc_line(theta, dx, dy, distance, bearing_error)
        self._omega = float(twist[2])
        return twist

    def _turn_rate(self, error: float) -> float:
        return math.copysign(braking_speed(self.turn, self.angular_accel, abs(error)), error)

    def _straight(self, theta, dx, dy, distance, heading_error) -> np.ndarray:
        self.phase = "straight"
        v = braking_speed(self.speed, self.accel, distance) if distance > self.tolerance else 0.0
        ux, uy = (dx / distance, dy / distance) if distance > 0 else (0.0, 0.0)
        c, s = math.cos(theta), math.sin(theta)
        omega = self._turn_rate(heading_error) if self.spins else 0.0
        return np.array([v * (c * ux + s * uy), v * (-s * ux + c * uy), omega])

    def _turn_drive_turn(self, distance, bearing_error, heading_error) -> np.ndarray:
        near = max(20 * self.tolerance, 0.02)  # closer than this the robot backs up rather than turn round
        if self.phase == "drive" and distance <= self.tolerance and self._moving:
            return np.zeros(3)  # (the caller records omega 0)  # stop on the goal before turning on it
        if self.phase != "turn" and distance > self.tolerance or distance > 3 * self.tolerance:
            if self.phase in ("start", "face") and abs(bearing_error) > FACING and distance > near:
                self.phase = "face"
                return np.array([0.0, 0.0, self._turn_rate(bearing_error)])
            self.phase = "drive"
            along = math.cos(bearing_error)  # < 0: the goal is behind (coasted past it)
            ahead_error = bearing_error if along >= 0 else float(wrap_angle(bearing_error + math.pi))
            v = math.copysign(braking_speed(self.speed, self.accel, distance * abs(along)), along)
            omega = self._turn_rate(ahead_error) * min(1.0, distance / near)
            return np.array([v, 0.0, omega])
        self.phase = "turn"
        return np.array([0.0, 0.0, self._turn_rate(heading_error)])

    def _arc_line(self, theta, dx, dy, distance, bearing_error) -> np.ndarray:
        c, s = math.cos(theta), math.sin(theta)
        bx, by = c * dx + s * dy, -s * dx + c * dy  # the goal in the body frame
        v = braking_speed(self.speed, self.accel, distance)
        if abs(bearing_error) <= FACING:
            self.phase = "line"
            kappa = 2.0 * by / max(distance * distance, 1e-12)  # pure pursuit onto the goal
            return np.array([v, 0.0, v * max(-self.curvature, min(self.curvature, kappa))])
        radius = 1.0 / self.curvature
        side = 1.0 if by >= 0 else -1.0
        if math.hypot(bx, by - side * radius) < radius:  # inside the tightest circle on its side
            side = -side
        self.phase = "arc"
        v = min(self.speed, max(v, 0.3 * self.speed))  # the arc leads round: no braking on it
        return np.array([v, 0.0, side * self.curvature * v])
