"""Robots built from first principles and closed-form poses, for tests whose expected values
must not come from the code under test."""

from __future__ import annotations

import math

import numpy as np

from omnikin import Encoder, Robot, Wheel


def omni_robot(angles_deg, distance=0.113, radius=0.04125, drive_offsets_deg=None, name="test"):
    """Omni wheels on a circle; drive = CCW tangent (+ optional offsets)."""
    wheels = []
    for i, a in enumerate(angles_deg):
        b = math.radians(a)
        off = math.radians(drive_offsets_deg[i]) if drive_offsets_deg else 0.0
        wheels.append(
            Wheel(f"w{i + 1}", "omni", distance * math.cos(b), distance * math.sin(b), b + math.pi / 2 + off, radius)
        )
    return Robot(name, tuple(wheels))


def circle_wheels(n, distance=0.2, radius=0.05, ticks_per_rev=100):
    """``n`` encoded omni wheels ``w0 .. w{n-1}`` evenly on a circle, driving along the CCW
    tangent (for tests of how checks scale with the wheel count)."""
    step = 2 * math.pi / n
    return tuple(
        Wheel(
            f"w{i}",
            "omni",
            distance * math.cos(i * step),
            distance * math.sin(i * step),
            i * step + math.pi / 2,
            radius,
            encoder=Encoder(ticks_per_rev),
        )
        for i in range(n)
    )


def constant_twist_pose(twist, t):
    """Closed-form pose after moving with a constant body twist for time t (from the origin)."""
    vx, vy, w = twist
    if abs(w) < 1e-15:
        return np.array([vx * t, vy * t, 0.0])
    th = w * t
    x = (vx * math.sin(th) - vy * (1 - math.cos(th))) / w
    y = (vx * (1 - math.cos(th)) + vy * math.sin(th)) / w
    return np.array([x, y, (th + math.pi) % (2 * math.pi) - math.pi])


def distance_to_polyline(points, corners) -> np.ndarray:
    """Distance [m] of ``points`` ``(n, 2)`` to the polyline through ``corners`` ``(m, 2)``: the
    nearest of its segments, each point's foot clamped to the segment."""
    points = np.asarray(points, dtype=float)
    corners = np.asarray(corners, dtype=float)
    best = np.full(len(points), np.inf)
    for a, b in zip(corners[:-1], corners[1:], strict=True):
        d = b - a
        f = np.clip(((points - a) @ d) / (d @ d), 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(points - a - f[:, None] * d).T))
    return best
