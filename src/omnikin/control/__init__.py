"""Trajectories and tracking control (extra ``control``).

- :mod:`~omnikin.control.path`: geometric paths ``q(s)`` with a heading, sampled by length.
- :mod:`~omnikin.control.time_optimal`: the fastest timing of a path under every wheel's speed
  and acceleration limit (the wheel-space polytope, not boxes per axis).
- :mod:`~omnikin.control.trajectory`: a path with its timing, read at any time.
- :mod:`~omnikin.control.feedback`: feedforward plus feedback on the SE(2) error.
"""

from .feedback import PoseFeedback
from .path import Path, circle, figure8, moved, parse_path, polyline, spline, square
from .time_optimal import Timing, WheelLimits, time_optimal
from .trajectory import Trajectory, plan_trajectory

__all__ = [
    "Path",
    "PoseFeedback",
    "Timing",
    "Trajectory",
    "WheelLimits",
    "circle",
    "figure8",
    "moved",
    "parse_path",
    "plan_trajectory",
    "polyline",
    "spline",
    "square",
    "time_optimal",
]
