"""Trajectories and tracking control (extra ``control``).

- :mod:`~omnikin.control.path`: geometric paths ``q(s)`` with a heading, sampled by length.
- :mod:`~omnikin.control.time_optimal`: the fastest timing of a path under every wheel's speed
  and acceleration limit (the wheel-space polytope, not boxes per axis).
"""

from .path import Path, circle, figure8, polyline, square
from .time_optimal import Timing, WheelLimits, time_optimal

__all__ = ["Path", "Timing", "WheelLimits", "circle", "figure8", "polyline", "square", "time_optimal"]
