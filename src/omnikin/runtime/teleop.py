"""Keyboard teleop: held keys set the components of a target twist (body frame,
``docs/conventions.md``), shared by the MuJoCo window of ``omnikin sim`` and the browser viewer
of ``omnikin view``.

A move action *sets* one component while its key is held: ``forward``/``back`` ``vx =
+/-speed``, ``left``/``right`` ``vy = +/-speed``, ``turn_left``/``turn_right`` ``omega =
+/-turn`` [m/s, rad/s; counter-clockwise positive]; letting the key go sets the component back
to zero unless another key set it since; the other components are kept, so forward and
turn_left together drive an arc. ``stop`` sets all three to zero. Front ends map their keys to
these names (W/S, A/D, Q/E and space in both) and send the target through the runtime's
:class:`~omnikin.runtime.command.CommandFilter`, whose limits and timeout act as on the real
robot.

A layout may not obey every move: a differential drive or a car cannot move sideways (the
filter drops ``vy``), a car cannot turn on the spot (the filter refuses ``omega`` alone).
:func:`moves_not_obeyed` asks the command filter itself which moves of a robot it drops or
refuses, so that front ends mark those keys in their help and say why when one is pressed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..kinematics.robot import Robot
from .command import CommandFilter

MOVES = {
    "forward": (0, 1.0),
    "back": (0, -1.0),
    "left": (1, 1.0),
    "right": (1, -1.0),
    "turn_left": (2, 1.0),
    "turn_right": (2, -1.0),
}
"""Move action -> (component of the twist, sign)."""

STEER_STEP = math.radians(15.0)
"""Steering turned by one press of ``[`` or ``]`` (``steer_left``, ``steer_right``) [rad], in the
window of ``omnikin sim`` and the page of ``omnikin view``."""


@dataclass
class Teleop:
    """The target twist set by held keys (module docstring): ``speed`` [m/s], ``turn`` [rad/s];
    ``presses`` counts the actions applied, by name."""

    speed: float
    turn: float
    target: np.ndarray = field(default_factory=lambda: np.zeros(3))
    presses: dict = field(default_factory=dict)

    def __post_init__(self):
        for name, value in (("speed", self.speed), ("turn", self.turn)):
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"{name} must be a positive number, got {value!r}")

    def value(self, action: str) -> tuple[int, float]:
        """The component and the value a move action sets."""
        axis, sign = MOVES[action]
        return axis, sign * (self.turn if axis == 2 else self.speed)

    def press(self, action: str) -> bool:
        """Apply a key press, counted by name: a move sets its component, ``stop`` clears the
        target (True); any other name (a front end's own action) changes nothing (False)."""
        self.presses[action] = self.presses.get(action, 0) + 1
        if action in MOVES:
            axis, value = self.value(action)
            self.target[axis] = value
        elif action == "stop":
            self.target[:] = 0.0
        else:
            return False
        return True

    def release(self, action: str) -> bool:
        """A move key let go: its component back to zero unless another key set it since; True
        when the target changed."""
        if action not in MOVES:
            return False
        axis, value = self.value(action)
        if self.target[axis] != value:
            return False
        self.target[axis] = 0.0
        return True

    def release_all(self) -> bool:
        """Every key let go (focus lost, link silent): the target becomes zero; True when it changed."""
        changed = bool(np.any(self.target))
        self.target[:] = 0.0
        return changed


COMPONENTS = ("vx", "vy", "omega")
"""Names of the twist components, by index."""


def moves_not_obeyed(robot: Robot) -> dict[str, str]:
    """The move actions (:data:`MOVES`) that ``robot``'s command filter does not drive as asked,
    each with a short reason (for a front end's help and notice; no key names), e.g.
    ``{"left": "its fixed wheels forbid vy", ...}`` for a differential drive.

    Each move alone, at 0.1 m/s or 0.1 rad/s, is offered to a fresh
    :class:`~omnikin.runtime.command.CommandFilter` of the robot (no limits, no timeout): a
    move whose twist it projects (fixed wheels: the part they cannot make is dropped) or
    refuses (steering beyond its limits) is listed. The answer does not depend on the speed:
    projection is linear and the steering a twist needs depends only on its direction.

    Parameters
    ----------
    robot : Robot
        The robot driven from the keys.

    Returns
    -------
    dict of str to str
        The reason of each move action it does not drive as asked, by action name; empty for a
        robot that drives every move (a holonomic one).
    """
    out = {}
    for action, (axis, sign) in MOVES.items():
        twist = np.zeros(3)
        twist[axis] = 0.1 * sign
        f = CommandFilter(robot, timeout=0.0)
        name = COMPONENTS[axis]
        if not f.command(twist, 0.0):
            out[action] = f"{name} alone needs steering beyond its limits (refused; with another move, an arc)"
        elif f.stats.projected:
            out[action] = (
                f"its fixed wheels forbid {name}"
                if not np.any(f.target)
                else f"its fixed wheels allow only part of {name}"
            )
    return out
