"""Motion limits and wheel-speed saturation that keeps the command's direction.

ros2_controllers clamps each axis on its own, which bends the path (a clamped vx with an
unclamped omega changes the curvature). omnikin scales the *whole* twist by one factor
``k in (0, 1]``: direction of travel and curvature ``omega / |v|`` are kept, only the pace
changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..common.arrays import as_components, require_finite
from ..errors import InputError


@dataclass(frozen=True)
class MotionLimits:
    """Speed and acceleration limits of the body and the wheels (None: unlimited).

    ``linear`` [m/s] bounds ``hypot(vx, vy)``; ``angular`` [rad/s] bounds ``|omega|``;
    ``linear_accel`` [m/s^2] and ``angular_accel`` [rad/s^2] likewise the rates of change;
    ``wheel`` [rad/s] bounds every wheel speed (a wheel's own ``max_speed`` in the robot
    file applies too, whichever is smaller).
    """

    linear: float | None = 0.3
    angular: float | None = 1.0
    linear_accel: float | None = 0.5
    angular_accel: float | None = 2.0
    wheel: float | None = None

    def __post_init__(self):
        for name in ("linear", "angular", "linear_accel", "angular_accel", "wheel"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise InputError(f"MotionLimits.{name} must be a positive number or None, got {value!r}")


def wheel_limits(robot, limits: MotionLimits) -> np.ndarray:
    """Per rolling wheel speed bound [rad/s] (inf where none)."""
    out = np.full(len(robot.rolling), np.inf)
    for i, w in enumerate(robot.rolling):
        if w.max_speed is not None:
            out[i] = w.max_speed
        if limits.wheel is not None:
            out[i] = min(out[i], limits.wheel)
    return out


def speed_scale(robot, twist, limits: MotionLimits) -> np.ndarray:
    """Largest factor ``k`` (may exceed 1) with ``k * twist`` inside every speed limit.

    ``twist`` ``(..., 3)``; returns ``(...)``; ``inf`` for a zero twist.
    """
    t = as_components(twist, 3, "twist")
    require_finite(t, "twist")
    speeds = np.abs(robot.ik(t, on_infeasible="return").wheel_speeds)
    with np.errstate(divide="ignore"):  # a bound over a zero speed is no bound: inf
        bound = np.broadcast_to(wheel_limits(robot, limits), speeds.shape)
        k = np.min(
            np.divide(bound, speeds, out=np.full(speeds.shape, np.inf), where=speeds > 0), axis=-1, initial=np.inf
        )
        if limits.linear is not None:
            k = np.minimum(k, limits.linear / np.hypot(t[..., 0], t[..., 1]))
        if limits.angular is not None:
            k = np.minimum(k, limits.angular / np.abs(t[..., 2]))
    return k


def saturate(robot, twist, limits: MotionLimits) -> np.ndarray:
    """``twist`` scaled down (never up) by one factor so that every speed limit holds."""
    t = as_components(twist, 3, "twist")
    k = np.minimum(1.0, speed_scale(robot, t, limits))
    return t * k[..., None]
