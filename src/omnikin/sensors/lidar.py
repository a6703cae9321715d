"""A 2D lidar's scan of a world, by vectorised ray casting (``docs/sensors.md``, "Lidar").

The beams leave the lidar's mount (:class:`~omnikin.kinematics.sensors.Mount`) in the floor's
plane at its height, at the angles of :meth:`~omnikin.kinematics.sensors.Lidar.angles` turned
by the mount's yaw and the robot's heading, and meet the first wall or obstacle taller than the
mount (:func:`omnikin.world.shapes.cast_rays`). The ranges follow REP 117: ``+inf`` where no
body lies within ``range_max``, ``-inf`` where one lies closer than ``range_min``, ``nan`` for a
beam lost (``dropout``); the others get Gaussian noise of standard deviation ``range_noise``
[m], clipped to ``[range_min, range_max]`` (a reading outside would be another kind).
"""

from __future__ import annotations

import math

import numpy as np

from ..kinematics.sensors import Lidar
from ..world.shapes import Shapes, cast_rays


def beam_origin(pose, lidar: Lidar) -> tuple[float, float, float]:
    """The lidar's position (x, y) [m] and the direction of its x axis [rad], world frame, with
    the body at ``pose`` (x, y, theta)."""
    x, y, theta = (float(v) for v in pose)
    m = lidar.mount
    c, s = math.cos(theta), math.sin(theta)
    return x + c * m.x - s * m.y, y + s * m.x + c * m.y, theta + m.yaw


def true_ranges(shapes: Shapes, pose, lidar: Lidar) -> tuple[np.ndarray, np.ndarray]:
    """``(beams,)`` distances [m] from the lidar at ``pose`` to the first body each beam meets
    (``inf`` for none within ``range_max``), and the body each met (-1 for none)."""
    x, y, heading = beam_origin(pose, lidar)
    angles = heading + lidar.angles()
    origins = np.broadcast_to(np.array([x, y]), (lidar.beams, 2))
    return cast_rays(shapes.above(lidar.mount.z), origins, angles, lidar.range_max)


def measured(ranges: np.ndarray, lidar: Lidar, rng: np.random.Generator | None) -> np.ndarray:
    """The scan a lidar reports of the true ``ranges`` (module docstring); ``rng`` None: exact
    (no noise, no dropouts). The draws per scan: ``beams`` normal variates, then ``beams``
    uniform ones, whatever the ranges (so the same seed gives the same stream)."""
    out = np.asarray(ranges, dtype=float).copy()
    hit = np.isfinite(out)
    if rng is not None:
        noise = rng.standard_normal(lidar.beams) * lidar.range_noise
        lost = rng.random(lidar.beams) < lidar.dropout
        out[hit] = np.clip(out[hit] + noise[hit], lidar.range_min, lidar.range_max)
        out[lost] = np.nan
        close = hit & ~lost & (np.asarray(ranges) < lidar.range_min)
    else:
        close = hit & (out < lidar.range_min)
    out[close] = -np.inf
    return out


def scan(shapes: Shapes, pose, lidar: Lidar, rng: np.random.Generator | None = None) -> np.ndarray:
    """``(beams,)`` ranges [m] the lidar reports at ``pose`` (:func:`true_ranges`, :func:`measured`)."""
    return measured(true_ranges(shapes, pose, lidar)[0], lidar, rng)
