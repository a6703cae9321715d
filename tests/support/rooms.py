"""Closed-form ranges in a square room, for the lidar tests: the distance along each beam from
a point inside to the room's inner faces, by hand (no ray caster of omnikin's involved)."""

from __future__ import annotations

import numpy as np


def to_faces(x: float, y: float, angles: np.ndarray, face: float) -> np.ndarray:
    """``(n,)`` distances [m] from ``(x, y)`` along the directions ``angles`` [rad] (world frame)
    to the inner faces ``x = +-face``, ``y = +-face`` of a square room: along each axis the face
    ahead is met at ``(face - x) / cos`` (or ``(-face - x) / cos``), the nearer of the two axes wins."""
    c, s = np.cos(angles), np.sin(angles)
    with np.errstate(divide="ignore"):
        to_x = np.where(c > 0, (face - x) / c, np.where(c < 0, (-face - x) / c, np.inf))
        to_y = np.where(s > 0, (face - y) / s, np.where(s < 0, (-face - y) / s, np.inf))
    return np.minimum(to_x, to_y)
