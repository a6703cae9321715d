"""The tracking controllers by name, the one a layout gets by default, and building one for a
trajectory (:func:`build_controller`): one place for ``omnikin track``, ``omnikin.track`` and
the path followers of the ROS node and the viewer (:mod:`omnikin.control.follower`).

A controller gives the body twist to hold for one control period from the time and the pose the
robot has (:class:`Controller`).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..common.messages import shorten
from ..errors import InputError
from ..kinematics.robot import Robot
from .trajectory import Trajectory

CONTROLLERS = {
    "feedback": "feedforward plus feedback on the SE(2) error (layouts that translate: omni, mecanum)",
    "mpc": "model predictive control with every wheel's speed and acceleration limit as constraints "
    "(OSQP, extra control; layouts whose wheels do not steer)",
    "pursuit": "regulated pure pursuit (layouts that drive along their heading: differential drives, cars)",
}
"""The controllers by name, with what they are."""

STEERED_GAIN = 0.2
"""The feedback controller's gain (:class:`~omnikin.control.feedback.PoseFeedback`: the share of
the pose error removed per period) for a layout that steers its wheels; 0.5 for the others. Its
corrections turn the wheels, which swing round behind them: in MuJoCo a synchro drive's blended
1 m square was tracked to 151 mm RMS at 0.5 and to 26 mm at 0.2 (docs/control.md)."""


class Controller(Protocol):
    """A tracking controller: a body twist from the time and the robot's pose."""

    name: str

    def command(self, t: float, pose) -> np.ndarray:
        """Body twist ``(vx, vy, omega)`` [m/s, m/s, rad/s] to hold from ``t`` [s] (the
        trajectory's time), the robot at ``pose`` ``(x, y, theta)`` [m, m, rad] (its frame)."""
        ...


def default_controller(robot: Robot) -> str:
    """The controller a layout gets when none is named: ``feedback`` for a layout that translates
    in any direction, ``mpc`` for one with fixed wheels that do not steer (a differential drive),
    ``pursuit`` for one with fixed and steered wheels (a car)."""
    if not robot.fixed:
        return "feedback"
    return "pursuit" if robot.steerable else "mpc"


def check_controller(name) -> str:
    """``name`` if it is one of :data:`CONTROLLERS`; else an :class:`~omnikin.errors.InputError`
    in one line listing them."""
    if not isinstance(name, str) or name not in CONTROLLERS:
        raise InputError(f"controller must be one of {', '.join(CONTROLLERS)}, got {shorten(name)}")
    return name


def check_controller_for(name: str | None, robot: Robot) -> str:
    """The controller ``name`` (default :func:`default_controller`) if ``robot``'s layout can be
    driven by it, before any path: ``feedback`` needs a layout that translates, ``mpc`` one whose
    wheels do not steer, ``pursuit`` one that drives straight ahead; else an
    :class:`~omnikin.errors.InputError` in one line (a node's parameters, checked at start)."""
    name = default_controller(robot) if name is None else check_controller(name)
    if name == "feedback" and robot.fixed:
        raise InputError(
            f"robot {robot.name!r} cannot move sideways (fixed wheels): the feedback controller needs a layout "
            "that translates; use pursuit or mpc"
        )
    if name == "mpc" and robot.steerable:
        raise InputError(f"robot {robot.name!r} steers its wheels: the MPC is for layouts whose wheels do not steer")
    if name == "pursuit" and not robot.ik([1.0, 0.0, 0.0], on_infeasible="return").feasible.all():
        raise InputError(f"robot {robot.name!r} cannot drive straight ahead: pure pursuit drives along the heading")
    return name


def build_controller(name: str | None, robot: Robot, trajectory: Trajectory, *, rate: float) -> Controller:
    """The controller ``name`` (default :func:`default_controller`) of ``robot`` tracking
    ``trajectory`` at ``rate`` [Hz].

    Raises
    ------
    InputError
        An unknown name, a layout the controller cannot drive (named in the line), a rate out of
        range; ``mpc`` without OSQP names the extra ``control``.
    """
    name = default_controller(robot) if name is None else check_controller(name)
    if name == "feedback":
        from .feedback import PoseFeedback

        return PoseFeedback(robot, trajectory, rate=rate, gain=STEERED_GAIN if robot.steerable else 0.5)
    if name == "mpc":
        from .mpc import PoseMPC

        return PoseMPC(robot, trajectory, rate=rate)
    from .pursuit import PurePursuit

    return PurePursuit(robot, trajectory, rate=rate)
